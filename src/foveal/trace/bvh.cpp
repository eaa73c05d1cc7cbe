// foveal/trace/bvh.cpp — Embree's SAH builder (rtcBuildBVH) into the flat two-wide BVH.
#include "foveal/trace/bvh.h"

#include "foveal/scene/scene.h"
#include "foveal/util/error.h"
#include "foveal/util/timer.h"

#include <embree3/rtcore.h>

#include <algorithm>
#include <limits>
#include <memory>

namespace foveal {
namespace {

// The tree as Embree's callbacks make it, in Embree's thread-local memory.
struct BuildNode {
  bool leaf;
};
struct BuildInner : BuildNode {
  BuildNode* children[2];
  RTCBounds bounds[2];
};
struct BuildLeaf : BuildNode {
  uint32_t count;
  const uint32_t* prims;
};

void* create_node(RTCThreadLocalAllocator alloc, unsigned int child_count, void*) {
  void* memory = rtcThreadLocalAlloc(alloc, sizeof(BuildInner), 16);
  auto* node = new (memory) BuildInner{};
  node->leaf = false;
  for (unsigned int k = child_count; k < 2; ++k) node->children[k] = nullptr;
  return node;
}

void set_children(void* node, void** children, unsigned int count, void*) {
  auto* inner = static_cast<BuildInner*>(node);
  for (unsigned int k = 0; k < 2; ++k) inner->children[k] = k < count ? static_cast<BuildNode*>(children[k]) : nullptr;
}

void set_bounds(void* node, const RTCBounds** bounds, unsigned int count, void*) {
  auto* inner = static_cast<BuildInner*>(node);
  for (unsigned int k = 0; k < count && k < 2; ++k) inner->bounds[k] = *bounds[k];
}

void* create_leaf(RTCThreadLocalAllocator alloc, const RTCBuildPrimitive* prims, size_t count, void*) {
  auto* ids = static_cast<uint32_t*>(rtcThreadLocalAlloc(alloc, sizeof(uint32_t) * count, 4));
  for (size_t k = 0; k < count; ++k) ids[k] = prims[k].primID;
  void* memory = rtcThreadLocalAlloc(alloc, sizeof(BuildLeaf), 16);
  auto* leaf = new (memory) BuildLeaf{};
  leaf->leaf = true;
  leaf->count = static_cast<uint32_t>(count);
  leaf->prims = ids;
  return leaf;
}

float half_area(glm::vec3 lo, glm::vec3 hi) {
  const glm::vec3 d = glm::max(hi - lo, glm::vec3(0.0f));
  return d.x * d.y + d.y * d.z + d.z * d.x;
}

// Depth-first flattening; returns the node's index.
struct Flattener {
  const Scene& scene;
  Bvh& bvh;
  double cost = 0;  // Σ area(inner)·1 + Σ area(leaf)·count, before dividing by the root's

  // A child slot: inner → its index; leaf → its triangles appended
  void link(const BuildNode* child, const RTCBounds& b, glm::vec3& lo, glm::vec3& hi, int32_t& link, int32_t& count, int depth) {
    if (child == nullptr) {  // empty slot: an inverted box and no triangles
      lo = glm::vec3(std::numeric_limits<float>::max());
      hi = glm::vec3(-std::numeric_limits<float>::max());
      link = -1;
      count = 0;
      return;
    }
    lo = {b.lower_x, b.lower_y, b.lower_z};
    hi = {b.upper_x, b.upper_y, b.upper_z};
    if (!child->leaf) {
      cost += half_area(lo, hi);
      link = flatten(static_cast<const BuildInner*>(child), depth + 1);
      count = 0;
      return;
    }
    const auto* leaf = static_cast<const BuildLeaf*>(child);
    link = ~static_cast<int32_t>(bvh.triangles.size());
    count = static_cast<int32_t>(leaf->count);
    cost += half_area(lo, hi) * leaf->count;
    bvh.depth = std::max(bvh.depth, depth + 1);
    for (uint32_t k = 0; k < leaf->count; ++k) {
      const uint32_t prim = leaf->prims[k];
      const glm::uvec3 t = scene.triangles[prim];
      const glm::vec3 v0 = scene.positions[t.x], v1 = scene.positions[t.y], v2 = scene.positions[t.z];
      bvh.triangles.push_back({v0, prim, v1 - v0, 0.0f, v2 - v0, 0.0f});
    }
  }

  int32_t flatten(const BuildInner* node, int depth) {
    const auto index = static_cast<int32_t>(bvh.nodes.size());
    bvh.nodes.emplace_back();
    bvh.depth = std::max(bvh.depth, depth);
    BvhNode n;
    link(node->children[0], node->bounds[0], n.lo0, n.hi0, n.link0, n.count0, depth);
    link(node->children[1], node->bounds[1], n.lo1, n.hi1, n.link1, n.count1, depth);
    bvh.nodes[static_cast<size_t>(index)] = n;
    return index;
  }
};

}  // namespace

Bvh build_bvh(const Scene& scene) {
  const Timer timer;
  Bvh bvh;
  std::vector<RTCBuildPrimitive> prims;
  prims.reserve(scene.triangles.size());
  glm::vec3 root_lo(std::numeric_limits<float>::max()), root_hi(-std::numeric_limits<float>::max());
  for (size_t i = 0; i < scene.triangles.size(); ++i) {
    const glm::uvec3 t = scene.triangles[i];
    const glm::vec3 a = scene.positions[t.x], b = scene.positions[t.y], c = scene.positions[t.z];
    const glm::vec3 lo = glm::min(a, glm::min(b, c)), hi = glm::max(a, glm::max(b, c));
    root_lo = glm::min(root_lo, lo);
    root_hi = glm::max(root_hi, hi);
    prims.push_back({lo.x, lo.y, lo.z, 0, hi.x, hi.y, hi.z, static_cast<unsigned>(i)});
  }
  if (prims.empty()) {  // no triangles: a root whose two slots are empty
    Flattener f{scene, bvh};
    BvhNode n;
    RTCBounds none{};
    f.link(nullptr, none, n.lo0, n.hi0, n.link0, n.count0, 0);
    f.link(nullptr, none, n.lo1, n.hi1, n.link1, n.count1, 0);
    bvh.nodes.push_back(n);
    bvh.depth = 1;
    bvh.build_ms = timer.ms();
    return bvh;
  }
  RTCDevice device = rtcNewDevice(nullptr);
  if (device == nullptr) fail("cannot create the Embree device (error {})", static_cast<int>(rtcGetDeviceError(nullptr)));
  RTCBVH handle = rtcNewBVH(device);
  RTCBuildArguments args = rtcDefaultBuildArguments();
  args.buildQuality = RTC_BUILD_QUALITY_MEDIUM;  // binned SAH
  args.maxBranchingFactor = 2;
  args.maxDepth = kBvhStackSize;
  args.minLeafSize = 1;
  args.maxLeafSize = 4;
  args.traversalCost = 1.0f;
  args.intersectionCost = 1.0f;
  args.bvh = handle;
  args.primitives = prims.data();
  args.primitiveCount = prims.size();
  args.primitiveArrayCapacity = prims.size();
  args.createNode = create_node;
  args.setNodeChildren = set_children;
  args.setNodeBounds = set_bounds;
  args.createLeaf = create_leaf;
  auto* root = static_cast<BuildNode*>(rtcBuildBVH(&args));
  const RTCError error = rtcGetDeviceError(device);
  if (root == nullptr || error != RTC_ERROR_NONE) {
    rtcReleaseBVH(handle);
    rtcReleaseDevice(device);
    fail("Embree's BVH builder failed (error {})", static_cast<int>(error));
  }
  Flattener f{scene, bvh};
  bvh.nodes.reserve(prims.size() / 2 + 1);  // about one inner node per two leaves of 1–4 triangles
  bvh.triangles.reserve(prims.size());
  if (root->leaf) {  // a scene small enough for one leaf: a root with one leaf child
    BvhNode n;
    RTCBounds all{root_lo.x, root_lo.y, root_lo.z, 0, root_hi.x, root_hi.y, root_hi.z, 0};
    bvh.nodes.emplace_back();
    f.link(root, all, n.lo0, n.hi0, n.link0, n.count0, 0);
    f.link(nullptr, all, n.lo1, n.hi1, n.link1, n.count1, 0);
    bvh.nodes[0] = n;
  } else {
    f.flatten(static_cast<const BuildInner*>(root), 1);
  }
  // Memory of the build tree belongs to the RTCBVH: release it only after flattening
  rtcReleaseBVH(handle);
  rtcReleaseDevice(device);
  if (bvh.depth > kBvhStackSize)  // the traversal's fixed stack holds one entry per level
    fail("the BVH is {} levels deep; the GPU traversal stack holds {}", bvh.depth, kBvhStackSize);
  const float root_area = half_area(root_lo, root_hi);
  bvh.sah_cost = root_area > 0 ? (f.cost + root_area) / root_area : 0.0;
  bvh.build_ms = timer.ms();
  return bvh;
}

}  // namespace foveal
