// foveal/render/render.cpp — primary rays, foveation maps, foveated AO and Phong shading.
#include "foveal/render/render.h"

#include "foveal/render/frame_renderer.h"
#include "foveal/render/reuse.h"

#include "foveal/util/error.h"
#include "foveal/util/gaze_point.h"
#include "foveal/util/sampling.h"
#include "foveal/util/timer.h"

#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>
#include <tbb/task_group.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <limits>
#include <mutex>
#include <optional>
#include <thread>
#include <type_traits>

#include <time.h>

namespace foveal {
namespace {

constexpr int kTile = kTileSize;      // pixels per tile side
constexpr size_t kAoBatch = 1024;     // occlusion rays handed to the tracer at once
constexpr int kMaxRaysLimit = 65535;  // n is stored in 16 bits

// Run body(x0, x1, y0, y1, tile) over fixed 16×16 tiles in parallel; the result never depends on the order.
template <class Body>
void for_each_tile(int width, int height, Body&& body) {
  const int tiles_x = (width + kTile - 1) / kTile, tiles_y = (height + kTile - 1) / kTile;
  tbb::parallel_for(0, tiles_x * tiles_y, [&](int t) {
    const int x0 = (t % tiles_x) * kTile, y0 = (t / tiles_x) * kTile;
    if constexpr (std::is_invocable_v<Body, int, int, int, int, int>)
      body(x0, std::min(x0 + kTile, width), y0, std::min(y0 + kTile, height), t);
    else
      body(x0, std::min(x0 + kTile, width), y0, std::min(y0 + kTile, height));
  });
}

}  // namespace

const char* to_string(RenderMode mode) { return mode == RenderMode::full ? "full" : "foveated"; }

RenderMode parse_render_mode(const std::string& name) {
  if (name == "foveated") return RenderMode::foveated;
  if (name == "full") return RenderMode::full;
  fail("mode: unknown mode '{}' (known: foveated, full)", name);
}

void validate(const RenderParams& p) {
  if (p.width < 1 || p.height < 1) fail("size: image must be at least 1x1, got {}x{}", p.width, p.height);
  if (p.width > 16384 || p.height > 16384) fail("size: {}x{} is larger than 16384x16384", p.width, p.height);
  validate(p.display);
  const auto& f = p.foveation;
  if (f.max_rays < 0 || f.max_rays > kMaxRaysLimit) fail("max_rays: must be in [0, {}], got {}", kMaxRaysLimit, f.max_rays);
  if (f.min_rays < 0 || f.min_rays > f.max_rays) fail("min_rays: must be in [0, max_rays = {}], got {}", f.max_rays, f.min_rays);
  if (!(f.gamma > 0) || !std::isfinite(f.gamma)) fail("gamma: must be > 0, got {}", f.gamma);
  if (!(f.beta >= 0) || !std::isfinite(f.beta)) fail("beta: must be >= 0, got {}", f.beta);
  if (!(f.ellipse_ratio > 0) || !std::isfinite(f.ellipse_ratio)) fail("ellipse_ratio: must be > 0, got {}", f.ellipse_ratio);
  if (p.ao_distance && !(*p.ao_distance > 0)) fail("ao_distance: must be > 0 or inf, got {}", *p.ao_distance);
  if (p.ambient_constant && !(*p.ambient_constant >= 0 && std::isfinite(*p.ambient_constant)))
    fail("ambient_constant: must be a number >= 0 or 'auto', got {}", *p.ambient_constant);
  if (p.gaze_px) check_gaze_point("gaze_px", p.gaze_px->x, p.gaze_px->y, p.width, p.height);
  const AoReuseParams& r = p.reuse;
  if (r.adaptive_min_rays < 1 || r.adaptive_min_rays > kMaxRaysLimit)
    fail("adaptive_min_rays: must be in [1, {}], got {}", kMaxRaysLimit, r.adaptive_min_rays);
  if (!(r.denoise_radius > 0) || r.denoise_radius > kMaxDenoiseRadius)
    fail("denoise_radius: must be in (0, {}] pixels, got {}", kMaxDenoiseRadius, r.denoise_radius);
  if (r.temporal_frames < 1 || r.temporal_frames > 1024) fail("temporal_frames: must be in [1, 1024], got {}", r.temporal_frames);
  if (r.history_frames < 1 || r.history_frames > 4096) fail("history_frames: must be in [1, 4096], got {}", r.history_frames);
  if (r.target_rays < 1 || r.target_rays > kMaxRaysLimit) fail("target_rays: must be in [1, {}], got {}", kMaxRaysLimit, r.target_rays);
  if (!(r.tolerance > 0) || !std::isfinite(r.tolerance)) fail("tolerance: must be > 0, got {}", r.tolerance);
}

CameraRays::CameraRays(const Camera& camera, int width, int height)
    : eye_(camera.eye), forward_(glm::normalize(camera.look - camera.eye)), width_(width), height_(height) {
  const float tan_half = std::tan(glm::radians(camera.fov_deg) * 0.5f);
  const float aspect = static_cast<float>(width) / static_cast<float>(height);
  const glm::vec3 right = glm::normalize(glm::cross(forward_, camera.up));
  right_ = right * tan_half * aspect;
  up_ = glm::cross(right, forward_) * tan_half;
  // Rays that are not finite abort the process in Embree: a camera whose view cannot be built
  // (coordinates too large for single precision, eye and look equal, up along the view) is refused
  auto finite = [](glm::vec3 v) { return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z); };
  if (!finite(eye_) || !finite(forward_) || !finite(right_) || !finite(up_))
    fail("camera '{}': no view from eye ({}, {}, {}) towards ({}, {}, {}) with up ({}, {}, {}) and a {}° field of view", camera.name,
         camera.eye.x, camera.eye.y, camera.eye.z, camera.look.x, camera.look.y, camera.look.z, camera.up.x, camera.up.y, camera.up.z,
         camera.fov_deg);
}

std::vector<MaterialView> material_views(const Scene& scene) {
  std::vector<MaterialView> views;
  for (const Material& m : scene.materials) views.push_back({m.diffuse, m.specular, m.shininess, m.diffuse_texture});
  return views;
}

SceneView scene_view(const Scene& scene, std::vector<MaterialView>& materials, std::vector<TextureView>& textures) {
  materials = material_views(scene);
  textures.clear();
  for (const Texture& t : scene.textures) textures.push_back({t.rgb.data(), t.width, t.height});
  SceneView v;
  v.positions = scene.positions.data();
  v.normals = scene.normals.data();
  v.uvs = scene.uvs.data();
  v.triangles = scene.triangles.data();
  v.material_ids = scene.material_ids.data();
  v.materials = materials.data();
  v.textures = textures.data();
  v.srgb_lut = srgb_to_linear_lut();
  return v;
}

std::vector<Light> frame_lights(const std::vector<Light>& scene_lights, const Camera& camera) {
  std::vector<Light> lights = scene_lights;
  if (lights.empty()) lights.push_back({Light::Type::point, camera.eye, glm::vec3(0.5f), glm::vec3(0.3f)});
  return lights;
}

float resolve_ao_distance(const Scene& scene, const Bounds& bounds, std::optional<float> requested) {
  if (requested) return *requested;
  if (scene.ao_distance) return *scene.ao_distance;
  return 0.2f * bounds.diagonal();
}

float surface_epsilon(const Bounds& bounds) { return std::max(1e-9f, 1e-6f * bounds.diagonal()); }

namespace {

// Trace one ray per pixel, made by `ray_for(x, y)`, into a G-buffer, reusing its memory. Every
// pixel is written in the parallel loop (misses too), so nothing is cleared on one thread first.
// `after_tile(x0, x1, y0, y1)` runs on each tile once it is traced, while its pixels are in cache.
template <class RayFor, class AfterTile>
void trace_into_gbuffer(const Tracer& tracer, const Scene& scene, int width, int height, const RayFor& ray_for, GBuffer& g,
                        const AfterTile& after_tile) {
  g.width = width;
  g.height = height;
  const size_t n = static_cast<size_t>(width) * height;
  for (auto* v : {&g.position, &g.normal, &g.geo_normal, &g.albedo, &g.view}) v->resize(n);
  g.prim.resize(n);
  g.depth.resize(n);
  std::vector<MaterialView> materials;
  std::vector<TextureView> textures;
  const SceneView view = scene_view(scene, materials, textures);
  for_each_tile(width, height, [&](int x0, int x1, int y0, int y1) {
    Ray rays[kTile * kTile];
    Hit hits[kTile * kTile];
    // The whole tile in one tracer call: coherent rays, in streams as long as the tile
    const int count = (x1 - x0) * (y1 - y0);
    for (int y = y0, k = 0; y < y1; ++y)
      for (int x = x0; x < x1; ++x, ++k) rays[k] = ray_for(x, y);
    tracer.intersect({rays, static_cast<size_t>(count)}, {hits, static_cast<size_t>(count)});
    for (int y = y0, k = 0; y < y1; ++y) {
      for (int x = x0; x < x1; ++x, ++k) {
        const size_t i = static_cast<size_t>(y) * width + x;
        const Hit& h = hits[k];
        g.view[i] = rays[k].dir;
        if (!h.valid()) {
          g.prim[i] = Hit::kNoHit;
          g.depth[i] = std::numeric_limits<float>::infinity();
          g.position[i] = g.geo_normal[i] = g.normal[i] = g.albedo[i] = glm::vec3(0.0f);
          continue;
        }
        const Surface surface = surface_at(view, h, rays[k].dir);
        g.prim[i] = h.prim;
        g.depth[i] = h.t;
        g.position[i] = surface.position;
        g.geo_normal[i] = surface.geo_normal;
        g.normal[i] = surface.normal;
        g.albedo[i] = surface.albedo;
      }
    }
    after_tile(x0, x1, y0, y1);
  });
}

constexpr auto kNothingAfter = [](int, int, int, int) {};

}  // namespace

GBuffer trace_primary(const Tracer& tracer, const Scene& scene, const Camera& camera, int width, int height) {
  GBuffer g;
  const CameraRays camera_ray(camera, width, height);
  trace_into_gbuffer(
      tracer, scene, width, height, [&](int x, int y) { return camera_ray(x + 0.5, y + 0.5); }, g, kNothingAfter);
  return g;
}

GBuffer trace_primary_rows(const Tracer& tracer, const Scene& scene, const Camera& camera, int width, int height, int y0, int y1) {
  if (y0 < 0 || y1 > height || y0 >= y1) fail("trace_primary_rows: rows [{}, {}) are not inside 0..{}", y0, y1, height);
  GBuffer g;
  const CameraRays camera_ray(camera, width, height);
  const double row0 = y0;
  trace_into_gbuffer(
      tracer, scene, width, y1 - y0, [&](int x, int y) { return camera_ray(x + 0.5, row0 + y + 0.5); }, g, kNothingAfter);
  return g;
}

GBuffer trace_gbuffer(const Tracer& tracer, const Scene& scene, int width, int height, const std::function<Ray(int, int)>& ray_for) {
  GBuffer g;
  trace_into_gbuffer(tracer, scene, width, height, ray_for, g, kNothingAfter);
  return g;
}

FoveationMaps foveation_maps(const RenderParams& params, glm::dvec2 gaze_px) {
  FoveationMaps m;
  m.width = params.width;
  m.height = params.height;
  const size_t n = static_cast<size_t>(params.width) * params.height;
  m.quality.assign(n, 1.0f);
  m.eccentricity.assign(n, 0.0f);
  m.rays.assign(n, static_cast<uint16_t>(params.foveation.max_rays));
  m.blend.assign(n, params.foveation.max_rays > 0 ? 1.0f : 0.0f);
  const FoveationModel model(params.display, params.width, params.height, gaze_px, params.foveation);
  const bool foveated = params.mode == RenderMode::foveated;
  for_each_tile(params.width, params.height, [&](int x0, int x1, int y0, int y1) {
    for (int y = y0; y < y1; ++y)
      for (int x = x0; x < x1; ++x) {
        const size_t i = static_cast<size_t>(y) * params.width + x;
        const FoveaSample s = model.evaluate(x, y);
        m.eccentricity[i] = static_cast<float>(s.effective_deg);
        if (!foveated) continue;
        m.quality[i] = static_cast<float>(s.quality);
        m.rays[i] = static_cast<uint16_t>(s.rays);
        m.blend[i] = static_cast<float>(s.blend);
      }
  });
  return m;
}

float estimate_visibility(const Tracer& tracer, glm::vec3 position, glm::vec3 normal, int rays, float ao_distance, float epsilon,
                          uint64_t seed, uint32_t x, uint32_t y) {
  if (rays <= 0) return 1.0f;
  const AoPixelRays pixel(position, normal, epsilon, ao_distance, seed, x, y, sobol_table_2d());
  std::vector<Ray> batch(static_cast<size_t>(rays));
  std::vector<uint8_t> occluded(batch.size());
  for (int k = 0; k < rays; ++k) batch[k] = pixel(static_cast<uint32_t>(k));
  tracer.occluded(batch, occluded);
  int open = 0;
  for (uint8_t o : occluded) open += o ? 0 : 1;
  return static_cast<float>(open) / static_cast<float>(rays);
}

int ao_tiles_x(int width) { return (width + kTile - 1) / kTile; }
int ao_tile_count(int width, int height) { return ao_tiles_x(width) * ((height + kTile - 1) / kTile); }

AoSampling ao_sampling(const AoReuseParams& reuse, uint32_t frame_index) {
  AoSampling s;
  s.adaptive = reuse.adaptive;
  s.first_round = std::max(1, reuse.adaptive_min_rays);
  s.tau_fovea = reuse.tau_fovea();
  if (reuse.temporal) {
    s.temporal_frames = std::max(1, reuse.temporal_frames);
    s.frame_index = frame_index;
  }
  return s;
}

uint64_t trace_ao_counts(const Tracer& tracer, const GBuffer& g, const FoveationMaps& maps, float ao_distance, float epsilon, uint64_t seed,
                         const AoSampling& sampling, AoCounts& counts, const AoPassHooks& hooks) {
  const size_t pixels = static_cast<size_t>(g.width) * g.height;
  const bool prior = counts.open.size() == pixels && counts.cast.size() == pixels;
  if (!prior) {
    counts.open.assign(pixels, 0.0f);
    counts.cast.assign(pixels, 0.0f);
  }
  counts.traced.assign(pixels, 0);
  const CountsView view = counts_view(counts);
  // One pixel of a tile: its rays, and its rounds (how many are cast and found blocked, where this
  // round and the frame end)
  struct Pixel {
    size_t i;
    AoPixelRays rays;
    AoPixelRounds rounds;
  };
  struct Segment {
    uint32_t pixel;       // index into Work::pixels
    uint32_t begin, end;  // ray range in the current batch
  };
  struct Work {
    std::vector<Ray> rays = std::vector<Ray>(kAoBatch);
    std::vector<uint8_t> occluded = std::vector<uint8_t>(kAoBatch);
    std::vector<Segment> segments;
    std::vector<Pixel> pixels;
    std::vector<uint32_t> active, next;
  };
  tbb::enumerable_thread_specific<Work> works;
  tbb::enumerable_thread_specific<uint64_t> traced(0);
  const int tiles = ao_tile_count(g.width, g.height);
  if (hooks.tile_ms) hooks.tile_ms->assign(static_cast<size_t>(tiles), 0.0);
  std::atomic<int> tiles_done{0};
  std::mutex progress_mutex;
  int tiles_reported = 0;  // guarded by progress_mutex
  for_each_tile(g.width, g.height, [&](int x0, int x1, int y0, int y1, int tile) {
    const Timer tile_timer;
    Work& w = works.local();
    w.pixels.clear();
    w.active.clear();
    for (int y = y0; y < y1; ++y)
      for (int x = x0; x < x1; ++x) {
        const size_t i = static_cast<size_t>(y) * g.width + x;
        const int n = maps.rays[i];
        if (!g.hit(i) || n == 0) continue;
        const AoPixelPlan plan = plan_ao_pixel(n, counts.cast[i], sampling, seed);
        w.active.push_back(static_cast<uint32_t>(w.pixels.size()));
        w.pixels.push_back({i,
                            AoPixelRays(g.position[i], g.geo_normal[i], epsilon, ao_distance, plan.seed, static_cast<uint32_t>(x),
                                        static_cast<uint32_t>(y), sobol_table_2d()),
                            AoPixelRounds(plan, n)});
      }
    size_t fill = 0;
    auto flush = [&] {
      tracer.occluded({w.rays.data(), fill}, {w.occluded.data(), fill});
      for (const Segment& s : w.segments) {
        uint32_t blocked = 0;
        for (uint32_t k = s.begin; k < s.end; ++k) blocked += w.occluded[k];
        w.pixels[s.pixel].rounds.blocked += blocked;
      }
      w.segments.clear();
      traced.local() += fill;
      fill = 0;
    };
    // Rounds: every active pixel casts up to its round's end; then each is judged on all its rays
    while (!w.active.empty()) {
      for (uint32_t a : w.active) {
        Pixel& p = w.pixels[a];
        AoPixelRounds& r = p.rounds;
        w.segments.push_back({a, static_cast<uint32_t>(fill), static_cast<uint32_t>(fill)});
        while (r.cast < r.round_end) {
          w.rays[fill++] = p.rays(r.offset + r.cast++);
          w.segments.back().end = static_cast<uint32_t>(fill);
          if (fill == kAoBatch) {
            flush();  // a pixel cut by the batch end continues in a new segment
            w.segments.push_back({a, 0, 0});
          }
        }
      }
      if (fill > 0) flush();
      w.segments.clear();
      w.next.clear();
      for (uint32_t a : w.active)
        if (w.pixels[a].rounds.next_round(view, w.pixels[a].i, maps.quality[w.pixels[a].i], sampling)) w.next.push_back(a);
      std::swap(w.active, w.next);
    }
    for (const Pixel& p : w.pixels) counts.traced[p.i] = p.rounds.finish(view, p.i, g.position[p.i]);
    if (hooks.tile_ms) (*hooks.tile_ms)[static_cast<size_t>(tile)] = tile_timer.ms();
    // Progress: whichever thread finishes a tile reports, one at a time
    if (hooks.progress) {
      const int done = ++tiles_done;
      std::unique_lock lock(progress_mutex, std::defer_lock);
      if (done == tiles)
        lock.lock();  // the last tile always reports
      else if (!lock.try_lock())
        return;
      if (done > tiles_reported) {  // never backwards
        tiles_reported = done;
        hooks.progress(static_cast<double>(done) / tiles);
      }
    }
  });
  uint64_t total = 0;
  for (uint64_t t : traced) total += t;
  return total;
}

namespace {

// V = open / cast per pixel; 1 where no ray was cast (or nothing hit).
void visibility_from_counts(const AoCounts& c, std::vector<float>& visibility) {
  visibility.resize(c.open.size());
  for (size_t i = 0; i < c.open.size(); ++i) visibility[i] = c.cast[i] > 0 ? c.open[i] / c.cast[i] : 1.0f;
}

}  // namespace

uint64_t trace_ao(const Tracer& tracer, const GBuffer& g, const FoveationMaps& maps, float ao_distance, float epsilon, uint64_t seed,
                  std::vector<float>& visibility, const AoPassHooks& hooks) {
  AoCounts counts;
  const uint64_t rays = trace_ao_counts(tracer, g, maps, ao_distance, epsilon, seed, AoSampling{}, counts, hooks);
  visibility_from_counts(counts, visibility);
  return rays;
}

namespace {

// CPU time of the calling thread, ms.
double thread_cpu_ms() {
  timespec ts{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
  return static_cast<double>(ts.tv_sec) * 1e3 + static_cast<double>(ts.tv_nsec) * 1e-6;
}

}  // namespace

// One batch's work on the CPU: its chunks, what the threads share, and the tasks that run them.
// It outlives the call where chunks are left behind (AoLeftBehind holds it), so it keeps a copy of
// the batch; the tasks, outputs and surfaces that copy points to stay the caller's.
struct AoBatchWork {
  static constexpr uint32_t kClosed = 1u << 31;
  AoBatchWork(const Tracer& t, const AoRayBatch& b) : tracer(t), batch(b) {}
  const Tracer& tracer;
  const AoRayBatch batch;
  std::vector<size_t> chunk_start;
  size_t chunks = 0;
  std::atomic<size_t> next{0};      // the next chunk to take
  std::atomic<size_t> finished{0};  // chunks taken and ended (traced, or skipped at the deadline)
  std::atomic<bool> stopped{false};
  std::atomic<uint64_t> traced{0};
  // The results' gate: the threads inside it (low bits), and whether the call has returned without
  // waiting for them (kClosed). Results are written, and expired() asked, only inside: once closed,
  // a chunk still tracing drops its rays and writes nothing of the caller's (it reads the tasks and
  // surfaces until it ends, which the caller keeps as they are until AoLeftBehind::finish()).
  std::atomic<uint32_t> gate{0};
  std::atomic<int64_t> last_dropped_ns{0};  // steady clock: when the latest chunk left behind ended
  tbb::task_group group;                    // (last: destroyed first, waiting for its tasks while the rest is alive)

  bool enter() {
    if (gate.fetch_add(1, std::memory_order_acquire) & kClosed) {
      gate.fetch_sub(1, std::memory_order_release);
      return false;
    }
    return true;
  }
  void leave() { gate.fetch_sub(1, std::memory_order_release); }
  void close() {
    gate.fetch_or(kClosed, std::memory_order_acq_rel);
    while ((gate.load(std::memory_order_acquire) & ~kClosed) != 0) std::this_thread::yield();  // results being written: microseconds
  }
  size_t taken() const { return std::min(next.load(std::memory_order_acquire), chunks); }

  // One thread's share: chunks in turn until none is left, the batch expires or the call returned
  void run() {
    // Each thread's buffers outlive the call: a frame's rounds allocate nothing
    thread_local std::vector<Ray> rays;
    thread_local std::vector<uint8_t> occluded;
    thread_local std::vector<uint32_t> chunk_blocked;
    const GBuffer& g = *batch.gbuffer;
    const auto tasks = batch.tasks;
    while (!stopped.load(std::memory_order_relaxed)) {
      if (!enter()) return;
      const size_t c = next.fetch_add(1, std::memory_order_acq_rel);
      if (c >= chunks) {
        leave();
        return;
      }
      if (batch.expired && batch.expired()) {
        stopped = true;
        finished.fetch_add(1, std::memory_order_release);
        leave();
        return;
      }
      leave();
      if (batch.chunk_hook) batch.chunk_hook();
      const Timer chunk_timer;
      // (the thread's CPU clock is a system call: read only for the tests' slower tracer)
      const double cpu_start = batch.slowdown > 1 ? thread_cpu_ms() : 0.0;
      rays.clear();
      for (size_t t = chunk_start[c]; t < chunk_start[c + 1]; ++t) {
        const AoRayTask& task = tasks[t];
        const size_t i = task.pixel;
        if (i >= g.prim.size() || !g.hit(i)) continue;
        const AoPixelRays pixel(g.position[i], g.geo_normal[i], batch.epsilon, batch.ao_distance, batch.seed,
                                static_cast<uint32_t>(i % static_cast<size_t>(g.width)),
                                static_cast<uint32_t>(i / static_cast<size_t>(g.width)), sobol_table_2d());
        for (uint32_t k = 0; k < task.count; ++k) rays.push_back(pixel(task.first + k));
      }
      occluded.resize(rays.size());
      tracer.occluded(rays, occluded);
      chunk_blocked.clear();
      size_t r = 0;
      for (size_t t = chunk_start[c]; t < chunk_start[c + 1]; ++t) {
        const AoRayTask& task = tasks[t];
        uint32_t n = 0;
        if (task.pixel < g.prim.size() && g.hit(task.pixel))
          for (uint32_t k = 0; k < task.count; ++k) n += occluded[r++];
        chunk_blocked.push_back(n);
      }
      if (batch.slowdown > 1) {  // tests: a slower tracer: the chunk's CPU time stretched (not the OS's pauses)
        const double target = (thread_cpu_ms() - cpu_start) * batch.slowdown;
        while (chunk_timer.ms() < target) {}
      }
      if (!enter()) {  // left behind: the call has returned
        last_dropped_ns.store(std::chrono::steady_clock::now().time_since_epoch().count(), std::memory_order_release);
        return;
      }
      for (size_t t = chunk_start[c], k = 0; t < chunk_start[c + 1]; ++t, ++k) {
        batch.blocked[t] = chunk_blocked[k];
        batch.done[t] = 1;
      }
      traced.fetch_add(rays.size(), std::memory_order_relaxed);
      finished.fetch_add(1, std::memory_order_release);
      leave();
    }
  }
};

AoLeftBehind::AoLeftBehind() = default;
AoLeftBehind::~AoLeftBehind() {
  try {
    finish();
  } catch (...) {  // (a chunk left behind that failed: its rays were dropped anyway)
  }
}

void AoLeftBehind::hold(std::unique_ptr<AoBatchWork> work, uint32_t chunks) {
  finish();
  work_ = std::move(work);
  chunks_ = chunks;
}

AoLeftBehind::Finished AoLeftBehind::finish() {
  Finished f;
  if (!work_) return f;
  work_->group.wait();
  f.chunks = chunks_;
  f.last = std::chrono::steady_clock::time_point(std::chrono::steady_clock::duration(work_->last_dropped_ns.load()));
  work_.reset();
  chunks_ = 0;
  return f;
}

uint64_t trace_ao_tasks(const Tracer& tracer, const AoRayBatch& batch) {
  const auto tasks = batch.tasks;
  if (batch.blocked.size() < tasks.size() || batch.done.size() < tasks.size()) fail("trace_ao_tasks: output spans shorter than the tasks");
  if (batch.leave_behind_after_ms && (!batch.left_behind || !(*batch.leave_behind_after_ms >= 0)))
    fail("trace_ao_tasks: leave_behind_after_ms needs left_behind and a time >= 0");
  if (batch.left_behind) batch.left_behind->finish();  // (the caller's, if it has not)
  std::fill(batch.done.begin(), batch.done.begin() + static_cast<std::ptrdiff_t>(tasks.size()), uint8_t{0});
  auto work = std::make_unique<AoBatchWork>(tracer, batch);
  AoBatchWork& w = *work;
  // Chunks of whole tasks, about 128 rays each (a few hundredths of a millisecond: the deadline's
  // resolution), in task order
  w.chunk_start.push_back(0);
  for (size_t t = 0, rays = 0; t < tasks.size(); ++t) {
    rays += tasks[t].count;
    if (rays >= kAoBatch / 8) {
      w.chunk_start.push_back(t + 1);
      rays = 0;
    }
  }
  if (w.chunk_start.back() != tasks.size()) w.chunk_start.push_back(tasks.size());
  w.chunks = w.chunk_start.size() - 1;
  const int threads = std::max(1, tbb::this_task_arena::max_concurrency());
  for (int k = 1; k < threads; ++k) w.group.run([&w] { w.run(); });
  w.run();  // the caller's share
  if (!batch.leave_behind_after_ms || threads == 1) {
    w.group.wait();
    return w.traced.load();
  }
  // The chunks the other threads took: waited for, once the batch has expired at most
  // leave_behind_after_ms (a thread the machine paused mid-chunk would hold the frame for its pause)
  using clock = std::chrono::steady_clock;
  std::optional<clock::time_point> stopped_at;
  const auto grace = std::chrono::duration<double, std::milli>(*batch.leave_behind_after_ms);
  while (w.finished.load(std::memory_order_acquire) < w.taken()) {
    if (!w.stopped.load(std::memory_order_relaxed) && batch.expired && batch.expired()) w.stopped = true;
    if (w.stopped.load(std::memory_order_relaxed)) {
      const auto now = clock::now();
      if (!stopped_at)
        stopped_at = now;
      else if (now - *stopped_at >= grace)
        break;
    }
    std::this_thread::yield();
  }
  w.close();
  const uint64_t traced = w.traced.load();
  const size_t left = w.taken() - w.finished.load(std::memory_order_acquire);
  if (left > 0)
    batch.left_behind->hold(std::move(work), static_cast<uint32_t>(left));
  else
    w.group.wait();  // (threads yet to start find the gate closed)
  return traced;
}

void collect_ao_rays(const GBuffer& g, const FoveationMaps& maps, float ao_distance, float epsilon, uint64_t seed, size_t stride,
                     std::vector<Ray>& rays) {
  for (size_t i = 0; i < g.prim.size(); i += std::max<size_t>(1, stride)) {
    if (!g.hit(i) || maps.rays[i] == 0) continue;
    const AoPixelRays pixel(g.position[i], g.geo_normal[i], epsilon, ao_distance, seed, static_cast<uint32_t>(i % g.width),
                            static_cast<uint32_t>(i / g.width), sobol_table_2d());
    for (uint32_t k = 0; k < maps.rays[i]; ++k) rays.push_back(pixel(k));
  }
}

float foveal_mean_visibility(const GBuffer& g, const FoveationMaps& maps, const std::vector<float>& visibility) {
  // Sequential sum in pixel order: deterministic
  double sum = 0;
  size_t count = 0;
  for (size_t i = 0; i < visibility.size(); ++i)
    if (g.hit(i) && maps.quality[i] >= 1.0f && maps.rays[i] > 0) {
      sum += visibility[i];
      ++count;
    }
  return count > 0 ? static_cast<float>(sum / count) : 1.0f;
}

namespace {

// Phong shading of one tile's pixels from the G-buffer into `image`; `ambient_factor(i)` is pixel
// i's k_a, `occluded(ray)` answers shadow rays (asked only with `shadows`).
template <class AmbientFactor, class Occluded>
void shade_tile(const Scene& scene, const GBuffer& g, const std::vector<MaterialView>& materials, const std::vector<Light>& lights,
                bool shadows, float epsilon, const AmbientFactor& ambient_factor, const Occluded& occluded, int x0, int x1, int y0, int y1,
                Image& image) {
  for (int y = y0; y < y1; ++y)
    for (int x = x0; x < x1; ++x) {
      const size_t i = static_cast<size_t>(y) * g.width + x;
      glm::vec3 c = background_colour();
      if (g.hit(i)) {
        const MaterialView& m = materials[scene.material_ids[g.prim[i]]];
        c = shade_point(m, g.albedo[i], g.position[i], g.normal[i], g.geo_normal[i], g.view[i], ambient_factor(i), scene.ambient,
                        lights.data(), static_cast<int>(lights.size()), shadows, epsilon, occluded);
      }
      for (int k = 0; k < 3; ++k) image.at(x, y, k) = c[k];
    }
}

// Phong shading with one ambient factor everywhere and no shadow rays (the vision simulation's
// colour), a tile at a time into `image`.
class ConstantAmbientShading {
 public:
  ConstantAmbientShading(const Scene& scene, const Camera& camera, const GBuffer& g, float ambient_constant, float epsilon, Image& image)
      : scene_(scene),
        g_(g),
        lights_(frame_lights(scene.lights, camera)),
        materials_(material_views(scene)),
        ambient_constant_(ambient_constant),
        epsilon_(epsilon),
        image_(image) {}
  void operator()(int x0, int x1, int y0, int y1) const {
    shade_tile(
        scene_, g_, materials_, lights_, false, epsilon_, [this](size_t) { return ambient_constant_; }, [](const Ray&) { return false; },
        x0, x1, y0, y1, image_);
  }

 private:
  const Scene& scene_;
  const GBuffer& g_;
  const std::vector<Light> lights_;
  const std::vector<MaterialView> materials_;
  const float ambient_constant_, epsilon_;
  Image& image_;
};

}  // namespace

Image shade(const Tracer& tracer, const Scene& scene, const Camera& camera, const GBuffer& g, const FoveationMaps& maps,
            const std::vector<float>& visibility, float ambient_constant, bool shadows, float epsilon, uint64_t* shadow_rays) {
  Image image(g.width, g.height, 3);
  const std::vector<Light> lights = frame_lights(scene.lights, camera);
  const std::vector<MaterialView> materials = material_views(scene);
  tbb::enumerable_thread_specific<uint64_t> shadow_count(0);
  // Blended ambient factor: k_a = b·V + (1 − b)·k_const
  const auto ka = [&](size_t i) { return maps.blend[i] * visibility[i] + (1.0f - maps.blend[i]) * ambient_constant; };
  const auto occluded = [&](const Ray& ray) {
    Ray s = ray;
    uint8_t blocked = 0;
    tracer.occluded({&s, 1}, {&blocked, 1});
    ++shadow_count.local();
    return blocked != 0;
  };
  for_each_tile(g.width, g.height, [&](int x0, int x1, int y0, int y1) {
    shade_tile(scene, g, materials, lights, shadows, epsilon, ka, occluded, x0, x1, y0, y1, image);
  });
  if (shadow_rays) {
    *shadow_rays = 0;
    for (uint64_t s : shadow_count) *shadow_rays += s;
  }
  return image;
}

Image shade_constant_ambient(const Scene& scene, const Camera& camera, const GBuffer& g, float ambient_constant, float epsilon) {
  Image image(g.width, g.height, 3);
  for_each_tile(g.width, g.height, ConstantAmbientShading(scene, camera, g, ambient_constant, epsilon, image));
  return image;
}

void trace_primary_shaded(const Tracer& tracer, const Scene& scene, const Camera& camera, int width, int height, float ambient_constant,
                          float epsilon, GBuffer& gbuffer, Image& color) {
  if (color.width != width || color.height != height || color.channels != 3) color = Image(width, height, 3);  // else its memory is kept
  const CameraRays camera_ray(camera, width, height);
  trace_into_gbuffer(
      tracer, scene, width, height, [&](int x, int y) { return camera_ray(x + 0.5, y + 0.5); }, gbuffer,
      ConstantAmbientShading(scene, camera, gbuffer, ambient_constant, epsilon, color));
}

Frame render_frame(const Tracer& tracer, const Scene& scene, const Camera& camera, const RenderParams& params,
                   const std::function<void(double)>& progress, AoHistory* history) {
  validate(params);
  Frame f;
  Timer total;
  f.gaze_px = params.gaze_px.value_or(glm::dvec2(params.width * 0.5, params.height * 0.5));
  const Bounds bounds = scene.bounds();
  const float ao_distance = resolve_ao_distance(scene, bounds, params.ao_distance);
  const float epsilon = surface_epsilon(bounds);
  // Primary rays → G-buffer
  Timer t;
  f.gbuffer = trace_primary(tracer, scene, camera, params.width, params.height);
  f.stats.primary_ms = t.ms();
  // Foveation model → per-pixel q, n, b
  t.reset();
  f.maps = foveation_maps(params, f.gaze_px);
  f.stats.foveation_ms = t.ms();
  // Foveated AO: the paper's pass, or with history, adaptive rounds and the filter
  const AoReuseParams& reuse = params.reuse;
  if (!reuse.any()) {
    t.reset();
    f.stats.ao_rays = trace_ao(tracer, f.gbuffer, f.maps, ao_distance, epsilon, params.seed, f.visibility, {progress});
    f.stats.ao_ms = t.ms();
  } else {
    const bool temporal = reuse.temporal && history;
    AoCounts counts;
    t.reset();
    if (temporal) f.stats.history_pixels = history->reproject(f.gbuffer, f.maps, reuse, counts);
    f.stats.reuse_ms = t.ms();
    t.reset();
    const AoSampling sampling = ao_sampling(reuse, temporal ? history->frames() : 0);
    f.stats.ao_rays = trace_ao_counts(tracer, f.gbuffer, f.maps, ao_distance, epsilon, params.seed, sampling, counts, {progress});
    f.stats.ao_ms = t.ms();
    t.reset();
    visibility_from_counts(counts, f.visibility);
    if (reuse.denoise) f.stats.denoised_pixels = denoise_visibility(f.gbuffer, f.maps, counts, reuse, camera.fov_deg, f.visibility);
    if (temporal) history->store(f.gbuffer, camera, f.maps, reuse, counts);
    f.ao_traced = std::move(counts.traced);
    f.stats.reuse_ms += t.ms();
  }
  // Phong shading with the blended ambient term
  t.reset();
  const float k_const = params.ambient_constant ? *params.ambient_constant : foveal_mean_visibility(f.gbuffer, f.maps, f.visibility);
  f.color = shade(tracer, scene, camera, f.gbuffer, f.maps, f.visibility, k_const, params.shadows, epsilon, &f.stats.shadow_rays);
  f.stats.shade_ms = t.ms();
  f.stats.total_ms = total.ms();
  // Counts
  const size_t pixels = static_cast<size_t>(params.width) * params.height;
  f.stats.primary_rays = pixels;
  f.stats.ao_rays_mean = static_cast<double>(f.stats.ao_rays) / static_cast<double>(pixels);
  int lo = std::numeric_limits<int>::max(), hi = 0;
  for (size_t i = 0; i < pixels; ++i)
    if (f.gbuffer.hit(i)) {
      lo = std::min<int>(lo, f.maps.rays[i]);
      hi = std::max<int>(hi, f.maps.rays[i]);
    }
  f.stats.ao_rays_min = lo == std::numeric_limits<int>::max() ? 0 : lo;  // 0 when nothing was hit
  f.stats.ao_rays_max = hi;
  f.stats.ambient_constant = k_const;
  f.stats.ao_distance = ao_distance;
  return f;
}

}  // namespace foveal
