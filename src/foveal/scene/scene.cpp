// foveal/scene/scene.cpp — scene assembly: triangles, normals, shapes, cameras, dispatch.
#include "foveal/scene/scene.h"
#include "foveal/util/memory.h"

#include "foveal/util/error.h"
#include "foveal/util/files.h"
#include "foveal/util/text.h"

#include <glm/gtc/matrix_inverse.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <numbers>
#include <sstream>

namespace foveal {
namespace {

// sRGB 8-bit → linear float, built once.
const std::array<float, 256>& srgb_to_linear_table() {
  static const std::array<float, 256> table = [] {
    std::array<float, 256> t{};
    for (int i = 0; i < 256; ++i) {
      const float c = i / 255.0f;
      t[i] = c <= 0.04045f ? c / 12.92f : std::pow((c + 0.055f) / 1.055f, 2.4f);
    }
    return t;
  }();
  return table;
}

bool finite(glm::vec3 v) { return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z); }
// Finite and within ±kMaxSceneCoordinate (NaN fails the comparison)
bool in_range(glm::vec3 v) {
  return std::abs(v.x) <= kMaxSceneCoordinate && std::abs(v.y) <= kMaxSceneCoordinate && std::abs(v.z) <= kMaxSceneCoordinate;
}

}  // namespace

glm::vec3 Texture::sample(glm::vec2 uv) const { return sample_texture({rgb.data(), width, height}, srgb_to_linear_lut(), uv); }

const float* srgb_to_linear_lut() { return srgb_to_linear_table().data(); }

Bounds Scene::bounds() const {
  Bounds b;
  for (const auto& t : triangles)
    for (int k = 0; k < 3; ++k) b.extend(positions[t[k]]);
  return b;
}

void reserve_mesh_space(Scene& scene, size_t vertices, size_t triangles) {
  scene.positions.reserve(scene.positions.size() + vertices);
  scene.normals.reserve(scene.normals.size() + vertices);
  scene.uvs.reserve(scene.uvs.size() + vertices);
  scene.triangles.reserve(scene.triangles.size() + triangles);
  scene.material_ids.reserve(scene.material_ids.size() + triangles);
}

void append_mesh(Scene& scene, const MeshData& mesh, uint32_t material_id, const glm::mat4& transform) {
  const auto base = static_cast<uint32_t>(scene.positions.size());
  const glm::mat3 normal_matrix = glm::inverseTranspose(glm::mat3(transform));
  for (const auto& p : mesh.positions) scene.positions.push_back(glm::vec3(transform * glm::vec4(p, 1.0f)));
  // Triangles with zero area or vertices that are non-finite or out of range are dropped; the rest
  // add area-weighted face normals
  std::vector<glm::vec3> face_normals(mesh.positions.size(), glm::vec3(0.0f));
  for (const auto& t : mesh.triangles) {
    if (t.x >= mesh.positions.size() || t.y >= mesh.positions.size() || t.z >= mesh.positions.size())
      fail("triangle index {} out of range ({} vertices)", std::max({t.x, t.y, t.z}), mesh.positions.size());
    const glm::vec3 a = scene.positions[base + t.x], b = scene.positions[base + t.y], c = scene.positions[base + t.z];
    const glm::vec3 n = glm::cross(b - a, c - a);
    if (!in_range(a) || !in_range(b) || !in_range(c) || !finite(n) || glm::dot(n, n) <= 0.0f) {
      ++scene.skipped_triangles;
      continue;
    }
    for (int k = 0; k < 3; ++k) face_normals[t[k]] += n;
    scene.triangles.push_back(t + glm::uvec3(base));
    scene.material_ids.push_back(material_id);
  }
  // Vertex normals: the mesh's own where usable, else the faces' average
  for (size_t v = 0; v < mesh.positions.size(); ++v) {
    glm::vec3 n = v < mesh.normals.size() ? normal_matrix * mesh.normals[v] : glm::vec3(0.0f);
    float len = glm::length(n);
    if (!(len > 0) || !std::isfinite(len)) {
      n = face_normals[v];
      len = glm::length(n);
    }
    scene.normals.push_back(len > 0 && std::isfinite(len) ? n / len : glm::vec3(0, 1, 0));
    scene.uvs.push_back(v < mesh.uvs.size() ? mesh.uvs[v] : glm::vec2(0.0f));
  }
}

void append_triangles(Scene& scene, const std::vector<glm::vec3>& positions, const std::vector<glm::uvec3>& triangles,
                      const Material& material, const glm::mat4& transform) {
  scene.materials.push_back(material);
  append_mesh(scene, MeshData{positions, {}, {}, triangles}, static_cast<uint32_t>(scene.materials.size() - 1), transform);
}

void append_sphere(Scene& scene, glm::vec3 centre, float radius, int segments, const Material& material) {
  const int rings = std::max(2, segments / 2), slices = std::max(3, segments);
  std::vector<glm::vec3> p;
  std::vector<glm::uvec3> t;
  for (int i = 0; i <= rings; ++i) {
    const float theta = std::numbers::pi_v<float> * i / rings;
    for (int j = 0; j <= slices; ++j) {
      const float phi = 2.0f * std::numbers::pi_v<float> * j / slices;
      p.push_back(centre + radius * glm::vec3(std::sin(theta) * std::cos(phi), std::cos(theta), std::sin(theta) * std::sin(phi)));
    }
  }
  for (int i = 0; i < rings; ++i)
    for (int j = 0; j < slices; ++j) {
      const uint32_t a = i * (slices + 1) + j, b = a + 1, c = a + slices + 1, d = c + 1;
      t.push_back({a, b, c});  // degenerate at the poles: dropped by append_triangles
      t.push_back({b, d, c});
    }
  const size_t first = scene.positions.size();
  append_triangles(scene, p, t, material);
  // Exact sphere normals instead of the averaged ones
  for (size_t v = first; v < scene.positions.size(); ++v) scene.normals[v] = glm::normalize(scene.positions[v] - centre);
}

void append_plane(Scene& scene, glm::vec3 c, float h, const Material& material) {
  append_triangles(scene, {c + glm::vec3(-h, 0, -h), c + glm::vec3(h, 0, -h), c + glm::vec3(h, 0, h), c + glm::vec3(-h, 0, h)},
                   {{0, 2, 1}, {0, 3, 2}}, material);
}

void append_open_box(Scene& scene, glm::vec3 lo, glm::vec3 hi, const Material& material) {
  // Each wall gets its own four vertices so that normals are not smoothed across the edges
  auto wall = [&](glm::vec3 a, glm::vec3 b, glm::vec3 c, glm::vec3 d) {
    append_triangles(scene, {a, b, c, d}, {{0, 1, 2}, {0, 2, 3}}, material);
  };
  const glm::vec3 l = lo, h = hi;
  wall({l.x, l.y, l.z}, {l.x, l.y, h.z}, {h.x, l.y, h.z}, {h.x, l.y, l.z});  // floor
  wall({l.x, h.y, l.z}, {h.x, h.y, l.z}, {h.x, h.y, h.z}, {l.x, h.y, h.z});  // ceiling
  wall({l.x, l.y, l.z}, {h.x, l.y, l.z}, {h.x, h.y, l.z}, {l.x, h.y, l.z});  // back (−z)
  wall({l.x, l.y, l.z}, {l.x, h.y, l.z}, {l.x, h.y, h.z}, {l.x, l.y, h.z});  // left (−x)
  wall({h.x, l.y, l.z}, {h.x, l.y, h.z}, {h.x, h.y, h.z}, {h.x, h.y, l.z});  // right (+x)
}

Camera first_camera(const Scene& scene) { return scene.cameras.empty() ? default_camera(scene) : scene.cameras.front(); }

Camera default_camera(const Scene& scene) {
  const Bounds b = scene.bounds();
  Camera cam;
  cam.name = "default";
  if (!b.valid()) return cam;
  const float radius = 0.5f * b.diagonal();
  cam.fov_deg = 45.0f;
  cam.look = b.centre();
  cam.eye = b.centre() + glm::vec3(0.0f, 0.15f * radius, radius / std::tan(glm::radians(cam.fov_deg) * 0.5f) * 1.05f);
  return cam;
}

const Camera& find_camera(const Scene& scene, const std::string& name) {
  std::string known;
  for (const auto& c : scene.cameras) {
    if (c.name == name) return c;
    known += (known.empty() ? "" : ", ") + c.name;
  }
  fail("scene '{}' has no camera named '{}' (known: {})", scene.source, name, known.empty() ? "none" : known);
}

const CameraPath& find_camera_path(const Scene& scene, const std::string& name) {
  std::string known;
  for (const auto& p : scene.camera_paths) {
    if (p.name == name) return p;
    known += (known.empty() ? "" : ", ") + p.name;
  }
  fail("scene '{}' has no camera path named '{}' (known: {})", scene.source, name, known.empty() ? "none" : known);
}

Camera orbit_camera(const Camera& camera, double degrees) {
  Camera c = camera;
  const glm::dvec3 axis = glm::normalize(glm::dvec3(camera.up));
  const glm::dvec3 r = glm::dvec3(camera.eye - camera.look);
  const double a = glm::radians(degrees), ca = std::cos(a), sa = std::sin(a);
  // Rodrigues' rotation of the look point → eye offset about the axis
  const glm::dvec3 rotated = r * ca + glm::cross(axis, r) * sa + axis * glm::dot(axis, r) * (1 - ca);
  c.eye = camera.look + glm::vec3(rotated);
  return c;
}

Camera CameraPath::at(int step) const {
  if (keys.empty()) return Camera{};
  if (keys.size() == 1 || step <= 1) return keys.front();
  if (step >= steps) return keys.back();
  // Position along the path in segments: steps 1…steps span keys 0…n−1
  const double s = double(step - 1) / double(steps - 1) * double(keys.size() - 1);
  const size_t k = std::min(size_t(s), keys.size() - 2);
  const float t = static_cast<float>(s - double(k));
  const Camera& a = keys[k];
  const Camera& b = keys[k + 1];
  Camera c;
  c.name = fmt::format("{} step {}", name, step);
  c.eye = glm::mix(a.eye, b.eye, t);
  c.look = glm::mix(a.look, b.look, t);
  c.up = glm::mix(a.up, b.up, t);
  if (glm::length(glm::cross(c.look - c.eye, c.up)) < 1e-6f) c.up = a.up;
  if (glm::length(c.look - c.eye) < 1e-6f) c.look = b.look;
  c.fov_deg = a.fov_deg + (b.fov_deg - a.fov_deg) * t;
  return c;
}

Scene load_scene(const std::string& spec) {
  namespace fs = std::filesystem;
  Scene scene;
  if (spec.rfind("builtin:", 0) == 0) {
    scene = make_builtin_scene(spec.substr(8));
  } else {
    std::error_code ec;
    if (!fs::exists(spec, ec)) fail("{}: no such file", spec);
    if (fs::is_directory(spec, ec)) fail("{}: is a directory, not a scene file", spec);
    if (fs::file_size(spec, ec) == 0) fail("{}: file is empty", spec);
    const std::string ext = lower_extension(spec);
    if (ext == ".json") {
      scene = parse_scene_json(text::read_file(spec), spec, fs::path(spec).parent_path().string());
    } else {
      append_mesh_file(scene, spec, glm::mat4(1.0f));  // (which notes the files it reads as inputs)
    }
  }
  if (scene.source.empty()) scene.source = spec;
  if (scene.triangles.empty()) fail("{}: contains no usable triangles", spec);
  release_freed_memory();  // the importer's copies, freed: not resident beside the BVH
  return scene;
}

}  // namespace foveal
