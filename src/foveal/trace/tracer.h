// foveal/trace/tracer.h — the ray tracer: the only object with a vendor API (Embree) behind it.
//
// Rays and hits are plain structs of foveal's own; tracer.cpp, the one file that includes
// Embree, turns them into Embree's layouts in small per-thread batches.
#pragma once

#include <glm/glm.hpp>

#include <cstdint>
#include <memory>
#include <span>
#include <string>

namespace foveal {

struct Scene;

// A ray segment: origin, direction (any length), and the parametric interval [tnear, tfar].
// Its layout matches Embree's single ray (checked in tracer.cpp), so occlusion rays are traced
// where they were written, without a copy per ray (the copy cost ~10% of AO time, measured).
struct alignas(16) Ray {
  glm::vec3 org{0.0f};
  float tnear = 0.0f;
  glm::vec3 dir{0.0f, 0.0f, 1.0f};
  float time = 0.0f;            // unused (no motion blur)
  float tfar = 1e30f;           // set below 0 by occluded() where the ray is blocked
  uint32_t mask = 0xffffffffU;  // unused
  uint32_t id = 0;              // unused
  uint32_t flags = 0;           // unused
};

// The closest hit along a ray; prim == kNoHit when it missed.
struct Hit {
  static constexpr uint32_t kNoHit = 0xffffffffU;
  float t = 0.0f;            // distance along the ray in units of |dir|
  uint32_t prim = kNoHit;    // triangle index in Scene::triangles
  float u = 0.0f, v = 0.0f;  // barycentrics of vertices 1 and 2
  glm::vec3 ng{0.0f};        // unnormalised geometric normal
  bool valid() const { return prim != kNoHit; }
};

// How occlusion rays are handed to Embree; `bench ao` measures which is fastest.
enum class TraceApi { single, packet8, stream };
const char* to_string(TraceApi api);
TraceApi parse_trace_api(const std::string& name);  // throws Error for an unknown name

// Result of measure_raw_occlusion() and measure_raw_intersection().
struct RawTraceResult {
  double rays_per_second = 0;  // rays traced per second of wall time
  double seconds = 0;          // wall time of the traversal alone
  size_t hit = 0;              // rays that hit something
};

// A built acceleration structure over a scene's triangles; const methods are thread-safe.
class Tracer {
 public:
  // The scene must outlive the tracer: Embree reads its triangles' indices in place.
  explicit Tracer(const Scene& scene, TraceApi occlusion_api = TraceApi::stream);
  Tracer(Scene&&, TraceApi = TraceApi::stream) = delete;
  ~Tracer();
  Tracer(const Tracer&) = delete;
  Tracer& operator=(const Tracer&) = delete;

  // Closest hits of coherent rays (primary rays of a tile).
  void intersect(std::span<const Ray> rays, std::span<Hit> hits) const;
  // Any-hit test: occluded[i] = 1 when rays[i] hits something in [tnear, tfar]. The rays are
  // traced in place: the tfar of a blocked ray is overwritten.
  void occluded(std::span<Ray> rays, std::span<uint8_t> occluded) const;

  TraceApi occlusion_api() const;
  void set_occlusion_api(TraceApi api);
  double build_ms() const;   // time to build the BVH, milliseconds
  size_t triangles() const;  // triangles in the BVH

  struct Impl;

 private:
  friend RawTraceResult measure_raw_occlusion(const Tracer&, std::span<const Ray>, TraceApi);
  friend RawTraceResult measure_raw_intersection(const Tracer&, std::span<const Ray>);
  std::unique_ptr<Impl> impl_;
};

// Raw Embree occlusion throughput on the given rays, rays per second: the rays are converted
// to Embree's layout before the clock starts and traced in parallel chunks with `api`: the
// baseline against which the renderer's AO rate is judged.
RawTraceResult measure_raw_occlusion(const Tracer& tracer, std::span<const Ray> rays, TraceApi api);

// Raw Embree closest-hit throughput on the given rays, rays per second (converted before the
// clock starts, traced as coherent streams in parallel chunks, results left in Embree's layout):
// the baseline against which a primary-ray pass is judged.
RawTraceResult measure_raw_intersection(const Tracer& tracer, std::span<const Ray> rays);

}  // namespace foveal
