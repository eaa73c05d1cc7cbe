// The GPU backend's BVH, built by Embree's SAH builder and traversed by the shared per-pixel
// code, checked against Embree's own traversal on the CPU (the same code the kernels run).
#include "foveal/render/render.h"
#include "foveal/trace/bvh.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <vector>

namespace foveal {
namespace {

// Every triangle once, inside every box on its path; depth within the traversal stack.
void expect_well_formed(const Scene& scene, const Bvh& bvh) {
  ASSERT_FALSE(bvh.nodes.empty());
  EXPECT_EQ(bvh.triangles.size(), scene.triangles.size());
  std::vector<int> seen(scene.triangles.size(), 0);
  for (const BvhTriangle& t : bvh.triangles) ++seen.at(t.prim);
  EXPECT_TRUE(std::all_of(seen.begin(), seen.end(), [](int c) { return c == 1; }));
  EXPECT_LE(bvh.depth, kBvhStackSize);
  size_t checked = 0;
  auto inside = [](glm::vec3 p, glm::vec3 lo, glm::vec3 hi) {
    return glm::all(glm::greaterThanEqual(p, lo)) && glm::all(glm::lessThanEqual(p, hi));
  };
  for (const BvhNode& n : bvh.nodes)
    for (int c = 0; c < 2; ++c) {
      const int32_t link = c == 0 ? n.link0 : n.link1, count = c == 0 ? n.count0 : n.count1;
      const glm::vec3 lo = c == 0 ? n.lo0 : n.lo1, hi = c == 0 ? n.hi0 : n.hi1;
      if (link >= 0) {
        ASSERT_LT(static_cast<size_t>(link), bvh.nodes.size());
        const BvhNode& child = bvh.nodes[link];
        // A child's boxes lie within its parent's slot
        for (int k = 0; k < 2; ++k) {
          const int32_t ck = k == 0 ? child.count0 : child.count1, cl = k == 0 ? child.link0 : child.link1;
          if (cl < 0 && ck == 0) continue;
          EXPECT_TRUE(inside(k == 0 ? child.lo0 : child.lo1, lo, hi) && inside(k == 0 ? child.hi0 : child.hi1, lo, hi));
        }
        continue;
      }
      for (int32_t t = ~link; t < ~link + count; ++t) {
        const BvhTriangle& tri = bvh.triangles.at(t);
        for (glm::vec3 v : {tri.v0, tri.v0 + tri.e1, tri.v0 + tri.e2}) EXPECT_TRUE(inside(v, lo - 1e-4f, hi + 1e-4f));
        ++checked;
      }
    }
  EXPECT_EQ(checked, scene.triangles.size());
}

// Primary rays of a camera: the same closest triangle as Embree (ties at shared edges aside),
// the same distance; AO rays from those hits: the same occlusion answers.
void expect_same_hits_as_embree(const Scene& scene, const Camera& camera, int w, int h, double min_prim_agreement,
                                double min_occlusion_agreement) {
  const Bvh bvh = build_bvh(scene);
  expect_well_formed(scene, bvh);
  const BvhView view{bvh.nodes.data(), bvh.triangles.data()};
  const Tracer tracer(scene);
  const CameraRays camera_ray(camera, w, h);
  std::vector<Ray> rays;
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) rays.push_back(camera_ray(x + 0.5, y + 0.5));
  std::vector<Hit> embree(rays.size());
  tracer.intersect(rays, embree);
  size_t same = 0, both_hit = 0, hits = 0;
  double worst_t = 0;
  for (size_t i = 0; i < rays.size(); ++i) {
    Hit mine;
    const bool hit = bvh_trace<false>(view, rays[i], &mine);
    EXPECT_EQ(hit, mine.valid());
    hits += embree[i].valid();
    if (mine.prim == embree[i].prim) ++same;
    if (hit && embree[i].valid()) {
      ++both_hit;
      worst_t = std::max<double>(worst_t, std::abs(mine.t - embree[i].t) / embree[i].t);
    }
  }
  ASSERT_GT(hits, rays.size() / 4) << "the camera must see the scene";
  EXPECT_GE(static_cast<double>(same) / rays.size(), min_prim_agreement) << same << " of " << rays.size();
  EXPECT_LT(worst_t, 1e-4) << "distance to the closest hit";
  // Occlusion of the AO rays the renderer would trace from every 7th pixel
  RenderParams p;
  p.width = w;
  p.height = h;
  p.mode = RenderMode::full;
  p.foveation.max_rays = 16;
  const GBuffer g = trace_primary(tracer, scene, camera, w, h);
  const FoveationMaps maps = foveation_maps(p, {w * 0.5, h * 0.5});
  std::vector<Ray> ao;
  collect_ao_rays(g, maps, 0.2f * scene.bounds().diagonal(), surface_epsilon(scene.bounds()), 1, 7, ao);
  ASSERT_GT(ao.size(), 1000u);
  std::vector<Ray> copy = ao;
  std::vector<uint8_t> occluded(ao.size());
  tracer.occluded(copy, occluded);
  size_t agree = 0, blocked = 0;
  for (size_t i = 0; i < ao.size(); ++i) {
    const bool mine = bvh_trace<true>(view, ao[i], nullptr);
    agree += mine == (occluded[i] != 0);
    blocked += occluded[i] != 0;
  }
  EXPECT_GT(blocked, ao.size() / 20) << "the sample must hold occluded rays";
  EXPECT_LT(blocked, ao.size()) << "and open ones";
  EXPECT_GE(static_cast<double>(agree) / ao.size(), min_occlusion_agreement) << agree << " of " << ao.size();
}

TEST(Bvh, BuiltinBoxTracesLikeEmbree) {
  const Scene scene = make_builtin_scene("box");
  expect_same_hits_as_embree(scene, first_camera(scene), 160, 100, 0.999, 0.999);
}

TEST(Bvh, SpherePlaneTracesLikeEmbree) {
  const Scene scene = make_builtin_scene("sphere-plane");
  expect_same_hits_as_embree(scene, first_camera(scene), 160, 100, 0.999, 0.999);
}

TEST(Bvh, DragonTracesLikeEmbree) {
  const std::string dragon = FOVEAL_DATA_DIR "/scenes/dragon/dragon.obj";
  if (!std::filesystem::exists(dragon)) GTEST_SKIP() << "skipped: " << dragon << " absent";
  const Scene scene = load_scene(FOVEAL_SOURCE_DIR "/scenes/dragon-box.json");
  expect_same_hits_as_embree(scene, find_camera(scene, "camera1"), 210, 131, 0.999, 0.999);
}

TEST(Bvh, EmptyAndSingleTriangleScenes) {
  Scene empty;
  const Bvh none = build_bvh(empty);
  ASSERT_EQ(none.nodes.size(), 1u);
  Ray r;
  r.dir = {0, 0, -1};
  Hit h;
  EXPECT_FALSE(bvh_trace<false>({none.nodes.data(), none.triangles.data()}, r, &h));
  EXPECT_FALSE(bvh_trace<true>({none.nodes.data(), none.triangles.data()}, r, nullptr));
  Scene one;
  one.positions = {{-1, -1, -2}, {1, -1, -2}, {0, 1, -2}};
  one.normals = {{0, 0, 1}, {0, 0, 1}, {0, 0, 1}};
  one.uvs.assign(3, glm::vec2(0));
  one.triangles = {{0, 1, 2}};
  one.material_ids = {0};
  one.materials.emplace_back();
  const Bvh bvh = build_bvh(one);
  const BvhView view{bvh.nodes.data(), bvh.triangles.data()};
  ASSERT_TRUE(bvh_trace<false>(view, r, &h));
  EXPECT_EQ(h.prim, 0u);
  EXPECT_FLOAT_EQ(h.t, 2.0f);
  // Barycentrics of vertices 1 and 2 at (0, 0, -2): w0 = 0.25·2 … solve: p = v0 + u e1 + v e2
  EXPECT_NEAR(h.u, 0.25f, 1e-6f);
  EXPECT_NEAR(h.v, 0.5f, 1e-6f);
  r.tfar = 1.9f;  // the interval ends before the triangle
  EXPECT_FALSE(bvh_trace<true>(view, r, nullptr));
  r.tfar = 1e30f;
  r.dir = {0, 0, 1};  // away from it
  Hit away;
  EXPECT_FALSE(bvh_trace<false>(view, r, &away));
  EXPECT_EQ(away.prim, Hit::kNoHit);
  EXPECT_FALSE(bvh_trace<true>(view, r, nullptr));
}

}  // namespace
}  // namespace foveal
