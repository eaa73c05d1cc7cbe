// foveal/trace/bvh.h — a flat two-wide BVH for the GPU backend, and its traversal.
//
// build_bvh() runs Embree's surface-area-heuristic builder (rtcBuildBVH, binned SAH) over the
// scene's triangles and flattens the tree depth first into 64-byte nodes that hold both
// children's boxes (the layout of Aila & Laine 2009), with each leaf's triangles stored
// contiguously as a vertex and two edges. bvh_trace() is the stack-based traversal the CUDA
// kernels run; it is plain C++ too, so the tests compare it with Embree on the CPU.
#pragma once

#include "foveal/trace/tracer.h"
#include "foveal/util/hd.h"

#include <glm/glm.hpp>

#include <cmath>
#include <cstdint>
#include <vector>

namespace foveal {

struct Scene;

// Two children: box and link each. link ≥ 0: inner node index; link < 0: a leaf of `count`
// triangles starting at ~link (count 0: an empty slot, never entered).
struct alignas(16) BvhNode {
  glm::vec3 lo0;
  int32_t link0;
  glm::vec3 hi0;
  int32_t count0;
  glm::vec3 lo1;
  int32_t link1;
  glm::vec3 hi1;
  int32_t count1;
};
static_assert(sizeof(BvhNode) == 64);

// A triangle as v0 and the edges e1 = v1 − v0, e2 = v2 − v0 (Möller–Trumbore), with its index in Scene::triangles.
struct alignas(16) BvhTriangle {
  glm::vec3 v0;
  uint32_t prim;
  glm::vec3 e1;
  float pad1;
  glm::vec3 e2;
  float pad2;
};
static_assert(sizeof(BvhTriangle) == 48);

struct Bvh {
  std::vector<BvhNode> nodes;          // nodes[0] is the root
  std::vector<BvhTriangle> triangles;  // leaf order
  int depth = 0;                       // longest root-to-leaf path, nodes
  double build_ms = 0;
  double sah_cost = 0;  // SAH cost relative to the root box (traversal 1, triangle 1)
};

// Build the BVH over every triangle of the scene; throws Error if Embree fails.
Bvh build_bvh(const Scene& scene);

// Pointers to a BVH's arrays, in host or device memory.
struct BvhView {
  const BvhNode* nodes = nullptr;
  const BvhTriangle* triangles = nullptr;
};

// The traversal stack: one entry per level at most, and the builder stops at this depth.
inline constexpr int kBvhStackSize = 32;

namespace bvh_detail {

// A node or triangle read as 16-byte vectors through the read-only cache on the GPU (one load
// instruction per 16 bytes instead of one per field); a plain copy on the CPU.
template <class T>
FOVEAL_HD inline T load(const T* p) {
#if defined(__CUDA_ARCH__)
  static_assert(sizeof(T) % 16 == 0 && alignof(T) == 16);
  T out;
  const auto* src = reinterpret_cast<const float4*>(p);
  auto* dst = reinterpret_cast<float4*>(&out);
#pragma unroll
  for (size_t k = 0; k < sizeof(T) / 16; ++k) dst[k] = __ldg(src + k);
  return out;
#else
  return *p;
#endif
}

// Entry and exit distances of a box, or false; the exit is widened by 2 ulps so that flat
// boxes (axis-aligned triangles) and grazing rays are never lost to rounding.
FOVEAL_HD inline bool slab(glm::vec3 lo, glm::vec3 hi, glm::vec3 org, glm::vec3 inv, float tnear, float tfar, float& entry) {
  const glm::vec3 t0 = (lo - org) * inv, t1 = (hi - org) * inv;
  const float tmin = fmaxf(fmaxf(fminf(t0.x, t1.x), fminf(t0.y, t1.y)), fmaxf(fminf(t0.z, t1.z), tnear));
  const float tmax = fminf(fminf(fmaxf(t0.x, t1.x), fmaxf(t0.y, t1.y)), fminf(fmaxf(t0.z, t1.z), tfar)) * 1.00000024f;
  entry = tmin;
  return tmin <= tmax;
}

// Möller–Trumbore; u, v are the barycentrics of vertices 1 and 2 as in Embree's hits.
FOVEAL_HD inline bool triangle(const BvhTriangle& tri, glm::vec3 org, glm::vec3 dir, float tnear, float tfar, float& t, float& u,
                               float& v) {
  const glm::vec3 p = glm::cross(dir, tri.e2);
  const float det = glm::dot(tri.e1, p);
  if (det == 0.0f) return false;
  const float inv = 1.0f / det;
  const glm::vec3 s = org - tri.v0;
  u = glm::dot(s, p) * inv;
  if (!(u >= 0.0f && u <= 1.0f)) return false;
  const glm::vec3 q = glm::cross(s, tri.e1);
  v = glm::dot(dir, q) * inv;
  if (!(v >= 0.0f && u + v <= 1.0f)) return false;
  t = glm::dot(tri.e2, q) * inv;
  return t >= tnear && t <= tfar;
}

}  // namespace bvh_detail

// Trace one ray. kAnyHit: true as soon as anything lies in [tnear, tfar] (hit untouched).
// Otherwise: the closest hit into `hit` (prim, t, u, v, unnormalised ng), true if any.
template <bool kAnyHit>
FOVEAL_HD inline bool bvh_trace(const BvhView& bvh, const Ray& ray, Hit* hit) {
  const glm::vec3 org = ray.org, dir = ray.dir;
  // Reciprocal direction; a zero component becomes a huge one of the same sign
  auto safe_inv = [](float d) { return 1.0f / (fabsf(d) > 1e-30f ? d : copysignf(1e-30f, d)); };
  const glm::vec3 inv(safe_inv(dir.x), safe_inv(dir.y), safe_inv(dir.z));
  const float tnear = ray.tnear;
  float tfar = ray.tfar;
  bool found = false;
  uint32_t best_prim = Hit::kNoHit;
  float best_u = 0, best_v = 0;
  glm::vec3 best_ng(0.0f);
  int32_t stack[kBvhStackSize];
  float stack_entry[kBvhStackSize];
  int sp = 0;
  int32_t node = 0;
  // Leaves are intersected as soon as their box is entered; inner children are visited near
  // first, the far one pushed with its entry distance and skipped if a closer hit came since.
  while (true) {
    const BvhNode n = bvh_detail::load(bvh.nodes + node);
    float e0, e1;
    const bool h0 = bvh_detail::slab(n.lo0, n.hi0, org, inv, tnear, tfar, e0);
    const bool h1 = bvh_detail::slab(n.lo1, n.hi1, org, inv, tnear, tfar, e1);
    int32_t inner[2];
    float inner_entry[2];
    int inner_count = 0;
    for (int c = 0; c < 2; ++c) {
      const bool h = c == 0 ? h0 : h1;
      if (!h) continue;
      const int32_t link = c == 0 ? n.link0 : n.link1;
      if (link >= 0) {
        inner[inner_count] = link;
        inner_entry[inner_count++] = c == 0 ? e0 : e1;
        continue;
      }
      const int32_t first = ~link, count = c == 0 ? n.count0 : n.count1;
      for (int32_t k = first; k < first + count; ++k) {
        const BvhTriangle tri = bvh_detail::load(bvh.triangles + k);
        float t, u, v;
        if (!bvh_detail::triangle(tri, org, dir, tnear, tfar, t, u, v)) continue;
        if constexpr (kAnyHit) {
          return true;
        } else {
          found = true;
          tfar = t;
          best_prim = tri.prim;
          best_u = u;
          best_v = v;
          best_ng = glm::cross(tri.e1, tri.e2);
        }
      }
    }
    if (inner_count == 2) {
      const bool swap = inner_entry[1] < inner_entry[0];
      stack[sp] = inner[swap ? 0 : 1];
      if constexpr (!kAnyHit) stack_entry[sp] = inner_entry[swap ? 0 : 1];
      ++sp;
      node = inner[swap ? 1 : 0];
      continue;
    }
    if (inner_count == 1) {
      node = inner[0];
      continue;
    }
    // Pop the next subtree that may still hold a closer hit (an any-hit ray's interval never
    // shrinks, so it keeps no entry distances)
    node = -1;
    while (sp > 0) {
      --sp;
      if (kAnyHit || stack_entry[sp] <= tfar) {
        node = stack[sp];
        break;
      }
    }
    if (node < 0) break;
  }
  if constexpr (!kAnyHit) {
    if (found) {
      hit->t = tfar;
      hit->prim = best_prim;
      hit->u = best_u;
      hit->v = best_v;
      hit->ng = best_ng;
    }
  }
  return found;
}

}  // namespace foveal
