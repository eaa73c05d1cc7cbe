// Tests of the Embree tracer: hits at known distances and agreement of the occlusion APIs.
#include "foveal/trace/tracer.h"
#include "foveal/scene/scene.h"
#include "foveal/util/error.h"
#include "foveal/util/sampling.h"

#include <gtest/gtest.h>

using namespace foveal;

TEST(Tracer, HitsThePlaneAtTheRightDistance) {
  const Scene plane = make_builtin_scene("plane");
  const Tracer tracer(plane);
  EXPECT_EQ(tracer.triangles(), 2u);
  const Ray rays[2] = {{.org = {1, 5, 2}, .dir = {0, -1, 0}}, {.org = {1, 5, 2}, .dir = {0, 1, 0}}};
  Hit hits[2];
  tracer.intersect(rays, hits);
  ASSERT_TRUE(hits[0].valid());
  EXPECT_NEAR(hits[0].t, 5.0f, 1e-5f);
  EXPECT_FALSE(hits[1].valid());
}

TEST(Tracer, OcclusionStopsAtTfar) {
  const Scene plane = make_builtin_scene("plane");
  const Tracer tracer(plane);
  Ray rays[2] = {{.org = {0, 1, 0}, .dir = {0, -1, 0}, .tfar = 0.99f}, {.org = {0, 1, 0}, .dir = {0, -1, 0}, .tfar = 1.01f}};
  uint8_t blocked[2] = {7, 7};
  tracer.occluded(rays, blocked);
  EXPECT_EQ(blocked[0], 0);
  EXPECT_EQ(blocked[1], 1);
}

TEST(Tracer, OcclusionApisAgree) {
  const Scene scene = make_builtin_scene("box");
  Tracer tracer(scene);
  // Rays from points in the box in scrambled directions, some short, some long
  std::vector<Ray> rays;
  for (uint32_t i = 0; i < 3000; ++i) {
    const glm::vec2 u = scrambled_sobol_2d(i, 17), v = scrambled_sobol_2d(i, 99);
    const glm::vec3 dir = make_frame(glm::normalize(glm::vec3(v.x - 0.5f, v.y - 0.5f, 0.3f))).to_world(cosine_hemisphere(u));
    rays.push_back(
        {.org = {(v.x - 0.5f) * 3.5f, 0.05f + 2.4f * u.y, (u.x - 0.5f) * 3.5f}, .dir = dir, .tfar = (i % 3 == 0) ? 0.3f : 1e30f});
  }
  // occluded() traces in place, so each API gets a fresh copy of the rays
  std::vector<uint8_t> reference(rays.size());
  tracer.set_occlusion_api(TraceApi::single);
  std::vector<Ray> copy = rays;
  tracer.occluded(copy, reference);
  size_t blocked = 0;
  for (uint8_t b : reference) blocked += b;
  EXPECT_GT(blocked, 100u);
  EXPECT_LT(blocked, rays.size() - 100);
  for (TraceApi api : {TraceApi::packet8, TraceApi::stream}) {
    tracer.set_occlusion_api(api);
    std::vector<uint8_t> out(rays.size());
    copy = rays;
    tracer.occluded(copy, out);
    EXPECT_EQ(out, reference) << to_string(api);
    EXPECT_EQ(measure_raw_occlusion(tracer, rays, api).hit, blocked);
  }
  // Closest hits, raw: the same rays with an infinite tfar hit what intersect() says they hit
  std::vector<Ray> unbounded = rays;
  for (Ray& r : unbounded) r.tfar = 1e30f;
  std::vector<Hit> hits(unbounded.size());
  tracer.intersect(unbounded, hits);
  size_t hit = 0;
  for (const Hit& h : hits) hit += h.valid();
  const RawTraceResult raw = measure_raw_intersection(tracer, unbounded);
  EXPECT_EQ(raw.hit, hit);
  EXPECT_GT(raw.rays_per_second, 0);
  EXPECT_THROW(parse_trace_api("simd"), Error);
}
