// foveal/gaze/tobii.cpp — Tobii exports: the Tobii SDK TSV layout and Tobii Pro Lab's data export.
//
// SDK layout (as written by the Tobii SDK / read by I2MC's importTobiiTX300): `Time` in µs,
// `LGazePos2dx/y`, `RGazePos2dx/y` normalised to the screen, validity codes 0…4 per eye where
// > 1 means missing (gaze columns then hold −1).
// Pro Lab layout: `Recording timestamp` (µs when the header says [μs], else ms), `Gaze point X/Y`
// in screen pixels, `Validity left/right` ("Valid"/"Invalid"), `Recording resolution
// width/height`, and Tobii's own I-VT output in `Eye movement type` (+ index, fixation point),
// which becomes the recording's tracker fixations. Rows of other sensors are skipped; cells may
// be empty; a decimal comma is accepted.
#include "foveal/gaze/recording.h"
#include "foveal/util/text.h"
#include "foveal/util/error.h"

#include <cmath>
#include <map>

namespace foveal {

namespace {

struct Columns {
  std::vector<std::string> names;
  // Index of the first column whose name starts with `prefix` (Pro Lab appends units: "Gaze point X [DACS px]").
  std::optional<size_t> find(std::string_view prefix) const {
    for (size_t i = 0; i < names.size(); ++i)
      if (std::string_view(names[i]).substr(0, prefix.size()) == prefix) return i;
    return std::nullopt;
  }
};

}  // namespace

Recording parse_tobii(const std::string& content, const std::string& name, const ReadOptions& o) {
  if (text::has_bom(content)) return parse_tobii(content.substr(3), name, o);
  text::Lines lines(content);
  std::string_view line;
  if (!lines.next(line)) fail("{}: empty file", name);
  Columns cols;
  for (std::string_view f : text::split(line, '\t')) cols.names.emplace_back(text::trim(f));
  auto require = [&](std::string_view col) {
    const auto i = cols.find(col);
    if (!i) fail("{}:1: missing column '{}'", name, col);
    return *i;
  };
  Recording r;
  r.has_tracker_fixations = false;
  const bool sdk = cols.find("LGazePos2dx").has_value();
  double previous = -INFINITY;
  auto where = [&] { return fmt::format("{}:{}", name, lines.number()); };
  auto fields_of = [&](std::string_view l) {
    auto f = text::split(l, '\t');
    if (f.size() != cols.names.size())
      fail("{}: {} fields, but the header has {} (truncated or malformed line)", where(), f.size(), cols.names.size());
    return f;
  };

  if (sdk) {
    r.tracker = "Tobii (SDK TSV)";
    r.eyes = o.eye == EyeSelection::average ? "binocular (average of valid eyes)" : o.eye == EyeSelection::left ? "left" : "right";
    r.screen_px = o.screen_px;
    const size_t c_t = require("Time"), c_lx = require("LGazePos2dx"), c_ly = require("LGazePos2dy"), c_lv = require("LValidity"),
                 c_rx = require("RGazePos2dx"), c_ry = require("RGazePos2dy"), c_rv = require("RValidity");
    while (lines.next(line)) {
      if (text::trim(line).empty()) continue;
      const auto f = fields_of(line);
      auto num = [&](size_t c) {
        const auto v = text::to_number(f[c]);
        if (!v) fail("{}: column '{}': '{}' is not a number", where(), cols.names[c], text::trim(f[c]));
        return *v;
      };
      GazeSample s;
      s.t_s = num(c_t) * 1e-6;  // µs
      if (s.t_s < previous) fail("{}: time {} µs is before the previous sample's (time must not go backwards)", where(), num(c_t));
      previous = s.t_s;
      glm::dvec2 eye[2];
      bool ok[2];
      const size_t cx[2] = {c_lx, c_rx}, cy[2] = {c_ly, c_ry}, cv[2] = {c_lv, c_rv};
      for (int e = 0; e < 2; ++e) {
        const double validity = num(cv[e]);
        eye[e] = {num(cx[e]), num(cy[e])};
        ok[e] = validity <= 1 && eye[e].x != -1.0;  // codes 2–4 (and the −1 filler) mean no data
      }
      const glm::dvec2 screen(r.screen_px);
      switch (o.eye) {
        case EyeSelection::left:
          s.px = ok[0] ? eye[0] * screen : glm::dvec2(NAN);
          break;
        case EyeSelection::right:
          s.px = ok[1] ? eye[1] * screen : glm::dvec2(NAN);
          break;
        case EyeSelection::average:
          s.px = ok[0] && ok[1] ? 0.5 * (eye[0] + eye[1]) * screen : ok[0] ? eye[0] * screen : ok[1] ? eye[1] * screen : glm::dvec2(NAN);
          break;
      }
      r.samples.push_back(s);
    }
    apply_validity(r, o.min_confidence);
    return r;
  }

  // Tobii Pro Lab
  r.tracker = "Tobii Pro Lab (TSV)";
  r.eyes = "as exported (Pro Lab's eye selection)";
  r.has_tracker_fixations = true;
  const size_t c_t = require("Recording timestamp"), c_x = require("Gaze point X"), c_y = require("Gaze point Y");
  const std::string& t_name = cols.names[c_t];
  const double t_scale = t_name.find("μs") != std::string::npos || t_name.find("us]") != std::string::npos ? 1e-6 : 1e-3;
  const auto c_vl = cols.find("Validity left"), c_vr = cols.find("Validity right"), c_sensor = cols.find("Sensor"),
             c_type = cols.find("Eye movement type"), c_index = cols.find("Eye movement type index"), c_fx = cols.find("Fixation point X"),
             c_fy = cols.find("Fixation point Y"), c_w = cols.find("Recording resolution width"),
             c_h = cols.find("Recording resolution height");
  if (!c_type) r.has_tracker_fixations = false;
  r.screen_px = o.screen_px;
  std::string open_fixation;  // index of the fixation being read
  while (lines.next(line)) {
    if (text::trim(line).empty()) continue;
    const auto f = fields_of(line);
    auto optional_number = [&](std::optional<size_t> c) -> double {
      if (!c) return NAN;
      const std::string_view v = text::trim(f[*c]);
      if (v.empty()) return NAN;
      const auto n = text::to_number(v, true);
      if (!n) fail("{}: column '{}': '{}' is not a number", where(), cols.names[*c], v);
      return *n;
    };
    if (c_sensor && !text::trim(f[*c_sensor]).empty() && text::trim(f[*c_sensor]) != "Eye Tracker") continue;
    GazeSample s;
    const double t = optional_number(c_t);
    if (std::isnan(t)) fail("{}: empty 'Recording timestamp'", where());
    s.t_s = t * t_scale;
    if (s.t_s < previous) fail("{}: time {} is before the previous sample's (time must not go backwards)", where(), t);
    previous = s.t_s;
    s.px = {optional_number(c_x), optional_number(c_y)};
    bool valid_eye = true;
    if (c_vl && c_vr) valid_eye = text::trim(f[*c_vl]) == "Valid" || text::trim(f[*c_vr]) == "Valid";
    if (!valid_eye) s.px = glm::dvec2(NAN);
    if (!r.screen_from_file && c_w && c_h) {
      const double w = optional_number(c_w), h = optional_number(c_h);
      if (w >= 1 && h >= 1 && w <= 65536 && h <= 65536) {
        r.screen_px = glm::ivec2(static_cast<int>(w), static_cast<int>(h));
        r.screen_from_file = true;
      }
    }
    if (c_type) {
      const std::string_view type = text::trim(f[*c_type]);
      std::string index = c_index ? std::string(text::trim(f[*c_index])) : std::string();
      if (index.empty()) index = "open";
      if (type == "Fixation") {
        if (open_fixation != index) {
          GazeEvent e;
          e.start_s = s.t_s;
          e.px = {optional_number(c_fx), optional_number(c_fy)};
          r.fixations.push_back(e);
          open_fixation = index;
        }
        r.fixations.back().end_s = s.t_s;
      } else {
        open_fixation.clear();
      }
    }
    r.samples.push_back(s);
  }
  if (o.screen_from_user) r.screen_px = o.screen_px;
  apply_validity(r, o.min_confidence);
  return r;
}

}  // namespace foveal
