// foveal/scene/scene.h — triangle scenes: geometry, materials, textures, cameras and lights.
//
// A Scene is plain data: one flat triangle list (every mesh already transformed to world
// space), per-vertex normals and texture coordinates, and a material per triangle. It comes
// from a mesh file (through Assimp), a scene JSON file, or a built-in generator.
#pragma once

#include "foveal/util/hd.h"

#include <glm/glm.hpp>

#include <cmath>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

namespace foveal {

// An 8-bit sRGB texture, rows top to bottom (kept 8-bit: Sponza's 39 textures stay small).
struct Texture {
  std::string path;           // file it was read from
  int width = 0, height = 0;  // texels
  std::vector<uint8_t> rgb;   // width*height*3, sRGB-encoded

  // Bilinear, wrapping lookup in linear RGB; uv origin at the bottom-left as in OBJ.
  glm::vec3 sample(glm::vec2 uv) const;
};

// The 256 sRGB byte values decoded to linear.
const float* srgb_to_linear_lut();

// A texture's texels wherever they are (host or device memory), for the per-pixel shading code.
struct TextureView {
  const uint8_t* rgb = nullptr;  // width*height*3, sRGB-encoded
  int width = 0, height = 0;
};

// Texture::sample on a view, with `lut` = srgb_to_linear_lut() or its device copy.
FOVEAL_HD inline glm::vec3 sample_texture(const TextureView& tex, const float* lut, glm::vec2 uv) {
  if (tex.width <= 0 || tex.height <= 0 || !std::isfinite(uv.x) || !std::isfinite(uv.y)) return glm::vec3(1.0f);
  // Texel coordinates with wrap-around; v flipped since rows run top to bottom
  const float fx = (uv.x - std::floor(uv.x)) * tex.width - 0.5f;
  const float fy = (1.0f - (uv.y - std::floor(uv.y))) * tex.height - 0.5f;
  const int x0 = static_cast<int>(std::floor(fx)), y0 = static_cast<int>(std::floor(fy));
  const float tx = fx - x0, ty = fy - y0;
  auto texel = [&](int x, int y) {
    x = ((x % tex.width) + tex.width) % tex.width;
    y = ((y % tex.height) + tex.height) % tex.height;
    const uint8_t* p = &tex.rgb[(static_cast<size_t>(y) * tex.width + x) * 3];
    return glm::vec3(lut[p[0]], lut[p[1]], lut[p[2]]);
  };
  return glm::mix(glm::mix(texel(x0, y0), texel(x0 + 1, y0), tx), glm::mix(texel(x0, y0 + 1), texel(x0 + 1, y0 + 1), tx), ty);
}

// Phong material of eq. 2 (reflectances in linear RGB).
struct Material {
  std::string name;
  glm::vec3 diffuse{0.8f};   // k_d, also the albedo lit by the ambient term
  glm::vec3 specular{0.0f};  // k_s
  float shininess = 32.0f;   // Phong exponent α
  int diffuse_texture = -1;  // index into Scene::textures, or -1
};

// A pinhole camera in scene units; fov is vertical, degrees.
struct Camera {
  std::string name;
  glm::vec3 eye{0, 0, 5};
  glm::vec3 look{0, 0, 0};
  glm::vec3 up{0, 1, 0};
  float fov_deg = 45.0f;
};

// The same view: position, target, up and field of view all equal.
inline bool same_camera(const Camera& a, const Camera& b) {
  return a.eye == b.eye && a.look == b.look && a.up == b.up && a.fov_deg == b.fov_deg;
}

// A camera that moves: linear interpolation through key cameras (eye, look, up, fov), from the
// first key at step 1 to the last at step `steps`, held there afterwards.
// The camera moved `degrees` around its look point, about its up axis (right-handed: from +z
// towards +x about +y): an orbit that keeps the view on the look point at the same distance.
Camera orbit_camera(const Camera& camera, double degrees);

struct CameraPath {
  std::string name;
  std::vector<Camera> keys;  // at least two
  int steps = 2;             // steps from the first key to the last (≥ 2)
  Camera at(int step) const;
};

// Point light (position) or directional light (direction the light travels).
struct Light {
  enum class Type { point, directional } type = Type::point;
  glm::vec3 vector{0.0f};    // position (point) or direction (directional), scene units
  glm::vec3 diffuse{0.5f};   // i_d
  glm::vec3 specular{0.3f};  // i_s
};

// Axis-aligned bounding box.
struct Bounds {
  glm::vec3 lo{1e30f}, hi{-1e30f};
  void extend(glm::vec3 p) {
    lo = glm::min(lo, p);
    hi = glm::max(hi, p);
  }
  glm::vec3 centre() const { return (lo + hi) * 0.5f; }
  float diagonal() const { return glm::length(hi - lo); }
  bool valid() const { return lo.x <= hi.x; }
};

// A whole scene in world space.
struct Scene {
  std::string source;                  // what it was loaded from
  std::vector<glm::vec3> positions;    // per vertex, scene units
  std::vector<glm::vec3> normals;      // per vertex, unit length
  std::vector<glm::vec2> uvs;          // per vertex (zero where the mesh has none)
  std::vector<glm::uvec3> triangles;   // vertex indices
  std::vector<uint32_t> material_ids;  // per triangle
  std::vector<Material> materials;
  std::vector<Texture> textures;
  std::vector<Camera> cameras;           // named viewpoints (may be empty)
  std::vector<CameraPath> camera_paths;  // named camera paths through the cameras (may be empty)
  std::vector<Light> lights;             // empty → a head light at the camera
  glm::vec3 ambient{0.6f};               // i_a of eq. 2
  double meters_per_unit = 1.0;          // scene unit in metres
  std::optional<float> ao_distance;      // AO ray length, scene units (unset → 0.2 × diagonal)
  size_t skipped_triangles = 0;          // degenerate, non-finite or out-of-range triangles dropped on load

  Bounds bounds() const;
};

// Load a mesh file, a scene JSON file (.json) or "builtin:NAME"; throws Error on bad input.
Scene load_scene(const std::string& spec);

// Names of the built-in scenes ("box", "sphere-plane", …).
std::vector<std::string> builtin_scene_names();
// Make a built-in scene by name; throws Error for an unknown name.
Scene make_builtin_scene(const std::string& name);

// Append a mesh file read by Assimp, transformed by `transform`; throws Error naming the file.
void append_mesh_file(Scene& scene, const std::string& path, const glm::mat4& transform,
                      std::optional<glm::vec3> diffuse_override = std::nullopt);

// One mesh's vertex data before it joins a scene (normals and uvs may be empty).
struct MeshData {
  std::vector<glm::vec3> positions;
  std::vector<glm::vec3> normals;  // per vertex, or empty: computed from the faces
  std::vector<glm::vec2> uvs;      // per vertex, or empty
  std::vector<glm::uvec3> triangles;
};

// The largest coordinate a vertex may have, in scene units: the renderer squares distances in
// single precision (the largest float is 3.4e38), and a vertex at 1e21 (a corrupt binary PLY) made
// the camera framing the scene non-finite, which aborted the process in Embree.
inline constexpr float kMaxSceneCoordinate = 1e15f;

// Append a mesh with an existing material, transformed to world space: degenerate or
// non-finite triangles, and those with a coordinate beyond ±kMaxSceneCoordinate, are dropped
// (counted in skipped_triangles), missing or broken normals are the area-weighted average of the
// adjacent faces. Throws Error for an index out of range.
void append_mesh(Scene& scene, const MeshData& mesh, uint32_t material_id, const glm::mat4& transform);
// Make room for this many more vertices and triangles in the scene's arrays (one allocation each
// instead of growth by doubling, which briefly holds two copies).
void reserve_mesh_space(Scene& scene, size_t vertices, size_t triangles);

// Append raw triangles with one material; drops degenerate triangles; computes missing normals.
void append_triangles(Scene& scene, const std::vector<glm::vec3>& positions, const std::vector<glm::uvec3>& triangles,
                      const Material& material, const glm::mat4& transform = glm::mat4(1.0f));

// Shapes for built-ins and scene JSON: a sphere (UV-tessellated), a square plane (y up) and an
// open box of five walls (no wall at +z, the side facing the default camera).
void append_sphere(Scene& scene, glm::vec3 centre, float radius, int segments, const Material& material);
void append_plane(Scene& scene, glm::vec3 centre, float half_size, const Material& material);
void append_open_box(Scene& scene, glm::vec3 lo, glm::vec3 hi, const Material& material);

// A camera looking at the whole scene from +z (used when the scene names none).
Camera default_camera(const Scene& scene);
// The camera used when none is asked for: the scene's first named one, else default_camera().
Camera first_camera(const Scene& scene);
// Find a camera by name; throws Error listing the known names.
const Camera& find_camera(const Scene& scene, const std::string& name);
// The named camera path; throws Error listing the known ones.
const CameraPath& find_camera_path(const Scene& scene, const std::string& name);

// Scene file parsers, exposed for tests and fuzzing.
Scene parse_scene_json(const std::string& text, const std::string& path, const std::string& base_dir);

}  // namespace foveal
