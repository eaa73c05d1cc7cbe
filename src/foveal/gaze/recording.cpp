// foveal/gaze/recording.cpp — format names, detection, statistics, Pupil and plain-CSV readers.
#include "foveal/gaze/recording.h"

#include "foveal/gaze/bids.h"

#include "foveal/util/text.h"
#include "foveal/util/error.h"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <map>

namespace foveal {

const char* to_string(GazeFormat format) {
  switch (format) {
    case GazeFormat::automatic:
      return "auto";
    case GazeFormat::asc:
      return "asc";
    case GazeFormat::pupil:
      return "pupil";
    case GazeFormat::tobii:
      return "tobii";
    case GazeFormat::csv:
      return "csv";
    case GazeFormat::bids:
      return "bids";
  }
  return "?";
}

GazeFormat parse_gaze_format(const std::string& name) {
  for (GazeFormat f : {GazeFormat::automatic, GazeFormat::asc, GazeFormat::pupil, GazeFormat::tobii, GazeFormat::csv, GazeFormat::bids})
    if (name == to_string(f)) return f;
  fail("format: unknown recording format '{}' (expected auto, asc, pupil, tobii, csv or bids)", name);
}

EyeSelection parse_eye_selection(const std::string& name) {
  if (name == "average") return EyeSelection::average;
  if (name == "left") return EyeSelection::left;
  if (name == "right") return EyeSelection::right;
  fail("gaze_eye: unknown eye '{}' (expected average, left or right)", name);
}

size_t Recording::valid_count() const {
  return static_cast<size_t>(std::count_if(samples.begin(), samples.end(), [](const GazeSample& s) { return s.valid; }));
}

double Recording::duration_s() const { return samples.size() < 2 ? 0.0 : samples.back().t_s - samples.front().t_s; }

namespace {

// Calls f(first, last) for each block's index range [first, last).
template <class F>
void for_each_block(const Recording& r, F&& f) {
  std::vector<size_t> starts = r.block_starts;
  if (starts.empty() || starts.front() != 0) starts.insert(starts.begin(), 0);
  for (size_t b = 0; b < starts.size(); ++b) {
    const size_t first = starts[b], last = b + 1 < starts.size() ? starts[b + 1] : r.samples.size();
    if (last > first) f(first, last);
  }
}

}  // namespace

double Recording::recorded_s() const {
  double total = 0;
  for_each_block(*this, [&](size_t first, size_t last) { total += samples[last - 1].t_s - samples[first].t_s; });
  return total;
}

// Samples per second within blocks, leaving out gaps in time (intervals over ten times the median:
// a recording with one hour-long gap read as 0.1 Hz) — a rate for irregular trackers too (Pupil
// merges its eyes' streams).
double Recording::rate_hz() const {
  std::vector<double> intervals;
  for_each_block(*this, [&](size_t first, size_t last) {
    for (size_t i = first + 1; i < last; ++i)
      if (samples[i].t_s > samples[i - 1].t_s) intervals.push_back(samples[i].t_s - samples[i - 1].t_s);
  });
  if (intervals.empty()) return 0.0;
  std::vector<double> sorted = intervals;
  auto mid = sorted.begin() + sorted.size() / 2;
  std::nth_element(sorted.begin(), mid, sorted.end());
  const double gap = 10 * *mid;
  double span = 0;
  size_t count = 0;
  for (double d : intervals)
    if (d <= gap) {
      span += d;
      ++count;
    }
  return span > 0 ? static_cast<double>(count) / span : 0.0;
}

bool plausible_point(glm::dvec2 px, glm::ivec2 screen) {
  return std::isfinite(px.x) && std::isfinite(px.y) && px.x >= -screen.x && px.x <= 2.0 * screen.x && px.y >= -screen.y &&
         px.y <= 2.0 * screen.y;
}

void apply_validity(Recording& r, float min_confidence) {
  size_t blink = 0, implausible = 0;
  for (GazeSample& s : r.samples) {
    while (blink < r.blinks.size() && r.blinks[blink].end_s < s.t_s) ++blink;
    const bool in_blink = blink < r.blinks.size() && r.blinks[blink].start_s <= s.t_s;
    const bool finite = std::isfinite(s.px.x) && std::isfinite(s.px.y);
    const bool plausible = plausible_point(s.px, r.screen_px);
    if (finite && !plausible) {
      ++implausible;
      s.px = glm::dvec2(NAN);  // never a point to render or average with
    }
    s.valid = plausible && s.confidence >= min_confidence && !in_blink;
  }
  if (implausible > 0)
    r.notes.push_back(fmt::format("{} samples more than one screen ({}x{}) beyond its edges were marked invalid", implausible,
                                  r.screen_px.x, r.screen_px.y));
}

GazeFormat detect_gaze_format(const std::string& text, const std::string& name) {
  if (text::has_bom(text)) return detect_gaze_format(text.substr(3), name);
  const std::string_view head = std::string_view(text).substr(0, std::min<size_t>(text.size(), 1 << 16));
  const std::string_view first = head.substr(0, head.find('\n'));
  // A binary file (an image, an EDF not yet converted): NUL bytes, which no text recording has
  if (const size_t nul = head.substr(0, 4096).find('\0'); nul != std::string_view::npos)
    fail(
        "{}: binary data (a NUL byte at offset {}), not a gaze recording: give an EyeLink .asc (edf2asc converts an .edf), "
        "a Pupil Player gaze_positions.csv, a Tobii TSV or a t,x,y CSV",
        name, nul);
  auto has = [](std::string_view s, std::string_view what) { return s.find(what) != std::string_view::npos; };
  if (has(first, "gaze_timestamp") && has(first, "norm_pos_x")) return GazeFormat::pupil;
  if (has(first, "start_timestamp") && has(first, "dispersion"))
    fail("{}: this is Pupil's fixations.csv; give the gaze_positions.csv beside it (its fixations.csv and blinks.csv are read too)", name);
  if (has(first, "start_timestamp") && has(first, "filter_response"))
    fail("{}: this is Pupil's blinks.csv; give the gaze_positions.csv beside it", name);
  if (has(first, "LGazePos2dx") || has(first, "Recording timestamp") || has(first, "Gaze point X")) return GazeFormat::tobii;
  if (head.rfind("**", 0) == 0 || has(head, "\nMSG\t") || has(head, "\nSTART\t") || head.rfind("MSG\t", 0) == 0) return GazeFormat::asc;
  const auto ext = std::filesystem::path(name).extension().string();
  if (ext == ".asc" || ext == ".ASC") return GazeFormat::asc;
  return GazeFormat::csv;
}

// Samples that repeat the time of the sample before are one sample given twice: the first valid
// one is kept and the drop is a warning (they made the summary's rate 1005 Hz where the detector
// saw 500 Hz, and events shorter than their minimum: issue 36's finding 11).
void drop_repeated_times(Recording& r) {
  std::vector<GazeSample> kept;
  std::vector<size_t> index(r.samples.size());  // each sample's place among the kept (block starts move with it)
  kept.reserve(r.samples.size());
  size_t dropped = 0;
  for (size_t i = 0; i < r.samples.size(); ++i) {
    const GazeSample& s = r.samples[i];
    if (!kept.empty() && s.t_s == kept.back().t_s) {
      if (s.valid && !kept.back().valid) kept.back() = s;
      ++dropped;
      index[i] = kept.size() - 1;
      continue;
    }
    index[i] = kept.size();
    kept.push_back(s);
  }
  if (dropped == 0) return;
  r.samples = std::move(kept);
  for (size_t& b : r.block_starts)
    if (b < index.size()) b = index[b];
  r.block_starts.erase(std::unique(r.block_starts.begin(), r.block_starts.end()), r.block_starts.end());
  r.warnings.push_back(fmt::format("{} samples repeat the time of the sample before: dropped (one sample per time)", dropped));
}

Recording parse_recording(const std::string& text, const std::string& name, const ReadOptions& options) {
  if (text::has_bom(text)) return parse_recording(text.substr(3), name, options);
  if (text.find_first_not_of(" \t\r\n") == std::string::npos) fail("{}: empty recording", name);
  const GazeFormat format = options.format == GazeFormat::automatic ? detect_gaze_format(text, name) : options.format;
  Recording r;
  switch (format) {
    case GazeFormat::asc:
      r = parse_eyelink_asc(text, name, options);
      break;
    case GazeFormat::pupil:
      r = parse_pupil_gaze(text, name, options);
      break;
    case GazeFormat::tobii:
      r = parse_tobii(text, name, options);
      break;
    case GazeFormat::bids:
      fail("{}: a BIDS recording is read from its file, with its sidecar beside it (…_physio.tsv.gz and …_physio.json)", name);
    default:
      r = parse_gaze_csv(text, name, options);
      break;
  }
  r.source = name;
  r.format = format;
  if (r.samples.empty()) fail("{}: no gaze samples", name);
  drop_repeated_times(r);
  return r;
}

Recording read_recording(const std::string& path, const ReadOptions& options) {
  if (std::filesystem::is_directory(path)) fail("{}: is a folder; give the recording file", path);
  if (options.format == GazeFormat::bids || (options.format == GazeFormat::automatic && is_bids_physio(path)))
    return read_bids_physio(path, options);
  const std::string text = text::read_file(path);
  const ReadOptions& o = options;
  Recording r = parse_recording(text, path, o);
  if (r.format != GazeFormat::pupil) return r;
  // Pupil exports its fixations and blinks beside gaze_positions.csv
  namespace fs = std::filesystem;
  const fs::path dir = fs::path(path).parent_path();
  auto side = [&](const std::string& given, const char* default_name) -> std::string {
    if (!given.empty()) return given;
    if (!o.find_side_files) return {};
    const fs::path p = dir / default_name;
    return fs::exists(p) ? p.string() : std::string();
  };
  if (const std::string f = side(o.fixations_file, "fixations.csv"); !f.empty()) {
    r.fixations = parse_pupil_fixations(text::read_file(f), f, r.screen_px);
    r.has_tracker_fixations = true;
    r.notes.push_back(fmt::format("tracker fixations from {} ({})", f, r.fixations.size()));
  }
  if (const std::string f = side(o.blinks_file, "blinks.csv"); !f.empty()) {
    r.blinks = parse_pupil_blinks(text::read_file(f), f);
    r.notes.push_back(fmt::format("blinks from {} ({})", f, r.blinks.size()));
    apply_validity(r, o.min_confidence);
  }
  return r;
}

// ---------------------------------------------------------------------------------------------
// Comma-separated tables with a header (Pupil exports)

namespace {

struct Table {
  std::string name;
  std::vector<std::string> header;
  std::map<std::string, size_t, std::less<>> column;

  // Column index of a required column; throws naming the file.
  size_t require(std::string_view col) const {
    const auto it = column.find(col);
    if (it == column.end()) fail("{}:1: missing column '{}'", name, col);
    return it->second;
  }
  std::optional<size_t> find(std::string_view col) const {
    const auto it = column.find(col);
    return it == column.end() ? std::nullopt : std::optional<size_t>(it->second);
  }
};

Table read_header(text::Lines& lines, const std::string& name, char separator) {
  std::string_view line;
  if (!lines.next(line)) fail("{}: empty file", name);
  Table t;
  t.name = name;
  for (std::string_view f : text::split(line, separator)) {
    std::string col(text::trim(f));
    if (!col.empty() && col.front() == '"' && col.back() == '"' && col.size() >= 2) col = col.substr(1, col.size() - 2);
    t.column.emplace(col, t.header.size());
    t.header.push_back(col);
  }
  return t;
}

std::vector<std::string_view> row_fields(std::string_view line, const Table& t, int number, char separator) {
  auto fields = text::split(line, separator);
  if (fields.size() != t.header.size())
    fail("{}:{}: {} fields, but the header has {} (truncated or malformed line)", t.name, number, fields.size(), t.header.size());
  return fields;
}

// A number, or NaN for an empty cell / "nan" where `allow_missing`; anything else is an error.
double number(std::string_view field, const Table& t, size_t col, int line, bool allow_missing) {
  if (const auto v = text::to_number(field)) return *v;
  const std::string_view f = text::trim(field);
  if (allow_missing && (f.empty() || f == "nan" || f == "NaN" || f == "NAN")) return NAN;
  fail("{}:{}: column '{}': '{}' is not a number", t.name, line, t.header[col], f);
}

void check_time_order(double t, double previous, const std::string& name, int line) {
  if (t < previous) fail("{}:{}: time {} is before the previous sample's {} (time must not go backwards)", name, line, t, previous);
}

}  // namespace

Recording parse_pupil_gaze(const std::string& content, const std::string& name, const ReadOptions& o) {
  if (text::has_bom(content)) return parse_pupil_gaze(content.substr(3), name, o);
  text::Lines lines(content);
  const Table t = read_header(lines, name, ',');
  const size_t c_time = t.require("gaze_timestamp"), c_conf = t.require("confidence"), c_x = t.require("norm_pos_x"),
               c_y = t.require("norm_pos_y");
  const auto c_dx = t.find("gaze_point_3d_x"), c_dy = t.find("gaze_point_3d_y"), c_dz = t.find("gaze_point_3d_z");
  Recording r;
  r.tracker = "Pupil Player export (gaze_positions.csv)";
  r.eyes = "binocular (Pupil's gaze mapping)";
  r.screen_px = o.screen_px;
  r.has_tracker_fixations = false;
  std::string_view line;
  double previous = -INFINITY;
  while (lines.next(line)) {
    if (text::trim(line).empty()) continue;
    const auto f = row_fields(line, t, lines.number(), ',');
    GazeSample s;
    s.t_s = number(f[c_time], t, c_time, lines.number(), false);
    check_time_order(s.t_s, previous, name, lines.number());
    previous = s.t_s;
    const double conf = number(f[c_conf], t, c_conf, lines.number(), false);
    if (conf < 0 || conf > 1) fail("{}:{}: confidence {} is outside [0, 1]", name, lines.number(), conf);
    s.confidence = static_cast<float>(conf);
    const double nx = number(f[c_x], t, c_x, lines.number(), true), ny = number(f[c_y], t, c_y, lines.number(), true);
    s.px = {nx * r.screen_px.x, (1.0 - ny) * r.screen_px.y};  // Pupil: origin bottom-left
    if (c_dx && c_dy && c_dz) {
      const glm::dvec3 d{number(f[*c_dx], t, *c_dx, lines.number(), true), number(f[*c_dy], t, *c_dy, lines.number(), true),
                         number(f[*c_dz], t, *c_dz, lines.number(), true)};
      if (std::isfinite(d.x) && std::isfinite(d.y) && std::isfinite(d.z) && glm::length(d) > 0)
        s.direction = glm::normalize(d);  // Pupil's world camera: x right, y down, z forward, as ours
    }
    r.samples.push_back(s);
  }
  apply_validity(r, o.min_confidence);
  return r;
}

namespace {

// Pupil's event exports: one event per non-empty row, in start order. `columns(table)` looks its
// columns up once (missing ones are errors) and returns the row reader.
template <class Columns>
std::vector<GazeEvent> read_events(const std::string& content, const std::string& name, Columns&& columns) {
  text::Lines lines(content);
  const Table t = read_header(lines, name, ',');
  const auto read = columns(t);
  std::vector<GazeEvent> events;
  std::string_view line;
  while (lines.next(line)) {
    if (text::trim(line).empty()) continue;
    const GazeEvent e = read(row_fields(line, t, lines.number(), ','), lines.number());
    if (!events.empty()) check_time_order(e.start_s, events.back().start_s, name, lines.number());
    events.push_back(e);
  }
  return events;
}

}  // namespace

std::vector<GazeEvent> parse_pupil_fixations(const std::string& content, const std::string& name, glm::ivec2 screen_px) {
  if (text::has_bom(content)) return parse_pupil_fixations(content.substr(3), name, screen_px);
  return read_events(content, name, [&](const Table& t) {
    const size_t c_start = t.require("start_timestamp"), c_dur = t.require("duration");
    const auto c_x = t.find("norm_pos_x"), c_y = t.find("norm_pos_y");
    return [&t, &name, screen_px, c_start, c_dur, c_x, c_y](const std::vector<std::string_view>& f, int line) {
      GazeEvent e;
      e.start_s = number(f[c_start], t, c_start, line, false);
      const double ms = number(f[c_dur], t, c_dur, line, false);
      if (ms < 0) fail("{}:{}: negative duration {}", name, line, ms);
      e.end_s = e.start_s + ms / 1000.0;  // Pupil writes fixation durations in milliseconds
      if (c_x && c_y)
        e.px = {number(f[*c_x], t, *c_x, line, true) * screen_px.x, (1.0 - number(f[*c_y], t, *c_y, line, true)) * screen_px.y};
      return e;
    };
  });
}

std::vector<GazeEvent> parse_pupil_blinks(const std::string& content, const std::string& name) {
  if (text::has_bom(content)) return parse_pupil_blinks(content.substr(3), name);
  return read_events(content, name, [&](const Table& t) {
    const size_t c_start = t.require("start_timestamp"), c_end = t.require("end_timestamp");
    return [&t, &name, c_start, c_end](const std::vector<std::string_view>& f, int line) {
      GazeEvent e;
      e.start_s = number(f[c_start], t, c_start, line, false);
      e.end_s = number(f[c_end], t, c_end, line, false);
      if (e.end_s < e.start_s) fail("{}:{}: blink ends before it starts", name, line);
      return e;
    };
  });
}

// ---------------------------------------------------------------------------------------------
// Plain CSV: t,x,y[,confidence] with or without a header

Recording parse_gaze_csv(const std::string& content, const std::string& name, const ReadOptions& o) {
  if (text::has_bom(content)) return parse_gaze_csv(content.substr(3), name, o);
  text::Lines lines(content);
  Recording r;
  r.tracker = "plain CSV";
  r.eyes = "as recorded";
  r.screen_px = o.screen_px;
  // Column order: from a header of known names, or t,x,y[,confidence]
  int c_t = 0, c_x = 1, c_y = 2, c_conf = -1, c_status = -1, c_label = -1, c_pupil = -1;
  bool degrees = o.csv_degrees;
  size_t columns = 0;
  std::string_view line;
  double previous = -INFINITY;
  bool first = true;
  while (lines.next(line)) {
    if (text::trim(line).empty() || text::trim(line).front() == '#') continue;
    const auto f = text::split(line, ',');
    if (first) {
      first = false;
      if (!text::to_number(f[0])) {  // a header
        c_t = c_x = c_y = c_conf = -1;
        for (size_t i = 0; i < f.size(); ++i) {
          const std::string_view col = text::trim(f[i]);
          if (col == "x_deg" || col == "y_deg") degrees = true;
          int* slot = col == "t" || col == "time" || col == "t_s" ? &c_t
                      : col == "x" || col == "x_deg"              ? &c_x
                      : col == "y" || col == "y_deg"              ? &c_y
                      : col == "confidence"                       ? &c_conf
                      : col == "status"                           ? &c_status
                      : col == "label"                            ? &c_label
                      : col == "pupil"                            ? &c_pupil
                                                                  : nullptr;
          if (!slot)
            fail("{}:{}: unknown column '{}' (expected t, x, y (or x_deg, y_deg) and optionally confidence, status, label, pupil)", name,
                 lines.number(), col);
          if (*slot >= 0) fail("{}:{}: column '{}' appears twice", name, lines.number(), col);
          *slot = static_cast<int>(i);
        }
        if (c_t < 0 || c_x < 0 || c_y < 0) fail("{}:{}: the header needs columns t, x and y", name, lines.number());
        columns = f.size();
        continue;
      }
      columns = f.size();
      if (columns != 3 && columns != 4) fail("{}:{}: expected t,x,y[,confidence], got {} fields", name, lines.number(), columns);
      if (columns == 4) c_conf = 3;
    }
    if (f.size() != columns) fail("{}:{}: {} fields, expected {} (truncated or malformed line)", name, lines.number(), f.size(), columns);
    auto value = [&](int c, bool allow_missing, const char* what) {
      if (const auto v = text::to_number(f[c])) return *v;
      const std::string_view s = text::trim(f[c]);
      if (allow_missing && (s.empty() || s == "nan" || s == "NaN" || s == "NAN")) return static_cast<double>(NAN);
      fail("{}:{}: {} '{}' is not a number", name, lines.number(), what, s);
    };
    GazeSample s;
    s.t_s = value(c_t, false, "time") * o.csv_time_scale;
    check_time_order(s.t_s, previous, name, lines.number());
    previous = s.t_s;
    glm::dvec2 p{value(c_x, true, "x"), value(c_y, true, "y")};
    if (degrees) {
      // Degrees from the screen centre (y up) → the screen point of that direction
      if (!(std::abs(p.x) < 89 && std::abs(p.y) < 89) && std::isfinite(p.x) && std::isfinite(p.y))
        fail("{}:{}: gaze ({}, {}) degrees is not in front of the eye", name, lines.number(), p.x, p.y);
      p = {0.5 * r.screen_px.x + std::tan(glm::radians(p.x)) * o.display_distance_cm * r.screen_px.x / o.display_width_cm,
           0.5 * r.screen_px.y - std::tan(glm::radians(p.y)) * o.display_distance_cm * r.screen_px.y / o.display_height_cm};
    } else if (o.csv_normalised) {
      p *= glm::dvec2(r.screen_px);
    }
    if (o.csv_origin_bottom_left) p.y = r.screen_px.y - p.y;
    s.px = p;
    if (c_status >= 0 && value(c_status, false, "status") == 0) s.confidence = 0;  // the tracker lost the eye
    if (c_conf >= 0) {
      const double c = value(c_conf, false, "confidence");
      if (c < 0 || c > 1) fail("{}:{}: confidence {} is outside [0, 1]", name, lines.number(), c);
      s.confidence = static_cast<float>(c);
    }
    if (c_pupil >= 0) {
      const double v = value(c_pupil, true, "pupil");
      if (v < 0) fail("{}:{}: pupil size {} is negative", name, lines.number(), v);
      if (v > 0) s.pupil = static_cast<float>(v);  // 0: no pupil seen (EyeLink's convention)
    }
    r.samples.push_back(s);
  }
  // Pixel coordinates without a stated screen may come from any monitor: judge them against at
  // least an 8K screen (7680x4320), so that only glitches, not a large display, are refused
  const glm::ivec2 screen = r.screen_px;
  if (!o.csv_normalised && !degrees && !o.screen_from_user) r.screen_px = glm::max(r.screen_px, glm::ivec2(7680, 4320));
  apply_validity(r, o.min_confidence);
  r.screen_px = screen;
  return r;
}

}  // namespace foveal
