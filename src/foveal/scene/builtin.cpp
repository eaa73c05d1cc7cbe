// foveal/scene/builtin.cpp — scenes that need no files: the papers' box and the analytic AO case.
#include "foveal/scene/scene.h"
#include "foveal/util/error.h"

#include <cmath>
#include <numbers>

namespace foveal {
namespace {

constexpr float kPi = std::numbers::pi_v<float>;

// A (2,3) torus knot tube with ridges: a detailed, self-occluding object of 110,592 triangles.
void append_torus_knot(Scene& scene, glm::vec3 centre, float scale, const Material& material) {
  const int along = 768, around = 72;
  auto curve = [&](float t) {
    const float p = 2.0f, q = 3.0f, r = 0.6f + 0.3f * std::cos(q * t);
    return glm::vec3(r * std::cos(p * t), 0.3f * std::sin(q * t), r * std::sin(p * t));
  };
  std::vector<glm::vec3> positions;
  std::vector<glm::uvec3> triangles;
  for (int i = 0; i < along; ++i) {
    const float t = 2.0f * kPi * i / along;
    // Frame along the curve from its tangent and the second difference
    const glm::vec3 c = curve(t), tangent = glm::normalize(curve(t + 1e-3f) - curve(t - 1e-3f));
    glm::vec3 normal = glm::normalize(glm::cross(tangent, glm::vec3(0, 1, 0)));
    const glm::vec3 binormal = glm::normalize(glm::cross(tangent, normal));
    for (int j = 0; j < around; ++j) {
      const float a = 2.0f * kPi * j / around;
      const float radius = 0.12f * (1.0f + 0.18f * std::sin(40.0f * t) * std::sin(6.0f * a));
      positions.push_back(centre + scale * (c + radius * (std::cos(a) * normal + std::sin(a) * binormal)));
    }
  }
  for (int i = 0; i < along; ++i)
    for (int j = 0; j < around; ++j) {
      const uint32_t a = i * around + j, b = i * around + (j + 1) % around;
      const uint32_t c = ((i + 1) % along) * around + j, d = ((i + 1) % along) * around + (j + 1) % around;
      triangles.push_back({a, c, b});
      triangles.push_back({b, c, d});
    }
  append_triangles(scene, positions, triangles, material);
}

}  // namespace

std::vector<std::string> builtin_scene_names() { return {"box", "sphere-plane", "plane"}; }

Scene make_builtin_scene(const std::string& name) {
  Scene scene;
  scene.source = "builtin:" + name;
  Material wall{"wall", glm::vec3(0.75f, 0.73f, 0.70f)};
  Material object{"object", glm::vec3(0.80f, 0.55f, 0.35f), glm::vec3(0.25f), 48.0f};
  if (name == "box") {
    // The papers' setting: a five-wall box, open towards the camera, around a detailed object
    append_open_box(scene, {-2.0f, 0.0f, -2.0f}, {2.0f, 2.6f, 2.0f}, wall);
    append_torus_knot(scene, {0.0f, 0.85f, -0.3f}, 1.6f, object);
    append_sphere(scene, {1.35f, 0.35f, 0.9f}, 0.35f, 64, Material{"ball", glm::vec3(0.35f, 0.5f, 0.8f)});
    scene.cameras = {{"front", {0.0f, 1.35f, 6.2f}, {0.0f, 1.1f, 0.0f}, {0, 1, 0}, 45.0f},
                     {"corner", {-1.8f, 2.3f, 4.6f}, {0.3f, 0.6f, -0.6f}, {0, 1, 0}, 50.0f},
                     {"close", {0.5f, 1.2f, 2.4f}, {0.0f, 0.8f, -0.3f}, {0, 1, 0}, 55.0f}};
    scene.lights = {{Light::Type::point, {1.2f, 2.3f, 2.5f}, glm::vec3(0.45f), glm::vec3(0.3f)}};
    scene.meters_per_unit = 1.0;
  } else if (name == "sphere-plane") {
    // The analytic AO case: under the centre of a sphere of radius R at height H, V = 1 − (R/H)²
    append_plane(scene, {0.0f, 0.0f, 0.0f}, 1000.0f, wall);
    append_sphere(scene, {0.0f, 2.0f, 0.0f}, 1.0f, 512, Material{"sphere", glm::vec3(0.8f)});
    scene.cameras = {{"front", {0.0f, 2.5f, 6.0f}, {0.0f, 0.8f, 0.0f}, {0, 1, 0}, 45.0f}};
    scene.ao_distance = INFINITY;
  } else if (name == "plane") {
    // An open plane: nothing occludes it, V = 1 everywhere
    append_plane(scene, {0.0f, 0.0f, 0.0f}, 1000.0f, wall);
    scene.cameras = {{"front", {0.0f, 2.0f, 6.0f}, {0.0f, 0.0f, 0.0f}, {0, 1, 0}, 45.0f}};
    scene.ao_distance = INFINITY;
  } else {
    std::string known;
    for (const auto& n : builtin_scene_names()) known += (known.empty() ? "" : ", ") + n;
    fail("unknown built-in scene 'builtin:{}' (known: {})", name, known);
  }
  return scene;
}

}  // namespace foveal
