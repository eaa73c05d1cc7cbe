// foveal/gaze/bids.cpp — BIDS eye-tracking physio files, read and written.
#include "foveal/gaze/bids.h"

#include "foveal/util/error.h"
#include "foveal/util/gzip.h"
#include "foveal/util/text.h"

#include <fmt/format.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <filesystem>

namespace foveal {

namespace fs = std::filesystem;

namespace {

constexpr const char* kBidsVersion = "1.10.0";

bool ends_with(const std::string& s, std::string_view tail) { return s.size() >= tail.size() && s.ends_with(tail); }

// The path with its suffix+extension (`_physio.tsv.gz`) replaced.
std::string sibling(const std::string& physio, const std::string& suffix) {
  for (std::string_view tail : {"_physio.tsv.gz", "_physio.tsv"})
    if (ends_with(physio, tail)) return physio.substr(0, physio.size() - tail.size()) + suffix;
  return physio + suffix;
}

nlohmann::json read_sidecar(const std::string& path) {
  std::error_code ec;
  if (!fs::exists(path, ec)) fail("{}: no such file (the sidecar of every BIDS physio file)", path);
  const std::string text = text::read_file(path);
  try {
    nlohmann::json j = nlohmann::json::parse(text);
    if (!j.is_object()) fail("{}: a sidecar is a JSON object", path);
    return j;
  } catch (const nlohmann::json::parse_error& e) {
    fail("{}: not valid JSON (byte {}): {}", path, e.byte, e.what());
  }
}

double number_key(const nlohmann::json& j, const char* key, const std::string& file) {
  if (!j.contains(key)) fail("{}: {}: missing (required)", file, key);
  if (!j[key].is_number() || !std::isfinite(j[key].get<double>())) fail("{}: {}: must be a number, got {}", file, key, j[key].dump());
  return j[key].get<double>();
}

std::vector<std::string> columns_key(const nlohmann::json& j, const std::string& file) {
  if (!j.contains("Columns")) fail("{}: Columns: missing (required: the names of the TSV's columns)", file);
  const nlohmann::json& c = j["Columns"];
  if (!c.is_array() || c.empty()) fail("{}: Columns: must be a non-empty list of column names", file);
  std::vector<std::string> out;
  for (const auto& name : c) {
    if (!name.is_string()) fail("{}: Columns: must be a list of names, got {}", file, name.dump());
    out.push_back(name.get<std::string>());
  }
  return out;
}

// A header-less TSV, each row as many numbers or strings as the sidecar's Columns name.
struct Table {
  std::vector<std::string> columns;
  std::vector<std::vector<std::string>> rows;
  std::vector<int> line;
  int column(const std::string& name) const {
    const auto it = std::find(columns.begin(), columns.end(), name);
    return it == columns.end() ? -1 : static_cast<int>(it - columns.begin());
  }
};

Table read_table(const std::string& text, const std::string& name, std::vector<std::string> columns, const std::string& sidecar) {
  Table t;
  t.columns = std::move(columns);
  text::Lines lines(text::strip_bom(text));
  for (std::string_view line; lines.next(line);) {
    if (line.empty()) continue;
    const auto fields = text::split(line, '\t');
    if (fields.size() != t.columns.size())
      fail("{}:{}: {} values, but Columns in {} names {} columns", name, lines.number(), fields.size(), sidecar, t.columns.size());
    t.rows.emplace_back(fields.begin(), fields.end());
    t.line.push_back(lines.number());
  }
  return t;
}

// A cell as a number: n/a (or empty) is NaN; anything else not a number is an error naming the cell.
double cell(const Table& t, size_t row, int column, const std::string& name) {
  if (column < 0) return NAN;
  const std::string& v = t.rows[row][static_cast<size_t>(column)];
  if (v == "n/a" || v.empty()) return NAN;
  const std::optional<double> x = text::to_number(v);
  if (!x) fail("{}:{}: {}: '{}' is not a number (or n/a)", name, t.line[row], t.columns[static_cast<size_t>(column)], v);
  return *x;
}

// Seconds per unit of a column, from its description in the sidecar ({"timestamp": {"Units": "ms"}}).
double time_scale(const nlohmann::json& sidecar, const std::string& column, const std::string& file) {
  if (!sidecar.contains(column) || !sidecar[column].is_object() || !sidecar[column].contains("Units")) return 1.0;
  const std::string units = sidecar[column]["Units"].is_string() ? sidecar[column]["Units"].get<std::string>() : "";
  if (units == "s") return 1.0;
  if (units == "ms") return 1e-3;
  if (units == "us" || units == "µs") return 1e-6;
  fail("{}: {}.Units: '{}' (expected s, ms or us)", file, column, units);
}

std::string cell_text(double v) { return std::isfinite(v) ? fmt::format("{}", v) : std::string("n/a"); }

void check_label(const std::string& value, const char* entity, bool required) {
  if (value.empty()) {
    if (required) fail("{}: required (a BIDS label: letters and digits)", entity);
    return;
  }
  for (char c : value)
    if (!std::isalnum(static_cast<unsigned char>(c))) fail("{}: '{}' is not a BIDS label (letters and digits only)", entity, value);
}

void write_json(const std::string& path, const nlohmann::json& j) { write_file_atomically(path, j.dump(2) + "\n", false); }

nlohmann::json generated_by() { return nlohmann::json::array({{{"Name", "foveal"}, {"Version", "0.1.0"}}}); }

// The dataset's top-level files, where absent.
void ensure_dataset(const std::string& root, const nlohmann::json& description, const std::string& readme) {
  fs::create_directories(root);
  if (!fs::exists(fs::path(root) / "dataset_description.json"))
    write_json((fs::path(root) / "dataset_description.json").string(), description);
  if (!readme.empty() && !fs::exists(fs::path(root) / "README")) write_file_atomically((fs::path(root) / "README").string(), readme, false);
}

}  // namespace

bool is_bids_physio(const std::string& path) { return ends_with(path, "_physio.tsv.gz") || ends_with(path, "_physio.tsv"); }

Recording read_bids_physio(const std::string& path, const ReadOptions& o) {
  const std::string sidecar_path = sibling(path, "_physio.json");
  const std::string data = read_gzip_file(path);  // also reads the TSV uncompressed
  const nlohmann::json side = read_sidecar(sidecar_path);
  BidsFiles files;
  files.physio = path;
  files.sidecar = sidecar_path;
  // The screen: the sidecar's, else the task events' StimulusPresentation (where BIDS asks for it)
  const std::string events_sidecar = [&] {
    // sub-S[_ses-X]_task-T[_run-N]_events.json: the physio file's entities without recording-…
    std::string stem = sibling(fs::path(path).filename().string(), "");
    const size_t rec = stem.find("_recording-");
    if (rec != std::string::npos) stem = stem.substr(0, rec);
    return (fs::path(path).parent_path() / (stem + "_events.json")).string();
  }();
  if (!side.contains("ScreenResolution") && fs::exists(events_sidecar)) {
    const nlohmann::json ev = read_sidecar(events_sidecar);
    if (ev.contains("StimulusPresentation") && ev["StimulusPresentation"].is_object()) files.screen = ev["StimulusPresentation"];
  }
  const std::string events_path = sibling(path, "_physioevents.tsv.gz");
  if (fs::exists(events_path)) {
    files.events_sidecar = sibling(path, "_physioevents.json");
    files.events_json = read_sidecar(files.events_sidecar);
    files.events_tsv = read_gzip_file(events_path);
    files.events_name = events_path;
  }
  return parse_bids_physio(data, side, files, o);
}

Recording parse_bids_physio(const std::string& data, const nlohmann::json& side, const BidsFiles& files, const ReadOptions& o) {
  const std::string& path = files.physio;
  const std::string& sidecar_path = files.sidecar;
  if (!side.is_object()) fail("{}: a sidecar is a JSON object", sidecar_path);
  if (!side.contains("PhysioType"))
    fail("{}: PhysioType: missing; an eye-tracking recording says \"PhysioType\": \"eyetrack\"", sidecar_path);
  if (side["PhysioType"] != "eyetrack")
    fail("{}: PhysioType: {} is not \"eyetrack\": not an eye-tracking recording", sidecar_path, side["PhysioType"].dump());
  const double rate = number_key(side, "SamplingFrequency", sidecar_path);
  if (!(rate > 0)) fail("{}: SamplingFrequency: must be > 0 Hz, got {}", sidecar_path, rate);
  const Table t = read_table(data, path, columns_key(side, sidecar_path), sidecar_path);
  const int ct = t.column("timestamp"), cx = t.column("x_coordinate"), cy = t.column("y_coordinate"), cp = t.column("pupil_size"),
            cc = t.column("confidence"), dx = t.column("gaze_direction_x"), dy = t.column("gaze_direction_y"),
            dz = t.column("gaze_direction_z");
  if (cx < 0 || cy < 0) fail("{}: Columns: no x_coordinate and y_coordinate (BIDS eye tracking's gaze columns)", sidecar_path);
  if (side.contains("SampleCoordinateUnits") && side["SampleCoordinateUnits"] != "pixel")
    fail("{}: SampleCoordinateUnits: {}; foveal reads gaze in pixels", sidecar_path, side["SampleCoordinateUnits"].dump());
  const double start = side.contains("StartTime") ? number_key(side, "StartTime", sidecar_path) : 0.0;
  const double scale = time_scale(side, "timestamp", sidecar_path);

  Recording r;
  r.source = path;
  r.format = GazeFormat::bids;
  r.nominal_rate_hz = rate;
  r.tracker = side.value("Manufacturer", std::string("BIDS eye tracking"));
  if (side.contains("ManufacturersModelName") && side["ManufacturersModelName"].is_string())
    r.tracker.append(" ").append(side["ManufacturersModelName"].get<std::string>());
  r.eyes = side.contains("RecordedEye") && side["RecordedEye"].is_string() ? side["RecordedEye"].get<std::string>() : "";
  const nlohmann::json& screen = side.contains("ScreenResolution") || !files.screen.is_object() ? side : files.screen;
  r.screen_px = o.screen_px;
  if (screen.contains("ScreenResolution")) {
    const nlohmann::json& res = screen["ScreenResolution"];
    if (!res.is_array() || res.size() != 2 || !res[0].is_number_integer() || !res[1].is_number_integer() || res[0].get<int>() <= 0 ||
        res[1].get<int>() <= 0)
      fail("{}: ScreenResolution: must be [width, height] in pixels, got {}", sidecar_path, res.dump());
    if (!o.screen_from_user) r.screen_px = {res[0].get<int>(), res[1].get<int>()}, r.screen_from_file = true;
  }
  if (screen.contains("ScreenSize") && screen.contains("ScreenDistance") && screen["ScreenSize"].is_array() &&
      screen["ScreenSize"].size() == 2 && screen["ScreenSize"][0].is_number() && screen["ScreenSize"][1].is_number() &&
      screen["ScreenDistance"].is_number())
    r.screen_cm =
        glm::dvec3(screen["ScreenSize"][0].get<double>(), screen["ScreenSize"][1].get<double>(), screen["ScreenDistance"].get<double>()) *
        100.0;

  r.samples.resize(t.rows.size());
  for (size_t i = 0; i < t.rows.size(); ++i) {
    GazeSample& s = r.samples[i];
    s.t_s = ct >= 0 ? cell(t, i, ct, path) * scale : start + static_cast<double>(i) / rate;
    if (!std::isfinite(s.t_s)) fail("{}:{}: timestamp: n/a; every sample needs its time", path, t.line[i]);
    if (i > 0 && s.t_s < r.samples[i - 1].t_s)
      fail("{}:{}: timestamp {} goes back in time (after {})", path, t.line[i], s.t_s, r.samples[i - 1].t_s);
    s.px = {cell(t, i, cx, path), cell(t, i, cy, path)};
    s.pupil = static_cast<float>(cell(t, i, cp, path));
    const double c = cell(t, i, cc, path);
    s.confidence = cc >= 0 && std::isfinite(c) ? static_cast<float>(c) : 1.0f;
    if (dx >= 0 && dy >= 0 && dz >= 0) {
      const glm::dvec3 d(cell(t, i, dx, path), cell(t, i, dy, path), cell(t, i, dz, path));
      if (std::isfinite(d.x) && std::isfinite(d.y) && std::isfinite(d.z)) s.direction = d;
    }
  }
  if (r.samples.empty()) fail("{}: no gaze samples", path);

  // The tracker's events and the blocks (messages START, as EyeLink's), from the physioevents file
  // beside it (where there is one)
  if (!files.events_name.empty()) {
    const std::string& events_path = files.events_name;
    const std::string& events_json = files.events_sidecar;
    const nlohmann::json& es = files.events_json;
    if (!es.is_object()) fail("{}: a sidecar is a JSON object", events_json);
    const Table e = read_table(files.events_tsv, events_path, columns_key(es, events_json), events_json);
    const int onset = e.column("onset"), duration = e.column("duration"), type = e.column("trial_type"), message = e.column("message"),
              ex = e.column("x_coordinate"), ey = e.column("y_coordinate");
    if (onset < 0) fail("{}: Columns: no onset column", events_json);
    const double escale = time_scale(es, "onset", events_json);
    for (size_t k = 0; k < e.rows.size(); ++k) {
      const double at = cell(e, k, onset, events_path) * escale;
      const double length = duration >= 0 ? cell(e, k, duration, events_path) * escale : 0.0;
      const std::string kind = type >= 0 ? e.rows[k][static_cast<size_t>(type)] : "";
      const std::string text = message >= 0 ? e.rows[k][static_cast<size_t>(message)] : "";
      if (kind == "fixation") {
        r.fixations.push_back(
            {at, at + (std::isfinite(length) ? length : 0.0), {cell(e, k, ex, events_path), cell(e, k, ey, events_path)}});
      } else if (kind == "blink") {
        r.blinks.push_back({at, at + (std::isfinite(length) ? length : 0.0), glm::dvec2(NAN)});
      } else if (text == "START") {
        const auto first =
            std::lower_bound(r.samples.begin(), r.samples.end(), at, [](const GazeSample& s, double time) { return s.t_s < time; });
        const size_t index = static_cast<size_t>(first - r.samples.begin());
        if (index < r.samples.size()) r.block_starts.push_back(index);
      }
    }
    r.has_tracker_fixations =
        es.contains("TrackerFixations") && es["TrackerFixations"].is_boolean() ? es["TrackerFixations"].get<bool>() : !r.fixations.empty();
    std::sort(r.block_starts.begin(), r.block_starts.end());
    r.block_starts.erase(std::unique(r.block_starts.begin(), r.block_starts.end()), r.block_starts.end());
  }
  apply_validity(r, o.min_confidence);
  return r;
}

std::string bids_stem(const BidsEntities& e) {
  check_label(e.subject, "subject", true);
  check_label(e.session, "session", false);
  check_label(e.task, "task", true);
  if (!e.run.empty() && (e.run.find_first_not_of("0123456789") != std::string::npos || std::stoll(e.run) <= 0))
    fail("run: '{}' is not a run number (a positive integer)", e.run);
  std::string stem = "sub-" + e.subject;
  if (!e.session.empty()) stem += "_ses-" + e.session;
  stem += "_task-" + e.task;
  if (!e.run.empty()) stem += "_run-" + e.run;
  return stem + "_recording-eye1";
}

std::string bids_folder(const BidsEntities& e) {
  std::string folder = "sub-" + e.subject;
  if (!e.session.empty()) folder += "/ses-" + e.session;
  return folder + "/beh";
}

std::string write_bids_recording(const Recording& r, const BidsEntities& entities, const std::string& root, const glm::dvec3& screen_cm) {
  const std::string stem = bids_stem(entities);
  if (r.samples.empty()) fail("{}: no samples to write", r.source);
  if (!(screen_cm.x > 0 && screen_cm.y > 0 && screen_cm.z > 0)) fail("display: the screen's size and distance must be > 0");
  const fs::path folder = fs::path(root) / bids_folder(entities);
  const std::string physio = (folder / (stem + "_physio.tsv.gz")).string();
  if (fs::exists(physio)) fail("{}: exists already; foveal adds recordings to a dataset but never replaces one", physio);
  ensure_dataset(
      root, {{"Name", "Eye-tracking recordings"}, {"BIDSVersion", kBidsVersion}, {"DatasetType", "raw"}, {"GeneratedBy", generated_by()}},
      "Eye-tracking recordings in BIDS (physio eyetrack files), converted by foveal gaze --to-bids.\n");
  fs::create_directories(folder);

  // The samples: invalid ones (lost, low confidence, inside a blink) without a position
  const bool pupil = std::any_of(r.samples.begin(), r.samples.end(), [](const GazeSample& s) { return std::isfinite(s.pupil); });
  const bool confidence = std::any_of(r.samples.begin(), r.samples.end(), [](const GazeSample& s) { return s.confidence != 1.0f; });
  const bool direction = std::any_of(r.samples.begin(), r.samples.end(), [](const GazeSample& s) { return s.direction.has_value(); });
  std::vector<std::string> columns{"timestamp", "x_coordinate", "y_coordinate"};
  if (pupil) columns.push_back("pupil_size");
  if (confidence) columns.push_back("confidence");
  if (direction) columns.insert(columns.end(), {"gaze_direction_x", "gaze_direction_y", "gaze_direction_z"});
  std::string tsv;
  tsv.reserve(r.samples.size() * 48);
  for (const GazeSample& s : r.samples) {
    tsv += fmt::format("{}\t{}\t{}", s.t_s, cell_text(s.valid ? s.px.x : NAN), cell_text(s.valid ? s.px.y : NAN));
    auto add = [&](double v) {
      tsv += '\t';
      tsv += cell_text(v);
    };
    if (pupil) add(s.pupil);
    if (confidence) add(s.confidence);
    if (direction)
      for (int k = 0; k < 3; ++k) add(s.direction ? (*s.direction)[k] : NAN);
    tsv += '\n';
  }
  const double rate = r.nominal_rate_hz > 0 ? r.nominal_rate_hz : std::round(r.rate_hz());
  const std::string eye = r.eyes.find("left") != std::string::npos && r.eyes.find("right") == std::string::npos   ? "left"
                          : r.eyes.find("right") != std::string::npos && r.eyes.find("left") == std::string::npos ? "right"
                                                                                                                  : "cyclopean";
  const nlohmann::json resolution = {r.screen_px.x, r.screen_px.y};
  const nlohmann::json size_m = {screen_cm.x / 100.0, screen_cm.y / 100.0};
  nlohmann::json side = {
      {"PhysioType", "eyetrack"},
      {"SamplingFrequency", rate},
      {"StartTime", 0},
      {"Columns", columns},
      {"RecordedEye", eye},
      {"SampleCoordinateSystem", "gaze-on-screen"},
      {"SampleCoordinateUnits", "pixel"},
      {"EnvironmentCoordinates", "top-left"},
      {"ScreenResolution", resolution},
      {"ScreenSize", size_m},
      {"ScreenDistance", screen_cm.z / 100.0},
      {"Manufacturer", r.tracker.empty() ? std::string("n/a") : r.tracker},
      {"timestamp", {{"Description", "The tracker's clock"}, {"Units", "s"}}},
      {"x_coordinate", {{"Description", "Gaze on the screen, x from the left edge (n/a: the sample is invalid)"}, {"Units", "pixel"}}},
      {"y_coordinate", {{"Description", "Gaze on the screen, y from the top edge (n/a: the sample is invalid)"}, {"Units", "pixel"}}},
      {"SourceRecording", fs::path(r.source).filename().string()},
  };
  if (pupil) side["pupil_size"] = {{"Description", "Pupil size (area or diameter) as the tracker reported it, in its own units"}};
  if (confidence) side["confidence"] = {{"Description", "The tracker's confidence in the sample, 0-1"}};
  if (direction)
    for (const char* c : {"gaze_direction_x", "gaze_direction_y", "gaze_direction_z"})
      side[c] = {{"Description", "The tracker's 3-D gaze direction (Pupil's gaze_point_3d), its camera coordinates"}};

  // The tracker's events and the blocks' starts
  std::string events;
  std::vector<std::pair<double, std::string>> rows;
  for (size_t b : r.block_starts)
    if (b < r.samples.size()) rows.push_back({r.samples[b].t_s, fmt::format("{}\tn/a\tn/a\tSTART\tn/a\tn/a", r.samples[b].t_s)});
  for (const GazeEvent& f : r.fixations)
    rows.push_back(
        {f.start_s, fmt::format("{}\t{}\tfixation\tn/a\t{}\t{}", f.start_s, f.end_s - f.start_s, cell_text(f.px.x), cell_text(f.px.y))});
  for (const GazeEvent& b : r.blinks)
    rows.push_back({b.start_s, fmt::format("{}\t{}\tblink\tn/a\tn/a\tn/a", b.start_s, b.end_s - b.start_s)});
  std::stable_sort(rows.begin(), rows.end(), [](const auto& a, const auto& b) { return a.first < b.first; });
  for (const auto& row : rows) events += row.second + "\n";
  const nlohmann::json events_side = {
      {"Columns", {"onset", "duration", "trial_type", "message", "x_coordinate", "y_coordinate"}},
      {"OnsetSource", "timestamp"},
      {"Description", "The tracker's own events (fixations, blinks) and the recording blocks' starts (message START)"},
      {"TrackerFixations", r.has_tracker_fixations},
      {"onset", {{"Description", "On the timestamp clock"}, {"Units", "s"}}},
      {"duration", {{"Units", "s"}}},
      {"x_coordinate", {{"Description", "A fixation's centre, pixels"}, {"Units", "pixel"}}},
      {"y_coordinate", {{"Description", "A fixation's centre, pixels"}, {"Units", "pixel"}}},
  };
  // The task's events: the recording as one trial, and the screen as BIDS asks for gaze on screen
  std::string task_stem = stem.substr(0, stem.find("_recording-"));
  const std::string task_events =
      fmt::format("onset\tduration\ttrial_type\n0\t{}\trecording\n", r.samples.back().t_s - r.samples.front().t_s);
  const nlohmann::json task_side = {{"StimulusPresentation",
                                     {{"ScreenDistance", screen_cm.z / 100.0},
                                      {"ScreenOrigin", {"top", "left"}},
                                      {"ScreenResolution", resolution},
                                      {"ScreenSize", size_m}}},
                                    {"trial_type", {{"Description", "recording: the whole eye-tracking recording"}}}};

  write_json((folder / (stem + "_physio.json")).string(), side);
  write_file_atomically((folder / (stem + "_physioevents.tsv.gz")).string(), events, true);
  write_json((folder / (stem + "_physioevents.json")).string(), events_side);
  if (!fs::exists(folder / (task_stem + "_events.tsv"))) {
    write_file_atomically((folder / (task_stem + "_events.tsv")).string(), task_events, false);
    write_json((folder / (task_stem + "_events.json")).string(), task_side);
  }
  write_file_atomically(physio, tsv, true);  // last: a recording is there only once all of it is
  return physio;
}

std::string write_bids_events(const EventDetection& d, const BidsEntities& entities, const std::string& root,
                              const nlohmann::json& parameters) {
  const std::string stem = bids_stem(entities);
  const fs::path base = fs::path(root) / "derivatives" / "foveal";
  ensure_dataset(base.string(),
                 {{"Name", "foveal: eye-movement events"},
                  {"BIDSVersion", kBidsVersion},
                  {"DatasetType", "derivative"},
                  {"GeneratedBy", generated_by()}},
                 "");
  const fs::path folder = base / bids_folder(entities);
  fs::create_directories(folder);
  std::string tsv;
  for (const DetectedEvent& e : d.events)
    tsv += fmt::format("{}\t{}\t{}\t{}\t{}\t{}\t{}\t{}\t{}\n", e.onset_s, e.duration_s, to_string(e.label), cell_text(e.amplitude_deg),
                       cell_text(e.peak_velocity_deg_s), cell_text(e.start_deg.x), cell_text(e.start_deg.y), cell_text(e.end_deg.x),
                       cell_text(e.end_deg.y));
  const nlohmann::json side = {
      {"Columns",
       {"onset", "duration", "trial_type", "amplitude_deg", "peak_velocity_deg_s", "start_x_deg", "start_y_deg", "end_x_deg", "end_y_deg"}},
      {"OnsetSource", "timestamp"},
      {"Description", "Eye-movement events detected by foveal gaze --events"},
      {"Sources", {fmt::format("bids:raw:{}/{}_physio.tsv.gz", bids_folder(entities), stem)}},
      {"Detector", d.method ? to_string(*d.method) : "labels"},
      {"DetectorParameters", parameters},
      {"SamplingFrequency", d.sampling_hz},
      {"onset", {{"Description", "The event's first sample, on the timestamp clock"}, {"Units", "s"}}},
      {"duration", {{"Units", "s"}}},
      {"trial_type",
       {{"Levels",
         {{"fixation", "fixation"},
          {"saccade", "saccade"},
          {"pso", "post-saccadic oscillation"},
          {"pursuit", "smooth pursuit"},
          {"blink", "blink"}}}}},
      {"amplitude_deg", {{"Units", "degree"}}},
      {"peak_velocity_deg_s", {{"Units", "degree/s"}}},
      {"start_x_deg", {{"Description", "First valid position, degrees from the screen centre, x right"}, {"Units", "degree"}}},
      {"start_y_deg", {{"Description", "First valid position, degrees from the screen centre, y up"}, {"Units", "degree"}}},
      {"end_x_deg", {{"Units", "degree"}}},
      {"end_y_deg", {{"Units", "degree"}}},
  };
  const std::string path = (folder / (stem + "_desc-foveal_physioevents.tsv.gz")).string();
  write_json((folder / (stem + "_desc-foveal_physioevents.json")).string(), side);
  write_file_atomically(path, tsv, true);
  return path;
}

}  // namespace foveal
