// foveal/trace/tracer.cpp — the Embree 3 back end (the only translation unit that includes Embree).
#include "foveal/trace/tracer.h"

#include "foveal/scene/scene.h"
#include "foveal/util/error.h"
#include "foveal/util/timer.h"

#include <embree3/rtcore.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstring>
#include <mutex>
#include <vector>

namespace foveal {

// Embree reports errors through a callback; keep the first one to throw after the call. (Outside
// the anonymous namespace: Tracer::Impl, a type with linkage, holds one.)
struct EmbreeErrorSink {
  std::mutex mutex;
  std::string message;
};

namespace {

constexpr size_t kBatch = 256;  // rays converted and traced per Embree call

void on_error(void* user, RTCError code, const char* str) {
  auto* sink = static_cast<EmbreeErrorSink*>(user);
  std::lock_guard lock(sink->mutex);
  if (sink->message.empty()) sink->message = fmt::format("Embree error {}: {}", static_cast<int>(code), str ? str : "");
}

// foveal::Ray is laid out as RTCRay, so spans of rays go to Embree without a copy
static_assert(sizeof(Ray) == sizeof(RTCRay) && alignof(Ray) == alignof(RTCRay));
static_assert(offsetof(Ray, org) == offsetof(RTCRay, org_x) && offsetof(Ray, tnear) == offsetof(RTCRay, tnear) &&
              offsetof(Ray, dir) == offsetof(RTCRay, dir_x) && offsetof(Ray, time) == offsetof(RTCRay, time) &&
              offsetof(Ray, tfar) == offsetof(RTCRay, tfar) && offsetof(Ray, mask) == offsetof(RTCRay, mask) &&
              offsetof(Ray, id) == offsetof(RTCRay, id) && offsetof(Ray, flags) == offsetof(RTCRay, flags));
inline RTCRay* as_embree(Ray* rays) { return reinterpret_cast<RTCRay*>(rays); }

inline void to_embree(const Ray& r, RTCRay& e) {
  e.org_x = r.org.x;
  e.org_y = r.org.y;
  e.org_z = r.org.z;
  e.tnear = r.tnear;
  e.dir_x = r.dir.x;
  e.dir_y = r.dir.y;
  e.dir_z = r.dir.z;
  e.time = 0.0f;
  e.tfar = r.tfar;
  e.mask = 0xffffffffU;
  e.id = 0;
  e.flags = 0;
}

// Occlusion of n ≤ 8 rays starting at `rays` with one rtcOccluded8 call.
void occluded8(RTCScene scene, RTCIntersectContext* ctx, const RTCRay* rays, size_t n, uint8_t* out) {
  alignas(32) RTCRay8 packet;
  alignas(32) int valid[8];
  for (size_t k = 0; k < 8; ++k) {
    const RTCRay& r = rays[std::min(k, n - 1)];
    valid[k] = k < n ? -1 : 0;
    packet.org_x[k] = r.org_x;
    packet.org_y[k] = r.org_y;
    packet.org_z[k] = r.org_z;
    packet.tnear[k] = r.tnear;
    packet.dir_x[k] = r.dir_x;
    packet.dir_y[k] = r.dir_y;
    packet.dir_z[k] = r.dir_z;
    packet.time[k] = 0.0f;
    packet.tfar[k] = r.tfar;
    packet.mask[k] = 0xffffffffU;
    packet.id[k] = 0;
    packet.flags[k] = 0;
  }
  rtcOccluded8(valid, scene, ctx, &packet);
  for (size_t k = 0; k < n; ++k) out[k] = packet.tfar[k] < 0.0f ? 1 : 0;
}

// Trace `n` Embree rays in place with the chosen API; out[i] = 1 where occluded.
void occluded_embree(RTCScene scene, TraceApi api, RTCRay* rays, size_t n, uint8_t* out) {
  RTCIntersectContext ctx;
  rtcInitIntersectContext(&ctx);
  ctx.flags = RTC_INTERSECT_CONTEXT_FLAG_INCOHERENT;
  switch (api) {
    case TraceApi::single:
      for (size_t i = 0; i < n; ++i) {
        rtcOccluded1(scene, &ctx, &rays[i]);
        out[i] = rays[i].tfar < 0.0f ? 1 : 0;
      }
      break;
    case TraceApi::packet8:
      for (size_t i = 0; i < n; i += 8) occluded8(scene, &ctx, &rays[i], std::min<size_t>(8, n - i), &out[i]);
      break;
    case TraceApi::stream:
      rtcOccluded1M(scene, &ctx, rays, static_cast<unsigned>(n), sizeof(RTCRay));
      for (size_t i = 0; i < n; ++i) out[i] = rays[i].tfar < 0.0f ? 1 : 0;
      break;
  }
}

}  // namespace

struct Tracer::Impl {
  RTCDevice device = nullptr;
  RTCScene scene = nullptr;
  TraceApi api = TraceApi::stream;
  double build_ms = 0;
  size_t triangles = 0;
  EmbreeErrorSink errors;
  // Per-thread conversion buffers, so no allocation happens per call
  struct Scratch {
    std::vector<RTCRayHit> hits = std::vector<RTCRayHit>(kBatch);
  };
  mutable tbb::enumerable_thread_specific<Scratch> scratch;

  void check() {
    std::lock_guard lock(errors.mutex);
    if (!errors.message.empty()) fail("{}", errors.message);
  }
};

const char* to_string(TraceApi api) {
  switch (api) {
    case TraceApi::single:
      return "single";
    case TraceApi::packet8:
      return "packet8";
    case TraceApi::stream:
      return "stream";
  }
  return "?";
}

TraceApi parse_trace_api(const std::string& name) {
  if (name == "single") return TraceApi::single;
  if (name == "packet8") return TraceApi::packet8;
  if (name == "stream") return TraceApi::stream;
  fail("unknown trace API '{}' (known: single, packet8, stream)", name);
}

Tracer::Tracer(const Scene& s, TraceApi api) : impl_(std::make_unique<Impl>()) {
  Timer timer;
  impl_->api = api;
  impl_->device = rtcNewDevice(nullptr);
  if (impl_->device == nullptr) fail("cannot create the Embree device (error {})", static_cast<int>(rtcGetDeviceError(nullptr)));
  rtcSetDeviceErrorFunction(impl_->device, on_error, &impl_->errors);

  // One triangle geometry; Embree allocates the buffers so they carry its required padding
  impl_->scene = rtcNewScene(impl_->device);
  rtcSetSceneBuildQuality(impl_->scene, RTC_BUILD_QUALITY_HIGH);
  RTCGeometry geom = rtcNewGeometry(impl_->device, RTC_GEOMETRY_TYPE_TRIANGLE);
  rtcSetGeometryBuildQuality(geom, RTC_BUILD_QUALITY_HIGH);
  auto* vertices = static_cast<float*>(rtcSetNewGeometryBuffer(geom, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3, 3 * sizeof(float),
                                                               std::max<size_t>(1, s.positions.size())));
  // The triangles' indices are read in place from the scene (no copy: 12 bytes per triangle saved);
  // vertices are copied, since Embree reads 16 bytes at the last one
  static_assert(sizeof(glm::uvec3) == 3 * sizeof(uint32_t));
  rtcSetSharedGeometryBuffer(geom, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3, s.triangles.data(), 0, sizeof(glm::uvec3),
                             s.triangles.size());
  impl_->check();
  if (vertices == nullptr) fail("Embree could not allocate the geometry buffers");
  std::memcpy(vertices, s.positions.data(), s.positions.size() * sizeof(glm::vec3));
  rtcCommitGeometry(geom);
  rtcAttachGeometry(impl_->scene, geom);
  rtcReleaseGeometry(geom);
  rtcCommitScene(impl_->scene);
  impl_->check();
  impl_->triangles = s.triangles.size();
  impl_->build_ms = timer.ms();
}

Tracer::~Tracer() {
  if (impl_->scene) rtcReleaseScene(impl_->scene);
  if (impl_->device) rtcReleaseDevice(impl_->device);
}

void Tracer::intersect(std::span<const Ray> rays, std::span<Hit> hits) const {
  auto& scratch = impl_->scratch.local();
  RTCIntersectContext ctx;
  rtcInitIntersectContext(&ctx);
  ctx.flags = RTC_INTERSECT_CONTEXT_FLAG_COHERENT;
  for (size_t start = 0; start < rays.size(); start += kBatch) {
    const size_t n = std::min(kBatch, rays.size() - start);
    for (size_t i = 0; i < n; ++i) {
      RTCRayHit& rh = scratch.hits[i];
      to_embree(rays[start + i], rh.ray);
      rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
      rh.hit.primID = RTC_INVALID_GEOMETRY_ID;
      rh.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
    }
    rtcIntersect1M(impl_->scene, &ctx, scratch.hits.data(), static_cast<unsigned>(n), sizeof(RTCRayHit));
    for (size_t i = 0; i < n; ++i) {
      const RTCRayHit& rh = scratch.hits[i];
      Hit& h = hits[start + i];
      if (rh.hit.geomID == RTC_INVALID_GEOMETRY_ID) {
        h = Hit{};
        continue;
      }
      h.t = rh.ray.tfar;
      h.prim = rh.hit.primID;
      h.u = rh.hit.u;
      h.v = rh.hit.v;
      h.ng = {rh.hit.Ng_x, rh.hit.Ng_y, rh.hit.Ng_z};
    }
  }
}

void Tracer::occluded(std::span<Ray> rays, std::span<uint8_t> occluded) const {
  occluded_embree(impl_->scene, impl_->api, as_embree(rays.data()), rays.size(), occluded.data());
}

TraceApi Tracer::occlusion_api() const { return impl_->api; }
void Tracer::set_occlusion_api(TraceApi api) { impl_->api = api; }
double Tracer::build_ms() const { return impl_->build_ms; }
size_t Tracer::triangles() const { return impl_->triangles; }

RawTraceResult measure_raw_occlusion(const Tracer& tracer, std::span<const Ray> rays, TraceApi api) {
  // Copy once, before timing
  std::vector<RTCRay> converted(rays.size());
  for (size_t i = 0; i < rays.size(); ++i) to_embree(rays[i], converted[i]);
  std::vector<uint8_t> out(rays.size());
  RTCScene scene = tracer.impl_->scene;
  Timer timer;
  tbb::parallel_for(tbb::blocked_range<size_t>(0, rays.size(), kBatch), [&](const tbb::blocked_range<size_t>& r) {
    occluded_embree(scene, api, converted.data() + r.begin(), r.size(), out.data() + r.begin());
  });
  RawTraceResult result;
  result.seconds = timer.ms() / 1000.0;
  result.rays_per_second = result.seconds > 0 ? rays.size() / result.seconds : 0;
  for (uint8_t o : out) result.hit += o;
  return result;
}

RawTraceResult measure_raw_intersection(const Tracer& tracer, std::span<const Ray> rays) {
  std::vector<RTCRayHit> converted(rays.size());
  for (size_t i = 0; i < rays.size(); ++i) {
    to_embree(rays[i], converted[i].ray);
    converted[i].hit.geomID = converted[i].hit.primID = converted[i].hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
  }
  RTCScene scene = tracer.impl_->scene;
  const Timer timer;
  tbb::parallel_for(tbb::blocked_range<size_t>(0, rays.size(), kBatch), [&](const tbb::blocked_range<size_t>& r) {
    RTCIntersectContext ctx;
    rtcInitIntersectContext(&ctx);
    ctx.flags = RTC_INTERSECT_CONTEXT_FLAG_COHERENT;
    rtcIntersect1M(scene, &ctx, converted.data() + r.begin(), static_cast<unsigned>(r.size()), sizeof(RTCRayHit));
  });
  RawTraceResult result;
  result.seconds = timer.ms() / 1000.0;
  result.rays_per_second = result.seconds > 0 ? rays.size() / result.seconds : 0;
  for (const RTCRayHit& rh : converted) result.hit += rh.hit.geomID != RTC_INVALID_GEOMETRY_ID;
  return result;
}

}  // namespace foveal
