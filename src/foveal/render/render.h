// foveal/render/render.h — one frame of gaze-dependent ambient occlusion, pass by pass.
//
// render_frame() runs the passes in order; each is a free function over plain buffers:
//   trace_primary  → GBuffer            (camera rays, one per pixel centre)
//   foveation_maps → FoveationMaps      (q(E), n(E), b(E) per pixel; full mode: n_max, b = 1)
//   trace_ao       → visibility V       (cosine-weighted occlusion rays, eq. 1)
//   shade          → linear RGB image   (Phong, eq. 2, with k_a = b·V + (1 − b)·k_const)
#pragma once

#include "foveal/perception/foveation.h"
#include "foveal/render/pixel.h"
#include "foveal/render/reuse_pixel.h"
#include "foveal/scene/scene.h"
#include "foveal/trace/tracer.h"
#include "foveal/util/image.h"

#include <glm/glm.hpp>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <functional>
#include <optional>
#include <string>
#include <vector>

namespace foveal {

// Foveated: the AO budget follows the gaze. Full: n_max rays everywhere (the reference).
enum class RenderMode { foveated, full };
const char* to_string(RenderMode mode);
RenderMode parse_render_mode(const std::string& name);  // throws Error for an unknown name

// Quality per ray: how each pixel's AO budget n(E) is spent and reconstructed. All off (the
// default) is the paper's method, bit-identical. Every threshold is the standard error τ(E) that
// the acuity model allows a pixel's visibility: τ(E) = tolerance · 0.5/√target_rays / q(E), the
// worst-case noise of the full-frame reference (target_rays per pixel) where q = 1, growing as
// acuity falls (the budget n(E) = n_max·q² of γ = 2 has exactly this worst-case noise).
struct AoReuseParams {
  bool adaptive = false;        // rays in rounds (doubling); a pixel stops once its standard error ≤ τ(E)
  int adaptive_min_rays = 16;   // the first round: the fewest rays a pixel with n(E) ≥ it casts
  bool denoise = false;         // edge-stopping filter of the pixels whose standard error > τ(E)
  double denoise_radius = 1.0;  // footprint r(E) = radius·(1/q(E) − 1) pixels, at most kMaxDenoiseRadius (none where q = 1)
  bool temporal = false;        // accumulate rays across frames (render_frame with an AoHistory)
  int temporal_frames = 4;      // F: a pixel whose history holds n(E) rays casts n(E)/F a frame
  int history_frames = 16;      // H: history length where q = 1, frames; H(E) = max(F, round(H·q(E)))
  int target_rays = 400;        // the reference's rays per pixel, whose noise sets τ
  double tolerance = 0.35;      // scales τ(E) (0.35: the fovea within the reference's noise in every frame, measured on the dragon)
  bool any() const { return adaptive || denoise || temporal; }
  // τ where q = 1: tolerance · 0.5/√target_rays (τ(E) = this / q(E))
  float tau_fovea() const { return static_cast<float>(tolerance * 0.5 / std::sqrt(std::max(1, target_rays))); }
};
// Everything that decides one frame besides the scene and camera.
struct RenderParams {
  int width = 840;   // render pixels
  int height = 525;  // render pixels
  RenderMode mode = RenderMode::foveated;
  std::optional<glm::dvec2> gaze_px;             // render pixels, origin top-left; unset → image centre
  Display display;                               // the screen the render fills
  FoveationParams foveation;                     // n_max, n_min, γ, β, ellipse ratio
  std::optional<float> ao_distance;              // scene units, may be infinite; unset → scene's or 0.2 × diagonal
  std::optional<float> ambient_constant = 1.0f;  // k_const; unset → mean visibility of the fovea
  uint64_t seed = 1;                             // scrambles every pixel's AO directions
  bool shadows = false;                          // shadow rays for the lights (off, as in the papers)
  AoReuseParams reuse;                           // adaptive rays, denoising, temporal reuse (all off: the paper)
};

// Check sizes and model parameters; throws Error naming the option.
void validate(const RenderParams& params);

// Per-pixel surface data from the primary rays. Pixels that hit nothing have prim == Hit::kNoHit.
struct GBuffer {
  int width = 0, height = 0;
  std::vector<uint32_t> prim;         // triangle index or Hit::kNoHit
  std::vector<glm::vec3> position;    // world position, scene units
  std::vector<glm::vec3> normal;      // shading normal, unit, facing the camera
  std::vector<glm::vec3> geo_normal;  // geometric normal, unit, facing the camera (AO hemisphere)
  std::vector<glm::vec3> albedo;      // diffuse reflectance k_d, linear RGB (texture applied)
  std::vector<float> depth;           // distance along the primary ray, scene units
  std::vector<glm::vec3> view;        // unit direction of the primary ray
  bool hit(size_t i) const { return prim[i] != Hit::kNoHit; }
};

// Per-pixel foveation model output.
struct FoveationMaps {
  int width = 0, height = 0;
  std::vector<float> quality;       // q(E) in [0, 1]
  std::vector<float> eccentricity;  // elliptical eccentricity E, degrees
  std::vector<uint16_t> rays;       // n(E), AO rays for the pixel
  std::vector<float> blend;         // b(E) in [0, 1]
};

// Counts and times of one frame (the `--stats` JSON).
struct FrameStats {
  uint64_t primary_rays = 0;
  uint64_t ao_rays = 0;
  uint64_t shadow_rays = 0;
  double ao_rays_mean = 0;  // AO rays traced / pixels
  int ao_rays_min = 0;      // smallest budget among pixels that hit the scene
  int ao_rays_max = 0;      // largest budget among pixels that hit the scene
  double primary_ms = 0, foveation_ms = 0, ao_ms = 0, shade_ms = 0, total_ms = 0;
  float ambient_constant = 1;  // k_const used
  float ao_distance = 0;       // scene units (may be infinite)
  // Quality per ray (zero when its option is off)
  uint64_t history_pixels = 0;   // pixels whose reprojected history was kept (--temporal)
  uint64_t denoised_pixels = 0;  // pixels the filter changed (--denoise)
  double reuse_ms = 0;           // reprojection and filtering
};

// A rendered frame with every intermediate buffer.
struct Frame {
  Image color;  // linear RGB
  GBuffer gbuffer;
  FoveationMaps maps;
  std::vector<float> visibility;    // AO visibility V per pixel (1 where nothing was hit or no ray cast)
  std::vector<uint16_t> ao_traced;  // AO rays traced this frame per pixel (filled with --adaptive/--temporal)
  glm::dvec2 gaze_px{0.0};
  FrameStats stats;
};

// AO ray length for a scene: the explicit value, else the scene's, else 0.2 × bounding-box diagonal.
float resolve_ao_distance(const Scene& scene, const Bounds& bounds, std::optional<float> requested);
// Smallest offset that lifts ray origins off a surface, scene units (10⁻⁶ × scene diagonal).
float surface_epsilon(const Bounds& bounds);

// The lights a frame is shaded with: the scene's, else a head light at the camera.
std::vector<Light> frame_lights(const std::vector<Light>& scene_lights, const Camera& camera);

// Primary rays through every pixel centre.
GBuffer trace_primary(const Tracer& tracer, const Scene& scene, const Camera& camera, int width, int height);
// Rows [y0, y1) of trace_primary's G-buffer (width × height), as a G-buffer of width × (y1 − y0),
// the same to the bit: a view's surfaces traced a few rows at a time. Throws Error for rows outside.
GBuffer trace_primary_rows(const Tracer& tracer, const Scene& scene, const Camera& camera, int width, int height, int y0, int y1);
// One ray per pixel from `ray_for(x, y)` (unit direction) into a G-buffer (depth = distance along that ray).
GBuffer trace_gbuffer(const Tracer& tracer, const Scene& scene, int width, int height, const std::function<Ray(int, int)>& ray_for);
// The foveation model evaluated at every pixel (full mode: q = 1, n = n_max, b = 1).
FoveationMaps foveation_maps(const RenderParams& params, glm::dvec2 gaze_px);
// Optional observers of the AO pass.
struct AoPassHooks {
  std::function<void(double)> progress;    // finished fraction in (0, 1], called from one thread at a time
  std::vector<double>* tile_ms = nullptr;  // if set: each tile's time on its thread, ms, in tile order
};
// Every pass runs over square tiles of this many pixels a side, row by row: tile t covers
// pixels from ((t % tiles_x)·kTileSize, (t / tiles_x)·kTileSize).
inline constexpr int kTileSize = 16;
int ao_tiles_x(int width);
int ao_tile_count(int width, int height);
// AO visibility per pixel with maps.rays[i] rays; returns the number of rays traced.
uint64_t trace_ao(const Tracer& tracer, const GBuffer& gbuffer, const FoveationMaps& maps, float ao_distance, float epsilon, uint64_t seed,
                  std::vector<float>& visibility, const AoPassHooks& hooks = {});
// AoSampling (how the AO pass spends each pixel's budget): reuse_pixel.h.
AoSampling ao_sampling(const AoReuseParams& reuse, uint32_t frame_index);
// AO ray counts per pixel: rays found open and rays cast, history included (floats: history is
// rescaled when capped). V = open / cast; cast = 0: no estimate (V = 1).
struct AoCounts {
  std::vector<float> open, cast;
  std::vector<uint16_t> traced;  // rays traced this frame
  // With history only (else empty): Σ over the counted rays of their origin, the surface point of
  // the pixel that cast each (origin_sum / cast: where the estimate stands). The pass adds its own.
  std::vector<glm::vec3> origin_sum;
};
// Views of the buffers for the per-pixel functions of reuse_pixel.h.
inline SurfaceView surface_view(const GBuffer& g) {
  return {g.prim.data(), g.position.data(), g.normal.data(), g.geo_normal.data(), g.albedo.data(), g.depth.data(), g.width, g.height};
}
inline CountsView counts_view(AoCounts& c) { return {c.open.data(), c.cast.data(), c.origin_sum.empty() ? nullptr : c.origin_sum.data()}; }
// The AO pass with a prior (`counts` on entry: history, or empty for none; on return, prior + this
// frame). The rays are each pixel's sequence from sample_offset, cast in rounds; the result does
// not depend on the thread count. Returns the number of rays traced.
uint64_t trace_ao_counts(const Tracer& tracer, const GBuffer& gbuffer, const FoveationMaps& maps, float ao_distance, float epsilon,
                         uint64_t seed, const AoSampling& sampling, AoCounts& counts, const AoPassHooks& hooks = {});
// visibility_standard_error(), history_contradicted(): reuse_pixel.h.

// The CPU's FrameRenderer::trace_ao_batch: the tasks in chunks of about a thousand rays, taken in
// order by every thread, batch.expired() asked before each; a task's result does not depend on
// the thread count. Returns the rays traced.
struct AoRayBatch;
uint64_t trace_ao_tasks(const Tracer& tracer, const AoRayBatch& batch);

// Visibility at one point from `rays` cosine-weighted directions of pixel (x, y)'s sequence:
// the per-pixel function the AO pass runs, exposed for analytic tests.
float estimate_visibility(const Tracer& tracer, glm::vec3 position, glm::vec3 normal, int rays, float ao_distance, float epsilon,
                          uint64_t seed, uint32_t x, uint32_t y);
// The AO rays the pass would trace for every `stride`-th pixel (in pixel order), appended to
// `rays`: the same distribution the renderer traces, for raw-throughput baselines.
void collect_ao_rays(const GBuffer& gbuffer, const FoveationMaps& maps, float ao_distance, float epsilon, uint64_t seed, size_t stride,
                     std::vector<Ray>& rays);
// Mean visibility of the pixels with q = 1 (the `auto` ambient constant); 1 when there are none.
float foveal_mean_visibility(const GBuffer& gbuffer, const FoveationMaps& maps, const std::vector<float>& visibility);
// Phong shading of eq. 2 with the blended ambient factor; returns linear RGB.
Image shade(const Tracer& tracer, const Scene& scene, const Camera& camera, const GBuffer& gbuffer, const FoveationMaps& maps,
            const std::vector<float>& visibility, float ambient_constant, bool shadows, float epsilon, uint64_t* shadow_rays = nullptr);

// Phong shading with the constant ambient factor everywhere (no AO): the vision simulation's colour.
Image shade_constant_ambient(const Scene& scene, const Camera& camera, const GBuffer& gbuffer, float ambient_constant, float epsilon);
// trace_primary into `gbuffer` and shade_constant_ambient into `color` in one pass over the tiles
// (each tile shaded while its G-buffer is in cache), reusing both one's memory: the same results.
void trace_primary_shaded(const Tracer& tracer, const Scene& scene, const Camera& camera, int width, int height, float ambient_constant,
                          float epsilon, GBuffer& gbuffer, Image& color);

// All passes for one frame.
// `progress` reports the AO pass, the long one (see trace_ao).
// With params.reuse.temporal and a `history`, the frame starts from the history reprojected to its
// surface points and leaves its own counts there for the next frame.
class AoHistory;
Frame render_frame(const Tracer& tracer, const Scene& scene, const Camera& camera, const RenderParams& params,
                   const std::function<void(double)>& progress = {}, AoHistory* history = nullptr);

}  // namespace foveal
