// foveal/scene/scene_json.cpp — the scene JSON format: meshes with transforms, shapes, cameras,
// lights, meters_per_unit and ao_distance. Unknown keys are errors, so typos do not pass silently.
#include "foveal/scene/scene.h"
#include "foveal/util/error.h"
#include "foveal/util/text.h"

#include <glm/gtc/matrix_transform.hpp>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <initializer_list>

namespace foveal {
namespace {

using nlohmann::json;

// Parsing context: the file and the JSON path of the value being read, for error messages.
struct Ctx {
  const std::string& file;
  std::string where;
  Ctx at(const std::string& key) const { return {file, where.empty() ? key : where + "." + key}; }
  Ctx at(size_t index) const { return {file, fmt::format("{}[{}]", where, index)}; }
  [[noreturn]] void error(const std::string& what) const { fail("{}: {}: {}", file, where, what); }
};

void check_keys(const Ctx& ctx, const json& obj, std::initializer_list<const char*> known) {
  if (!obj.is_object()) ctx.error("expected an object");
  for (const auto& [key, value] : obj.items()) {
    bool ok = false;
    std::string list;
    for (const char* k : known) {
      ok = ok || key == k;
      list += (list.empty() ? "" : ", ") + std::string(k);
    }
    if (!ok) ctx.error(fmt::format("unknown key '{}' (known: {})", key, list));
  }
}

float number(const Ctx& ctx, const json& v) {
  if (!v.is_number()) ctx.error("expected a number");
  const double d = v.get<double>();
  if (!std::isfinite(d)) ctx.error("expected a finite number");
  return static_cast<float>(d);
}

float positive(const Ctx& ctx, const json& v) {
  const float f = number(ctx, v);
  if (!(f > 0)) ctx.error(fmt::format("must be > 0, got {}", f));
  return f;
}

glm::vec3 vec3(const Ctx& ctx, const json& v) {
  if (!v.is_array() || v.size() != 3) ctx.error("expected an array of 3 numbers");
  return {number(ctx.at(0), v[0]), number(ctx.at(1), v[1]), number(ctx.at(2), v[2])};
}

std::string string(const Ctx& ctx, const json& v) {
  if (!v.is_string()) ctx.error("expected a string");
  return v.get<std::string>();
}

// translate / rotate [deg, x, y, z] / scale (number or 3) / matrix (16, row-major).
glm::mat4 transform(const Ctx& ctx, const json& m) {
  glm::mat4 t(1.0f);
  if (m.contains("matrix")) {
    const Ctx c = ctx.at("matrix");
    const json& a = m["matrix"];
    if (!a.is_array() || a.size() != 16) c.error("expected an array of 16 numbers (row-major)");
    for (int r = 0; r < 4; ++r)
      for (int k = 0; k < 4; ++k) t[k][r] = number(c.at(r * 4 + k), a[r * 4 + k]);
  }
  if (m.contains("translate")) t = t * glm::translate(glm::mat4(1.0f), vec3(ctx.at("translate"), m["translate"]));
  if (m.contains("rotate")) {
    const Ctx c = ctx.at("rotate");
    const json& r = m["rotate"];
    if (!r.is_array() || r.size() != 4) c.error("expected [degrees, axis_x, axis_y, axis_z]");
    const glm::vec3 axis(number(c.at(1), r[1]), number(c.at(2), r[2]), number(c.at(3), r[3]));
    if (glm::length(axis) == 0.0f) c.error("rotation axis must not be zero");
    t = t * glm::rotate(glm::mat4(1.0f), glm::radians(number(c.at(0), r[0])), glm::normalize(axis));
  }
  if (m.contains("scale")) {
    const Ctx c = ctx.at("scale");
    const glm::vec3 s = m["scale"].is_array() ? vec3(c, m["scale"]) : glm::vec3(positive(c, m["scale"]));
    if (s.x == 0 || s.y == 0 || s.z == 0) c.error("scale must not be zero");
    t = t * glm::scale(glm::mat4(1.0f), s);
  }
  return t;
}

Material material(const Ctx& ctx, const json& m) {
  Material mat;
  if (m.contains("diffuse")) mat.diffuse = vec3(ctx.at("diffuse"), m["diffuse"]);
  if (m.contains("specular")) mat.specular = vec3(ctx.at("specular"), m["specular"]);
  if (m.contains("shininess")) mat.shininess = positive(ctx.at("shininess"), m["shininess"]);
  return mat;
}

void mesh(Scene& scene, const Ctx& ctx, const json& m, const std::string& base_dir) {
  if (m.contains("file")) {
    check_keys(ctx, m, {"file", "translate", "rotate", "scale", "matrix", "diffuse"});
    std::filesystem::path file = string(ctx.at("file"), m["file"]);
    if (file.is_relative()) file = std::filesystem::path(base_dir) / file;
    std::optional<glm::vec3> diffuse;
    if (m.contains("diffuse")) diffuse = vec3(ctx.at("diffuse"), m["diffuse"]);
    append_mesh_file(scene, file.lexically_normal().string(), transform(ctx, m), diffuse);
    return;
  }
  if (!m.contains("shape")) ctx.error("a mesh needs either \"file\" or \"shape\"");
  const std::string shape = string(ctx.at("shape"), m["shape"]);
  if (shape == "box") {
    check_keys(ctx, m, {"shape", "min", "max", "diffuse", "specular", "shininess"});
    const glm::vec3 lo = vec3(ctx.at("min"), m.value("min", json())), hi = vec3(ctx.at("max"), m.value("max", json()));
    if (!(lo.x < hi.x && lo.y < hi.y && lo.z < hi.z)) ctx.error("box needs min < max on every axis");
    append_open_box(scene, lo, hi, material(ctx, m));
  } else if (shape == "sphere") {
    check_keys(ctx, m, {"shape", "centre", "radius", "segments", "diffuse", "specular", "shininess"});
    int segments = 128;
    if (m.contains("segments")) {
      const float s = number(ctx.at("segments"), m["segments"]);
      if (s < 3 || s > 4096 || s != std::floor(s)) ctx.at("segments").error("must be a whole number in [3, 4096]");
      segments = static_cast<int>(s);
    }
    append_sphere(scene, vec3(ctx.at("centre"), m.value("centre", json())), positive(ctx.at("radius"), m.value("radius", json())), segments,
                  material(ctx, m));
  } else if (shape == "plane") {
    check_keys(ctx, m, {"shape", "centre", "half_size", "diffuse", "specular", "shininess"});
    append_plane(scene, vec3(ctx.at("centre"), m.value("centre", json())), positive(ctx.at("half_size"), m.value("half_size", json())),
                 material(ctx, m));
  } else {
    ctx.at("shape").error(fmt::format("unknown shape '{}' (known: box, sphere, plane)", shape));
  }
}

}  // namespace

Scene parse_scene_json(const std::string& text, const std::string& path, const std::string& base_dir) {
  if (text::has_bom(text)) return parse_scene_json(std::string(text::strip_bom(text)), path, base_dir);
  json root;
  try {
    root = json::parse(text);
  } catch (const json::exception& e) {
    // nlohmann's message names the line and column (also for numbers out of range, e.g. 1e999)
    fail("{}: invalid JSON: {}", path, e.what());
  }
  Scene scene;
  scene.source = path;
  const Ctx ctx{path, ""};
  check_keys({path, "top level"}, root,
             {"meshes", "cameras", "camera_paths", "lights", "meters_per_unit", "ao_distance", "ambient", "comment"});
  if (root.contains("meters_per_unit")) scene.meters_per_unit = positive(ctx.at("meters_per_unit"), root["meters_per_unit"]);
  if (root.contains("ao_distance")) {
    const json& d = root["ao_distance"];
    if (d.is_string() && d.get<std::string>() == "inf")
      scene.ao_distance = INFINITY;
    else
      scene.ao_distance = positive(ctx.at("ao_distance"), d);
  }
  if (root.contains("ambient")) scene.ambient = vec3(ctx.at("ambient"), root["ambient"]);
  if (!root.contains("meshes") || !root["meshes"].is_array() || root["meshes"].empty())
    ctx.at("meshes").error("expected a non-empty array of meshes");
  for (size_t i = 0; i < root["meshes"].size(); ++i) mesh(scene, ctx.at("meshes").at(i), root["meshes"][i], base_dir);

  if (root.contains("cameras")) {
    const Ctx cc = ctx.at("cameras");
    if (!root["cameras"].is_array()) cc.error("expected an array");
    for (size_t i = 0; i < root["cameras"].size(); ++i) {
      const json& c = root["cameras"][i];
      const Ctx ci = cc.at(i);
      check_keys(ci, c, {"name", "eye", "look", "up", "fov"});
      Camera cam;
      cam.name = c.contains("name") ? string(ci.at("name"), c["name"]) : fmt::format("camera{}", i + 1);
      cam.eye = vec3(ci.at("eye"), c.value("eye", json()));
      cam.look = vec3(ci.at("look"), c.value("look", json()));
      if (c.contains("up")) cam.up = vec3(ci.at("up"), c["up"]);
      if (c.contains("fov")) cam.fov_deg = positive(ci.at("fov"), c["fov"]);
      if (cam.fov_deg >= 180) ci.at("fov").error("must be below 180 degrees");
      if (glm::length(cam.look - cam.eye) == 0) ci.error("eye and look must differ");
      if (glm::length(glm::cross(cam.look - cam.eye, cam.up)) == 0) ci.error("up must not be parallel to the view");
      scene.cameras.push_back(cam);
    }
  }
  if (root.contains("camera_paths")) {
    // [{"name": "walk", "cameras": ["door", "table"], "steps": 20}]: through named cameras
    const Ctx pc = ctx.at("camera_paths");
    if (!root["camera_paths"].is_array()) pc.error("expected an array");
    for (size_t i = 0; i < root["camera_paths"].size(); ++i) {
      const json& p = root["camera_paths"][i];
      const Ctx pi = pc.at(i);
      check_keys(pi, p, {"name", "cameras", "steps"});
      CameraPath path;
      path.name = p.contains("name") ? string(pi.at("name"), p["name"]) : fmt::format("path{}", i + 1);
      if (!p.contains("cameras") || !p["cameras"].is_array() || p["cameras"].size() < 2)
        pi.at("cameras").error("expected an array of at least two camera names");
      for (size_t k = 0; k < p["cameras"].size(); ++k) {
        const std::string name = string(pi.at("cameras").at(k), p["cameras"][k]);
        const auto it = std::find_if(scene.cameras.begin(), scene.cameras.end(), [&](const Camera& c) { return c.name == name; });
        if (it == scene.cameras.end()) pi.at("cameras").at(k).error(fmt::format("no camera named '{}' in \"cameras\"", name));
        path.keys.push_back(*it);
      }
      const float steps = p.contains("steps") ? positive(pi.at("steps"), p["steps"]) : 2.0f;
      if (steps < 2 || steps != std::floor(steps) || steps > 1e6) pi.at("steps").error("expected a whole number of steps from 2");
      path.steps = static_cast<int>(steps);
      scene.camera_paths.push_back(path);
    }
  }
  if (root.contains("lights")) {
    const Ctx lc = ctx.at("lights");
    if (!root["lights"].is_array()) lc.error("expected an array");
    for (size_t i = 0; i < root["lights"].size(); ++i) {
      const json& l = root["lights"][i];
      const Ctx li = lc.at(i);
      check_keys(li, l, {"type", "position", "direction", "diffuse", "specular"});
      Light light;
      const std::string type = l.contains("type") ? string(li.at("type"), l["type"]) : "point";
      if (type == "point") {
        light.type = Light::Type::point;
        light.vector = vec3(li.at("position"), l.value("position", json()));
      } else if (type == "directional") {
        light.type = Light::Type::directional;
        light.vector = vec3(li.at("direction"), l.value("direction", json()));
        if (glm::length(light.vector) == 0) li.at("direction").error("must not be zero");
        light.vector = glm::normalize(light.vector);
      } else {
        li.at("type").error(fmt::format("unknown light type '{}' (known: point, directional)", type));
      }
      if (l.contains("diffuse")) light.diffuse = vec3(li.at("diffuse"), l["diffuse"]);
      if (l.contains("specular")) light.specular = vec3(li.at("specular"), l["specular"]);
      scene.lights.push_back(light);
    }
  }
  return scene;
}

}  // namespace foveal
