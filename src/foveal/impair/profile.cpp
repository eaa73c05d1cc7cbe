// foveal/impair/profile.cpp — `--eye` presets and JSON eye profiles.
#include "foveal/impair/profile.h"

#include "foveal/util/text.h"
#include "foveal/util/error.h"

#include <nlohmann/json.hpp>

#include <filesystem>
#include <map>
#include <set>
#include <sstream>

namespace foveal {

namespace {

bool is_optics(const std::string& name) {
  return name == "healthy" || name == "glaucoma" || name == "myopia" || name == "hyperopia" || name == "presbyopia" ||
         name == "astigmatism";
}

double number_in(const std::string& part, const std::string& value, double lo, double hi, const char* what) {
  const auto v = text::to_number(value);
  if (!v) fail("eye: '{}': {} '{}' is not a number", part, what, value);
  if (!(*v >= lo && *v <= hi)) fail("eye: '{}': {} must be in [{}, {}], got {}", part, what, lo, hi, *v);
  return *v;
}

bool is_grid(const std::string& s) { return s == "24-2" || s == "30-2" || s == "10-2"; }

// The field part's text after "field:": a file, GRID:FILE, or a generated defect
void add_field(VisualField& field, const std::string& spec, const std::string& base_dir, const double& age, std::optional<Eye> eye,
               std::vector<std::function<void()>>& reads) {
  const auto colon = spec.find(':');
  const std::string head = spec.substr(0, colon);
  auto path_of = [&](const std::string& p) {
    return std::filesystem::path(p).is_absolute() ? p : (std::filesystem::path(base_dir) / p).lexically_normal().string();
  };
  std::error_code ec;
  if (!spec.empty() && std::filesystem::is_directory(path_of(spec), ec)) fail("field: {}: is a folder, not a file", path_of(spec));
  if (is_grid(head)) {
    if (colon == std::string::npos) fail("field:{}: name the file of values (field:{}:FILE.csv)", spec, head);
    const std::string path = path_of(spec.substr(colon + 1));
    reads.push_back([&field, path, head, eye, &age] {
      for (auto& f : read_field_file(path, head, eye.value_or(Eye::od), age)) field.measured.push_back(std::move(f));
    });
  } else if (spec.ends_with(".csv") || spec.ends_with(".CSV")) {
    const std::string path = path_of(spec);
    reads.push_back([&field, path, eye, &age] {
      for (auto& f : read_field_file(path, {}, eye.value_or(Eye::od), age)) field.measured.push_back(std::move(f));
    });
  } else {
    generated_defect(spec, eye.value_or(Eye::od));  // checks the spec now
    field.generated.push_back({spec, eye});
  }
}

}  // namespace

EyeSpec parse_eye_spec(const std::string& text) {
  if (text.ends_with(".json")) return read_eye_profile(text);
  EyeSpec spec;
  spec.source = text;
  if (text.empty())
    fail("eye: empty (expected presets such as healthy, glaucoma:0.5, cataract:0.5, cvd:deutan:0.6, field:arcuate:20, or a profile .json)");
  std::string joined = text;  // a sign right after ':' ("hyperopia:+2") belongs to the number
  for (size_t at = joined.find(":+"); at != std::string::npos; at = joined.find(":+")) joined.erase(at + 1, 1);
  std::string optics;
  bool age_from_presbyopia = false;
  double age = -1;
  std::vector<std::function<void()>> reads;  // files are read once the age is known
  Impairments& im = spec.impair;
  if (!joined.empty() && (joined.front() == '+' || joined.back() == '+' || joined.find("++") != std::string::npos))
    fail("eye: '{}': a '+' needs a preset on each side", text);
  std::map<std::string, std::string> given;  // each setting once: "cataract:0.3+cataract:0.9" is a conflict, not the last one winning
  std::stringstream parts(joined);
  for (std::string part; std::getline(parts, part, '+');) {
    const auto colon = part.find(':');
    const std::string name = part.substr(0, colon), value = colon == std::string::npos ? "" : part.substr(colon + 1);
    const bool colour = name == "cvd" || name == "achromatopsia" || name == "protanopia" || name == "deuteranopia" || name == "tritanopia";
    const std::string setting = colour ? "colour vision" : name == "amd" || name == "metamorphopsia" ? "metamorphopsia" : name;
    if (!is_optics(name) && name != "field") {
      if (const auto it = given.find(setting); it != given.end())
        fail("eye: '{}' and '{}' both set {}; give it once", it->second, part, setting);
      given[setting] = part;
    }
    if (is_optics(name)) {
      optics += (optics.empty() ? "" : "+") + part;
      if (name == "presbyopia") age_from_presbyopia = true;
    } else if (name == "age") {
      age = number_in(part, value, 0, 120, "age");
    } else if (name == "cataract") {
      im.media.cataract = value.empty() ? 0.5 : number_in(part, value, 0, 1, "severity");
      im.media.glare = im.media.yellowing = true;
    } else if (name == "glare" && value.empty()) {
      im.media.glare = true;
    } else if (name == "cvd" || name == "achromatopsia" || name == "protanopia" || name == "deuteranopia" || name == "tritanopia") {
      const std::string rest = name == "cvd" ? value : part;
      const auto c = rest.find(':');
      im.cvd.type = parse_cvd_type(rest.substr(0, c));
      const bool anomalous = im.cvd.type == CvdType::protan || im.cvd.type == CvdType::deutan || im.cvd.type == CvdType::tritan;
      if (c != std::string::npos && !anomalous) fail("eye: '{}': {} takes no severity", part, to_string(im.cvd.type));
      im.cvd.severity = c == std::string::npos ? 1.0 : number_in(part, rest.substr(c + 1), 0, 1, "severity");
    } else if (name == "field") {
      if (value.empty()) fail("eye: 'field' needs a file or a defect (field:FILE.csv, field:24-2:FILE.csv, field:arcuate:20)");
      add_field(im.field, value, ".", age, std::nullopt, reads);
    } else if (name == "field-view") {
      if (value != "OD" && value != "OS" && value != "both") fail("eye: '{}': expected field-view:OD, OS or both", part);
      im.field.view = value;
    } else if (name == "field-mode") {
      im.field_mode = parse_field_mode(value);
    } else if (name == "amd") {
      std::stringstream v(value);
      std::string r, a;
      std::getline(v, r, ':');
      std::getline(v, a, ':');
      const double radius = r.empty() ? 5.0 : number_in(part, r, 0.5, 30, "scotoma radius");
      im.field.generated.push_back({fmt::format("central:{}", radius), std::nullopt});
      im.metamorphopsia.amplitude_deg = a.empty() ? 0.3 : number_in(part, a, 0, 5, "distortion");
      im.metamorphopsia.radius_deg = radius + 3;
    } else if (name == "metamorphopsia") {
      std::stringstream v(value);
      std::string a, r;
      std::getline(v, a, ':');
      std::getline(v, r, ':');
      if (a.empty()) fail("eye: '{}': needs a distortion in degrees (metamorphopsia:0.5)", part);
      im.metamorphopsia.amplitude_deg = number_in(part, a, 0, 5, "distortion");
      if (!r.empty()) im.metamorphopsia.radius_deg = number_in(part, r, 1, 30, "radius");
    } else {
      fail(
          "eye: unknown preset '{}' in '{}' (expected healthy, glaucoma[:S], myopia:-D, hyperopia:D, presbyopia:AGE, "
          "astigmatism:CYL[@AXIS], age:Y, cataract[:S], glare, cvd:TYPE[:S], achromatopsia, field:…, field-view:…, "
          "field-mode:…, amd[:R[:A]], metamorphopsia:A[:R], or a profile .json)",
          name, text);
    }
  }
  spec.eye = optics.empty() ? EyeParams{} : parse_eye_preset(optics);
  spec.eye.preset = text;
  if (age >= 0 && !age_from_presbyopia) spec.eye.age_years = age;
  age = spec.eye.age_years;
  im.media.age_years = age;
  for (auto& read : reads) read();
  validate(spec.eye);
  return spec;
}

namespace {

using nlohmann::json;

// Strict reading of one JSON object: every key must be known; errors carry the JSON path.
class Reader {
 public:
  Reader(const std::string& file, const json& j, const std::string& path) : file_(file), j_(j), path_(path) {
    if (!j.is_object()) error("must be an object");
  }
  void keys(std::initializer_list<const char*> known) const {
    for (auto it = j_.begin(); it != j_.end(); ++it) {
      bool ok = false;
      for (const char* k : known) ok = ok || it.key() == k;
      if (!ok) {
        std::string list;
        for (const char* k : known) list += (list.empty() ? "" : ", ") + std::string(k);
        fail("{}: {}/{}: unknown key (expected {})", file_, path_, it.key(), list);
      }
    }
  }
  bool has(const char* key) const { return j_.contains(key); }
  double number(const char* key, double lo, double hi, double fallback) const {
    if (!has(key)) return fallback;
    const json& v = j_.at(key);
    if (!v.is_number()) fail("{}: {}/{}: must be a number", file_, path_, key);
    const double d = v.get<double>();
    if (!(d >= lo && d <= hi)) fail("{}: {}/{}: must be in [{}, {}], got {}", file_, path_, key, lo, hi, d);
    return d;
  }
  std::string string(const char* key, const std::string& fallback) const {
    if (!has(key)) return fallback;
    if (!j_.at(key).is_string()) fail("{}: {}/{}: must be a string", file_, path_, key);
    return j_.at(key).get<std::string>();
  }
  Reader child(const char* key) const { return Reader(file_, j_.at(key), path_ + "/" + key); }
  const json& value(const char* key) const { return j_.at(key); }
  [[noreturn]] void error(const std::string& why) const { fail("{}: {}: {}", file_, path_.empty() ? "/" : path_, why); }
  std::string where(const char* key) const { return fmt::format("{}: {}/{}", file_, path_, key); }

 private:
  std::string file_;
  const json& j_;
  std::string path_;
};

}  // namespace

EyeSpec parse_eye_profile(const std::string& text, const std::string& name, const std::string& base_dir) {
  json j;
  try {
    // A key given twice in one object is refused (nlohmann::json would keep the last silently)
    std::vector<std::set<std::string>> keys;
    std::string duplicate;
    const json::parser_callback_t check = [&](int, json::parse_event_t event, json& parsed) {
      if (event == json::parse_event_t::object_start) keys.emplace_back();
      if (event == json::parse_event_t::object_end && !keys.empty()) keys.pop_back();
      if (event == json::parse_event_t::key && !keys.empty() && !keys.back().insert(parsed.get<std::string>()).second && duplicate.empty())
        duplicate = parsed.get<std::string>();
      return true;
    };
    j = json::parse(text::strip_bom(text), check);
    if (!duplicate.empty()) fail("{}: the key \"{}\" is given twice in one object", name, duplicate);
  } catch (const json::parse_error& e) {
    fail("{}: not valid JSON (byte {}): {}", name, e.byte, e.what());
  } catch (const json::exception& e) {  // e.g. a number beyond double's range
    fail("{}: not valid JSON: {}", name, e.what());
  }
  const Reader root(name, j, "");
  root.keys({"name", "age", "pigmentation", "view", "optics_eye", "field_mode", "colour_vision", "eyes"});
  EyeSpec spec;
  spec.source = name;
  Impairments& im = spec.impair;
  if (root.has("name")) root.string("name", "");
  const double age = root.number("age", 0, 120, 50);
  im.media.age_years = age;
  im.media.pigmentation = root.number("pigmentation", 0, 1, 0.5);
  if (root.has("field_mode")) {
    try {
      im.field_mode = parse_field_mode(root.string("field_mode", ""));
    } catch (const Error& e) {
      fail("{}: {}", root.where("field_mode"), e.what());
    }
  }
  if (root.has("colour_vision")) {
    const Reader cv = root.child("colour_vision");
    cv.keys({"type", "severity"});
    try {
      im.cvd.type = parse_cvd_type(cv.string("type", "none"));
    } catch (const Error& e) {
      fail("{}: {}", cv.where("type"), e.what());
    }
    im.cvd.severity = cv.number("severity", 0, 1, 1.0);
  }
  if (!root.has("eyes")) root.error("needs \"eyes\" with \"OD\" and/or \"OS\"");
  const Reader eyes = root.child("eyes");
  eyes.keys({"OD", "OS"});
  std::map<Eye, EyeParams> optics;
  std::map<Eye, double> cataract;
  std::map<Eye, Metamorphopsia> distortion;
  std::vector<std::function<void()>> reads;
  for (Eye side : {Eye::od, Eye::os}) {
    if (!eyes.has(to_string(side))) continue;
    const Reader e = eyes.child(to_string(side));
    e.keys({"refraction", "cylinder", "axis", "pupil_mm", "glaucoma", "cataract", "field", "metamorphopsia"});
    EyeParams& o = optics[side];
    o.age_years = age;
    o.refraction_d = e.number("refraction", -30, 30, 0);
    o.cylinder_d = e.number("cylinder", 0, 10, 0);
    o.cylinder_axis_deg = e.number("axis", 0, 180, 0);
    o.pupil_diameter_mm = e.number("pupil_mm", 1, 10, 3.5);
    o.glaucoma = e.number("glaucoma", 0, 1, 0);
    cataract[side] = e.number("cataract", 0, 1, 0);
    if (e.has("metamorphopsia")) {
      const Reader m = e.child("metamorphopsia");
      m.keys({"amplitude_deg", "radius_deg"});
      distortion[side].amplitude_deg = m.number("amplitude_deg", 0, 5, 0.3);
      distortion[side].radius_deg = m.number("radius_deg", 1, 30, 6);
    }
    if (e.has("field")) {
      const Reader f = e.child("field");
      f.keys({"file", "grid", "defect"});
      if (f.has("file") == f.has("defect")) f.error("needs either \"file\" or \"defect\"");
      try {
        if (f.has("defect")) {
          add_field(im.field, f.string("defect", ""), base_dir, age, side, reads);
        } else {
          const std::string grid = f.string("grid", "");
          if (!grid.empty() && !is_grid(grid)) fail("unknown grid '{}' (expected 24-2, 30-2 or 10-2)", grid);
          add_field(im.field, grid.empty() ? f.string("file", "") : grid + ":" + f.string("file", ""), base_dir, age, side, reads);
        }
        for (auto& read : reads) read();  // the age is known: read the file here, so that its errors carry the path
        reads.clear();
      } catch (const Error& err) {
        fail("{}: {}", e.where("field"), err.what());
      }
    }
  }
  if (optics.empty()) eyes.error("needs \"OD\" and/or \"OS\"");
  const std::string view = root.string("view", optics.size() == 2 ? "both" : optics.count(Eye::od) ? "OD" : "OS");
  if (view != "OD" && view != "OS" && view != "both") fail("{}: must be OD, OS or both, got '{}'", root.where("view"), view);
  if (view != "both" && !optics.count(view == "OD" ? Eye::od : Eye::os))
    fail("{}: {} is not among the profile's eyes", root.where("view"), view);
  im.field.view = view;
  const std::string optics_name = root.string("optics_eye", view == "both" ? (optics.count(Eye::od) ? "OD" : "OS") : view);
  const auto optics_eye = parse_eye_side(optics_name);
  if (!optics_eye || !optics.count(*optics_eye)) fail("{}: '{}' is not among the profile's eyes", root.where("optics_eye"), optics_name);
  spec.eye = optics[*optics_eye];
  spec.eye.preset = name;
  im.media.cataract = cataract[*optics_eye];
  im.media.glare = im.media.yellowing = im.media.cataract > 0;
  if (distortion.count(*optics_eye)) im.metamorphopsia = distortion[*optics_eye];
  validate(spec.eye);
  return spec;
}

EyeSpec read_eye_profile(const std::string& path) {
  const std::string text = text::read_file(path);
  return parse_eye_profile(
      text, path,
      std::filesystem::path(path).parent_path().string().empty() ? std::string(".") : std::filesystem::path(path).parent_path().string());
}

EyeSpec resolve_eye(const std::string& spec, const EyeOverrides& overrides) {
  EyeSpec eye;
  try {
    eye = parse_eye_spec(spec);
  } catch (const Error& e) {  // every error of the eye names it (a preset's own message may not)
    const std::string_view what = e.what();
    if (what.starts_with("eye:") || what.starts_with(spec)) throw;
    fail("eye: '{}': {}", spec, what);
  }
  if (overrides.pupil_diameter_mm) eye.eye.pupil_diameter_mm = *overrides.pupil_diameter_mm;
  if (overrides.image_distance_mm) eye.eye.image_distance_mm = *overrides.image_distance_mm;
  validate(eye.eye);
  return eye;
}

json optics_json(const EyeParams& e) {
  return {{"preset", e.preset},
          {"pupil_mm", e.pupil_diameter_mm},
          {"image_distance_mm", e.image_distance_mm},
          {"refraction_d", e.refraction_d},
          {"cylinder_d", e.cylinder_d},
          {"axis_deg", e.cylinder_axis_deg},
          {"age_years", e.age_years},
          {"glaucoma", e.glaucoma}};
}

}  // namespace foveal
