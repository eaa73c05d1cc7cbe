// foveal/render/pixel.h — the renderer's per-pixel functions, written once for both backends.
//
// Camera rays, the surface point of a hit, a pixel's AO ray directions and Phong shading are
// FOVEAL_HD functions over plain views of the scene: render.cpp calls them from oneTBB tiles
// with Embree's hits, the CUDA kernels from GPU threads with their own BVH's hits. Each is a
// pure function of its arguments, so the two backends differ only where float arithmetic does
// (fused multiply-adds on the GPU, ray-triangle tests at edges).
#pragma once

#include "foveal/scene/scene.h"
#include "foveal/trace/tracer.h"
#include "foveal/util/hd.h"
#include "foveal/util/sampling.h"

#include <glm/glm.hpp>

#include <cmath>
#include <cstdint>
#include <limits>
#include <vector>

namespace foveal {

// Primary rays of a pinhole camera for one image size; the basis is computed once.
class CameraRays {
 public:
  CameraRays(const Camera& camera, int width, int height);
  // Ray through a render position (pixel centres at +0.5), unit direction.
  FOVEAL_HD Ray operator()(double x_px, double y_px) const {
    const auto sx = static_cast<float>(2.0 * x_px / width_ - 1.0), sy = static_cast<float>(1.0 - 2.0 * y_px / height_);
    Ray r;
    r.org = eye_;
    r.dir = glm::normalize(forward_ + sx * right_ + sy * up_);
    r.tnear = 0.0f;
    r.tfar = std::numeric_limits<float>::infinity();
    return r;
  }
  // The render position (pixel centres at +0.5) whose ray passes through `p`, and the distance
  // from the eye to p; false when p is not in front of the camera.
  FOVEAL_HD bool project(glm::vec3 p, double& x_px, double& y_px, float& distance) const {
    const glm::vec3 d = p - eye_;
    const float z = glm::dot(d, forward_);
    if (!(z > 0)) return false;
    const float sx = glm::dot(d, right_) / (z * glm::dot(right_, right_));
    const float sy = glm::dot(d, up_) / (z * glm::dot(up_, up_));
    x_px = (static_cast<double>(sx) + 1.0) * 0.5 * width_;
    y_px = (1.0 - static_cast<double>(sy)) * 0.5 * height_;
    distance = glm::length(d);
    return true;
  }

 private:
  glm::vec3 eye_, forward_, right_, up_;  // right_ and up_ scaled to the image plane at distance 1
  int width_, height_;
};

// Offset along the normal for a ray leaving point p: the scene's epsilon plus 10⁻⁵ × |p|∞
// (about 80 float ulps of the point's magnitude).
FOVEAL_HD inline float ray_offset(glm::vec3 p, float scene_epsilon) {
  return scene_epsilon + 1e-5f * fmaxf(fmaxf(fabsf(p.x), fabsf(p.y)), fabsf(p.z));
}

// The AO rays of one pixel: the hemisphere frame, the lifted origin and the pixel's scramble of
// the Sobol sequence (`sobol_table` = sobol_table_2d() or its device copy).
struct AoPixelRays {
  Frame3 frame;
  glm::vec3 origin;
  SobolScramble scramble;
  float distance;

  FOVEAL_HD AoPixelRays(glm::vec3 position, glm::vec3 normal, float epsilon, float ao_distance, uint64_t seed, uint32_t x, uint32_t y,
                        const uint32_t* sobol_table)
      : frame(make_frame(normal)),
        origin(position + ray_offset(position, epsilon) * normal),
        scramble(sobol_scramble(pixel_seed(seed, x, y), sobol_table)),
        distance(ao_distance) {}

  // Cosine-weighted ray k of the pixel's scrambled Sobol sequence.
  FOVEAL_HD Ray operator()(uint32_t k) const {
    Ray r;
    r.org = origin;
    r.tnear = 0.0f;
    r.dir = frame.to_world(cosine_hemisphere(sobol_2d(k, scramble)));
    r.tfar = distance;
    return r;
  }
};

// A material as the shading code reads it.
struct MaterialView {
  glm::vec3 diffuse;
  glm::vec3 specular;
  float shininess;
  int diffuse_texture;  // index into SceneView::textures, or -1
};

// The scene's per-vertex and per-triangle arrays, in host or device memory.
struct SceneView {
  const glm::vec3* positions = nullptr;
  const glm::vec3* normals = nullptr;
  const glm::vec2* uvs = nullptr;
  const glm::uvec3* triangles = nullptr;
  const uint32_t* material_ids = nullptr;
  const MaterialView* materials = nullptr;
  const TextureView* textures = nullptr;
  const float* srgb_lut = nullptr;
};

// The scene's materials as the shading code reads them (host memory; the GPU uploads a copy).
std::vector<MaterialView> material_views(const Scene& scene);
// Host views of a scene; the material and texture views are written into the two vectors.
SceneView scene_view(const Scene& scene, std::vector<MaterialView>& materials, std::vector<TextureView>& textures);

// What the G-buffer keeps of a primary hit.
struct Surface {
  glm::vec3 position;    // from the barycentrics (more precise than org + t·dir)
  glm::vec3 geo_normal;  // unit, facing the ray's origin (the AO hemisphere)
  glm::vec3 normal;      // interpolated shading normal, unit, never on the far side
  glm::vec3 albedo;      // material colour times the diffuse texture
};

FOVEAL_HD inline Surface surface_at(const SceneView& s, const Hit& h, glm::vec3 dir) {
  Surface out;
  const glm::uvec3 tri = s.triangles[h.prim];
  const float w = 1.0f - h.u - h.v;
  out.position = w * s.positions[tri.x] + h.u * s.positions[tri.y] + h.v * s.positions[tri.z];
  glm::vec3 ng = glm::normalize(h.ng);
  if (glm::dot(ng, dir) > 0) ng = -ng;
  glm::vec3 ns = w * s.normals[tri.x] + h.u * s.normals[tri.y] + h.v * s.normals[tri.z];
  const float len = glm::length(ns);
  ns = len > 0 && std::isfinite(len) ? ns / len : ng;
  if (glm::dot(ns, ng) < 0) ns = -ns;
  out.geo_normal = ng;
  out.normal = ns;
  const MaterialView& m = s.materials[s.material_ids[h.prim]];
  glm::vec3 albedo = m.diffuse;
  if (m.diffuse_texture >= 0) {
    const glm::vec2 uv = w * s.uvs[tri.x] + h.u * s.uvs[tri.y] + h.v * s.uvs[tri.z];
    albedo *= sample_texture(s.textures[m.diffuse_texture], s.srgb_lut, uv);
  }
  out.albedo = albedo;
  return out;
}

// Colour of pixels that hit nothing, linear RGB.
FOVEAL_HD inline glm::vec3 background_colour() { return {0.06f, 0.06f, 0.08f}; }

// Phong shading of eq. 2 at a surface point seen along `view_dir`, with the ambient factor k_a
// already blended. `occluded(ray)` answers shadow rays (called only when `shadows`).
template <class Occluded>
FOVEAL_HD glm::vec3 shade_point(const MaterialView& m, glm::vec3 albedo, glm::vec3 p, glm::vec3 n, glm::vec3 ng, glm::vec3 view_dir,
                                float ka, glm::vec3 ambient, const Light* lights, int light_count, bool shadows, float epsilon,
                                Occluded&& occluded) {
  const glm::vec3 v = -view_dir;
  glm::vec3 c = ka * ambient * albedo;
  for (int k = 0; k < light_count; ++k) {
    const Light& light = lights[k];
    glm::vec3 l = light.type == Light::Type::point ? light.vector - p : -light.vector;
    const float dist = glm::length(l);
    if (!(dist > 0)) continue;
    l /= dist;
    const float ndotl = glm::dot(n, l);
    if (ndotl <= 0) continue;
    if (shadows) {
      Ray s;
      s.org = p + ray_offset(p, epsilon) * ng;
      s.dir = l;
      s.tfar = light.type == Light::Type::point ? dist : 1e30f;
      if (occluded(s)) continue;
    }
    const glm::vec3 r = glm::reflect(-l, n);
    const float rdotv = fmaxf(0.0f, glm::dot(r, v));
    c += albedo * ndotl * light.diffuse + m.specular * std::pow(rdotv, m.shininess) * light.specular;
  }
  return c;
}

}  // namespace foveal
