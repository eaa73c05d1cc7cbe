// foveal/render/reuse.h — more quality per AO ray: temporal history and edge-stopping reconstruction.
//
// Both work on the AO pass's ray counts (open and cast rays per pixel, AoCounts), not on
// visibility: history adds rays, the filter pools them, and each pixel's standard error says
// whether it needs either. The threshold is the one adaptive sampling stops at (AoReuseParams):
// τ(E) = tolerance · 0.5/√target_rays / q(E).
//
// Temporal reuse follows the reprojection caches of real-time rendering (Nehab et al. 2007,
// "Accelerating real-time shading with reverse reprojection caching"; the history-length cap of
// temporal anti-aliasing, Patney et al. 2016 for the foveated case): a pixel's surface point is
// projected into the previous frame's camera and the counts of the four pixels around it are
// blended bilinearly, those that saw the same surface (geometric normal within 5.7°/q(E), on the
// same plane within two pixel footprints); where none did (a disocclusion) the pixel starts
// afresh. The history carries the mean origin of its rays: bilinear blending keeps it on the
// point to first order as the camera moves, and where it still drifts beyond what the eye
// resolves the history is weighed down. History is stored per pixel of the last frame, not per
// gaze, so a saccade keeps what the new fovea already has.
//
// The filter is a cross-bilateral pooling of rays (Dammertz et al. 2010 and the SVGF family's
// edge-stopping weights on depth, normal and albedo, and on the estimate itself, normalised by its
// variance as SVGF's luminance weight, Schied et al. 2017): V = Σ w·open / Σ w·cast over a window
// whose radius is what the pixel's rays lack to reach τ(E), at most radius·(1/q(E) − 1): the
// footprint grows as acuity falls, and is nothing where q = 1, where the eye resolves every pixel.
// Normal and plane tests are hard: no weight crosses a crease or a depth edge; the range weight
// keeps a crevice's AO apart from the open surface around it.
#pragma once

#include "foveal/render/render.h"

#include <cstdint>
#include <functional>
#include <vector>

namespace foveal {

class AoHistory {
 public:
  void clear() { *this = AoHistory(); }
  bool empty() const { return width_ == 0; }
  uint32_t frames() const { return frames_; }  // frames stored since the last clear
  // The stored frame for the per-pixel functions (reuse_pixel.h); valid until the next store().
  HistoryView view() const;
  // The counts kept for the surface points of `gbuffer` (its world positions stand for the current
  // camera): the previous frame's at the pixel each point projects to, where it saw the same
  // surface; zero elsewhere. The history's rays were cast from points around this one (their mean,
  // AoCounts::origin_sum, drifts as the camera moves); where that mean is farther than
  // history_reach_px(q(E)) the history is weighed down so that, with this frame's n(E)/F rays, it
  // comes back within reach. Returns the number of pixels that kept history.
  uint64_t reproject(const GBuffer& gbuffer, const FoveationMaps& maps, const AoReuseParams& reuse, AoCounts& counts) const;
  // The same for rows [y0, y1) alone, the rest of `counts` untouched: a view's counts taken over a
  // few rows at a time (the real-time loop). `counts` (and the maps) must hold those rows already;
  // the G-buffer every row the history is looked up from.
  uint64_t reproject_rows(const GBuffer& gbuffer, const FoveationMaps& maps, const AoReuseParams& reuse, AoCounts& counts, int y0,
                          int y1) const;
  // Keep a frame's counts for the next, each pixel's capped at H(E) frames of its refresh rays
  // (scaled down, V unchanged).
  void store(const GBuffer& gbuffer, const Camera& camera, const FoveationMaps& maps, const AoReuseParams& reuse, const AoCounts& counts);
  // The same for a view being left: its surfaces' positions and normals moved out of `gbuffer`
  // (not copied), and each pixel's counts asked of `counts(i, position, open, cast, origin_sum)`
  // (no arrays of them made). At a new view of the real-time loop copying them cost 17 ms of 840×525 on two
  // cores (page faults included), more than the frame.
  using PixelCounts = std::function<void(size_t, glm::vec3, float&, float&, glm::vec3&)>;
  void store(GBuffer&& gbuffer, const Camera& camera, const FoveationMaps& maps, const AoReuseParams& reuse, const PixelCounts& counts);
  // The same for a view that stays, a few rows at a time (the real-time loop builds a larger view of
  // it over several frames; copying its surfaces and counts at once, about 45 bytes a pixel, made a
  // frame of a 4–8 ms budget late by 6–17 ms at 616×385 on two cores, page faults included):
  // begin_rows() sets the size and camera and reserves the memory, untouched; store_rows() copies
  // rows [y0, y1), in order (y0 the rows stored so far). The history is empty() until the last row
  // is stored.
  void begin_rows(int width, int height, const Camera& camera);
  void store_rows(const GBuffer& gbuffer, const FoveationMaps& maps, const AoReuseParams& reuse, const PixelCounts& counts, int y0, int y1);
  int rows_stored() const { return rows_; }

 private:
  int width_ = 0, height_ = 0;
  Camera camera_;
  std::vector<glm::vec3> position_, normal_;
  std::vector<uint8_t> hit_;
  std::vector<float> open_, cast_;
  std::vector<glm::vec3> origin_;  // Σ of the counted rays' origins
  uint32_t frames_ = 0;
  int rows_width_ = 0, rows_height_ = 0, rows_ = 0;  // a store by rows under way (begin_rows)
  // Pixel i's counts, asked of `counts` and capped, into the history (its position_ already there)
  void keep_pixel(size_t i, bool hit, const FoveationMaps& maps, const AoReuseParams& reuse, const PixelCounts& counts);
};

// history_reach_px(), history_normal_cos(): reuse_pixel.h.

// The history cap of a pixel, rays: H(E) = max(F, round(H·q)) frames of ceil(n/F) rays.
inline float history_cap_rays(int rays, float quality, const AoReuseParams& reuse) {
  return history_cap_rays(rays, quality, reuse.temporal_frames, reuse.history_frames);
}

// The footprint radius a pixel may pool over, pixels: round(radius·(1/q − 1)) up to kMaxDenoiseRadius
// (the eye resolves cells of 1/q pixels; 0 where q = 1: the fovea is never filtered).
inline int denoise_max_radius(float quality, const AoReuseParams& reuse) { return denoise_max_radius(quality, reuse.denoise_radius); }

// Filter `visibility` (V = open / cast on entry) where a pixel's standard error exceeds τ(E);
// `fov_deg` is the camera's vertical field of view (pixel footprints). Returns the pixels changed.
uint64_t denoise_visibility(const GBuffer& gbuffer, const FoveationMaps& maps, const AoCounts& counts, const AoReuseParams& reuse,
                            float fov_deg, std::vector<float>& visibility);

}  // namespace foveal
