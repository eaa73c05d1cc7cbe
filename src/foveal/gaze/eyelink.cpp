// foveal/gaze/eyelink.cpp — SR Research EyeLink ASC (the text that edf2asc writes).
//
// Samples are read only inside START…END blocks: outside them, EyeLink writes indented
// calibration tables whose lines also start with numbers. The SAMPLES line of each block says
// which eyes are recorded and which extra columns (VEL, RES, HTARGET, INPUT) follow; a "." is a
// missing value (the eye was lost, e.g. in a blink), read as an invalid sample.
#include "foveal/gaze/recording.h"
#include "foveal/util/text.h"
#include "foveal/util/error.h"

#include <algorithm>
#include <cmath>

namespace foveal {

namespace {

struct BlockLayout {
  bool left = false, right = false;
};

bool is_missing(std::string_view f) { return f == "."; }

// Intersection of two sorted interval lists (both eyes in the event at once).
std::vector<GazeEvent> intersect(const std::vector<GazeEvent>& a, const std::vector<GazeEvent>& b) {
  std::vector<GazeEvent> out;
  size_t j = 0;
  for (const GazeEvent& e : a) {
    while (j < b.size() && b[j].end_s < e.start_s) ++j;
    for (size_t k = j; k < b.size() && b[k].start_s <= e.end_s; ++k) {
      GazeEvent both;
      both.start_s = std::max(e.start_s, b[k].start_s);
      both.end_s = std::min(e.end_s, b[k].end_s);
      both.px = 0.5 * (e.px + b[k].px);
      if (both.end_s >= both.start_s) out.push_back(both);
    }
  }
  return out;
}

}  // namespace

Recording parse_eyelink_asc(const std::string& content, const std::string& name, const ReadOptions& o) {
  if (text::has_bom(content)) return parse_eyelink_asc(content.substr(3), name, o);
  Recording r;
  r.tracker = "SR Research EyeLink (ASC)";
  r.has_tracker_fixations = true;
  text::Lines lines(content);
  std::string_view line;
  bool in_block = false, saw_left = false, saw_right = false, display_coords = false;
  size_t block_line = 0;  // where the open block started
  glm::dvec2 origin{0};   // top-left of DISPLAY_COORDS
  BlockLayout layout;
  std::vector<GazeEvent> fix[2], blink[2];  // per eye: 0 left, 1 right
  double previous = -INFINITY;
  auto where = [&] { return fmt::format("{}:{}", name, lines.number()); };
  auto num = [&](std::string_view f, const char* what) {
    const auto v = text::to_number(f);
    if (!v) fail("{}: {} '{}' is not a number", where(), what, f);
    return *v;
  };

  while (lines.next(line)) {
    if (line.empty()) continue;
    const char c0 = line.front();
    if (c0 >= '0' && c0 <= '9') {
      if (!in_block) continue;  // calibration tables between blocks
      const auto f = text::split(line, ' ');
      const int eyes = (layout.left ? 1 : 0) + (layout.right ? 1 : 0);
      const size_t needed = 1 + 3 * static_cast<size_t>(eyes);
      if (f.size() < needed)
        fail("{}: sample has {} fields, expected at least {} (time{})", where(), f.size(), needed,
             eyes == 2 ? ", x, y, pupil for each eye" : ", x, y, pupil");
      GazeSample s;
      s.t_s = num(f[0], "sample time") / 1000.0;  // EyeLink time stamps are milliseconds
      if (s.t_s < previous)
        fail("{}: time {} ms is before the previous sample's {} ms (time must not go backwards)", where(), f[0], previous * 1000);
      previous = s.t_s;
      glm::dvec2 eye_px[2]{glm::dvec2(NAN), glm::dvec2(NAN)};
      float eye_pupil[2]{NAN, NAN};
      size_t col = 1;
      for (int e = 0; e < 2; ++e) {
        if (e == 0 ? !layout.left : !layout.right) continue;
        const std::string_view fx = f[col], fy = f[col + 1], fp = f[col + 2];
        col += 3;
        if (!is_missing(fp) && !text::to_number(fp)) fail("{}: pupil '{}' is not a number", where(), fp);
        if (!is_missing(fp) && *text::to_number(fp) > 0) eye_pupil[e] = static_cast<float>(*text::to_number(fp));
        if (is_missing(fx) || is_missing(fy)) continue;  // eye lost: an invalid sample, not a zero
        eye_px[e] = {num(fx, "gaze x"), num(fy, "gaze y")};
      }
      const bool ok[2] = {std::isfinite(eye_px[0].x), std::isfinite(eye_px[1].x)};
      switch (o.eye) {
        case EyeSelection::left:
          s.px = layout.left ? eye_px[0] : eye_px[1];
          break;
        case EyeSelection::right:
          s.px = layout.right ? eye_px[1] : eye_px[0];
          break;
        case EyeSelection::average:
          s.px = ok[0] && ok[1] ? 0.5 * (eye_px[0] + eye_px[1]) : ok[0] ? eye_px[0] : eye_px[1];
          break;
      }
      switch (o.eye) {  // the pupil of the eye the point came from (average: of both where both were seen)
        case EyeSelection::left:
          s.pupil = layout.left ? eye_pupil[0] : eye_pupil[1];
          break;
        case EyeSelection::right:
          s.pupil = layout.right ? eye_pupil[1] : eye_pupil[0];
          break;
        case EyeSelection::average:
          s.pupil = ok[0] && ok[1] ? 0.5f * (eye_pupil[0] + eye_pupil[1]) : ok[0] ? eye_pupil[0] : eye_pupil[1];
          break;
      }
      r.samples.push_back(s);
      continue;
    }
    const auto f = text::split(line, ' ');
    if (f.empty()) continue;  // only blanks
    const std::string_view key = f.front();
    if (key == "START") {
      if (in_block) fail("{}: START inside a recording block (missing END)", where());
      in_block = true;
      layout = {};
      for (std::string_view w : f) {
        layout.left |= w == "LEFT";
        layout.right |= w == "RIGHT";
      }
      if (!layout.left && !layout.right) fail("{}: START names no eye (LEFT/RIGHT)", where());
      saw_left |= layout.left;
      saw_right |= layout.right;
      r.block_starts.push_back(r.samples.size());
      block_line = lines.number();
    } else if (key == "END") {
      if (!in_block) fail("{}: END without START", where());
      in_block = false;
    } else if (key == "SAMPLES") {
      bool left = false, right = false;
      for (size_t i = 1; i < f.size(); ++i) {
        left |= f[i] == "LEFT";
        right |= f[i] == "RIGHT";
        if (f[i] == "RATE" && i + 1 < f.size()) r.nominal_rate_hz = num(f[i + 1], "RATE");
      }
      if (in_block && (left || right)) {
        layout.left = left;
        layout.right = right;
      }
    } else if (key == "EFIX" || key == "EBLINK") {
      // EFIX eye start end dur x y pupil; EBLINK eye start end dur
      const bool is_fix = key == "EFIX";
      const size_t needed = is_fix ? 7 : 5;
      if (f.size() < needed) fail("{}: {} has {} fields, expected {}", where(), key, f.size(), needed);
      const int eye = f[1] == "L" ? 0 : f[1] == "R" ? 1 : -1;
      if (eye < 0) fail("{}: {} eye '{}' is not L or R", where(), key, f[1]);
      GazeEvent e;
      e.start_s = num(f[2], "event start") / 1000.0;
      e.end_s = num(f[3], "event end") / 1000.0;
      if (e.end_s < e.start_s) fail("{}: {} ends before it starts", where(), key);
      if (is_fix) {
        const auto x = text::to_number(f[5]), y = text::to_number(f[6]);
        e.px = x && y ? glm::dvec2(*x, *y) : glm::dvec2(NAN);
      }
      (is_fix ? fix : blink)[eye].push_back(e);
    } else if (key == "MSG" && f.size() >= 7 && (f[2] == "DISPLAY_COORDS" || f[2] == "GAZE_COORDS")) {
      if (f[2] == "GAZE_COORDS" && display_coords) continue;
      const double left = num(f[3], "screen left"), top = num(f[4], "screen top"), right = num(f[5], "screen right"),
                   bottom = num(f[6], "screen bottom");
      const glm::dvec2 size{right - left + 1, bottom - top + 1};
      if (!(size.x >= 1 && size.y >= 1 && size.x <= 65536 && size.y <= 65536)) fail("{}: {} gives an empty or huge screen", where(), f[2]);
      r.screen_px = glm::ivec2(glm::round(size));
      origin = {left, top};
      r.screen_from_file = true;
      display_coords |= f[2] == "DISPLAY_COORDS";
    }
    // Everything else (MSG, INPUT, SFIX, SSACC, ESACC, PRESCALER, BUTTON, "**" header, …) is not needed.
  }
  if (in_block && !r.samples.empty())
    r.warnings.push_back(fmt::format("{}: recording block {} (from line {}) has no END: the file may be truncated; its {} samples are used",
                                     name, r.block_starts.size(), block_line, r.samples.size() - r.block_starts.back()));
  if (r.samples.empty()) fail("{}: no samples inside START…END blocks", name);

  // Eyes and the tracker's events for the eye(s) used
  if (origin != glm::dvec2(0)) {
    for (GazeSample& s : r.samples) s.px -= origin;
    for (auto* events : {&fix[0], &fix[1]})
      for (GazeEvent& e : *events) e.px -= origin;
  }
  const bool binocular = saw_left && saw_right;
  if (binocular && o.eye == EyeSelection::average) {
    r.eyes = "binocular (average of valid eyes)";
    r.fixations = intersect(fix[0], fix[1]);  // both eyes fixating
    r.blinks = intersect(blink[0], blink[1]);
  } else {
    const int e = binocular ? (o.eye == EyeSelection::right ? 1 : 0) : (saw_left ? 0 : 1);
    r.eyes = e == 0 ? "left" : "right";
    r.fixations = fix[e];
    r.blinks = blink[e];
  }
  auto by_start = [](const GazeEvent& a, const GazeEvent& b) { return a.start_s < b.start_s; };
  std::sort(r.fixations.begin(), r.fixations.end(), by_start);
  std::sort(r.blinks.begin(), r.blinks.end(), by_start);
  if (o.screen_from_user || !r.screen_from_file) {
    if (r.screen_from_file && o.screen_from_user) r.notes.push_back("screen size from --screen, not the file");
    r.screen_px = o.screen_px;
    r.screen_from_file = false;
  }
  apply_validity(r, o.min_confidence);
  return r;
}

}  // namespace foveal
