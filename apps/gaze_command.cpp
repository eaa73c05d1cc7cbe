// apps/gaze_command.cpp — `foveal gaze`: read a recording, summarise it, filter its fixations,
// compare them with the tracker's own, draw the scan path.
#include "commands.h"
#include "foveal/gaze/detect.h"
#include "foveal/gaze/bids.h"
#include "foveal/gaze/events.h"
#include "foveal/gaze/landing.h"
#include "foveal/util/stats.h"
#include "foveal/gaze/summary.h"
#include "foveal/render/outputs.h"
#include "foveal/io/scanpath.h"
#include "foveal/util/error.h"
#include "foveal/util/parse.h"

#include <fmt/core.h>

#include <algorithm>
#include <chrono>
#include <filesystem>
#include <memory>

namespace foveal::app {

void add_gaze_options(CLI::App& cmd, GazeOptions& o, const std::string& fixation_help) {
  cmd.add_option("--format", o.format,
                 "recording format: auto, asc (EyeLink), pupil (Pupil Player gaze_positions.csv), tobii (SDK or Pro Lab TSV), csv "
                 "(t,x,y[,confidence])")
      ->capture_default_str();
  cmd.add_option("--screen", o.screen,
                 "screen WxH in pixels for normalised coordinates (Pupil, Tobii SDK, --coords norm) or to override the file's (default: "
                 "the display's resolution)");
  cmd.add_option("--gaze-eye", o.eye, "binocular recordings: average (of the valid eyes), left or right")->capture_default_str();
  cmd.add_option("--min-confidence", o.min_confidence, "samples with lower tracker confidence are invalid (Pupil's default)")
      ->capture_default_str()
      ->check(CLI::Range(0.0, 1.0));
  cmd.add_option("--time-unit", o.time_unit, "csv: unit of the t column: s, ms or us")->capture_default_str();
  cmd.add_option("--coords", o.coords,
                 "csv: x, y in px (screen pixels), norm ([0,1] of the screen) or deg (degrees from the screen centre, y up, through "
                 "--display; also columns x_deg, y_deg)")
      ->capture_default_str();
  cmd.add_option("--origin", o.origin, "csv: top-left or bottom-left")->capture_default_str();
  cmd.add_option("--fixations", o.fixations_file, "Pupil: the tracker's fixations.csv (default: the one beside the recording)");
  cmd.add_option("--blinks", o.blinks_file, "Pupil: the tracker's blinks.csv (default: the one beside the recording)");
  cmd.add_option("--fixation", o.fixation,
                 fixation_help.empty()
                     ? "fixation filter: ivvt (velocity threshold, smooth pursuit followed), mean (the paper's per-frame mean), "
                       "ivt (velocity threshold) or idt (dispersion threshold)"
                     : fixation_help)
      ->capture_default_str();
  cmd.add_option("--ivt-threshold", o.ivt_threshold, "I-VT, I-VVT: saccade velocity threshold, deg/s")->capture_default_str();
  cmd.add_option("--pursuit-velocity", o.pursuit_velocity,
                 "ivvt, --events nhp: samples slower than saccades but faster than this are pursuit candidates, deg/s")
      ->capture_default_str();
  cmd.add_option("--pursuit-window-ms", o.pursuit_window_ms, "ivvt, --events nhp: the pursuit velocity's least-squares window, ms")
      ->capture_default_str();
  cmd.add_option("--min-pursuit-ms", o.min_pursuit_ms, "ivvt, --events nhp: shortest pursuit, ms")->capture_default_str();
  cmd.add_option("--velocity-window-ms", o.velocity_window_ms, "I-VT velocity window, ms")->capture_default_str();
  cmd.add_option("--gap-fill-ms", o.gap_fill_ms, "invalid gaps up to this long are interpolated, ms")->capture_default_str();
  cmd.add_option("--merge-gap-ms", o.merge_gap_ms, "I-VT: merge fixations less than this apart in time, ms …")->capture_default_str();
  cmd.add_option("--merge-angle", o.merge_angle, "… and this apart in angle, deg")->capture_default_str();
  cmd.add_option("--min-fixation-ms", o.min_fixation_ms, "I-VT: discard shorter fixations, ms")->capture_default_str();
  cmd.add_option("--median-window", o.median_window,
                 "noise reduction: moving median over this many samples before filtering (odd; 1 = off)")
      ->capture_default_str();
  cmd.add_option("--idt-dispersion", o.idt_dispersion, "I-DT dispersion limit (x range + y range), deg")->capture_default_str();
  cmd.add_option("--idt-duration-ms", o.idt_duration_ms, "I-DT minimum fixation duration, ms")->capture_default_str();
}

ReadOptions resolve_read_options(const GazeOptions& o, const Display& display) {
  ReadOptions r;
  r.format = parse_gaze_format(o.format);
  r.screen_px = {display.res_x, display.res_y};
  if (!o.screen.empty()) {
    r.screen_px = parse_size("--screen", o.screen);
    r.screen_from_user = true;
  }
  r.eye = parse_eye_selection(o.eye);
  r.min_confidence = static_cast<float>(o.min_confidence);
  if (o.time_unit == "s")
    r.csv_time_scale = 1;
  else if (o.time_unit == "ms")
    r.csv_time_scale = 1e-3;
  else if (o.time_unit == "us")
    r.csv_time_scale = 1e-6;
  else
    fail("--time-unit: unknown unit '{}' (expected s, ms or us)", o.time_unit);
  if (o.coords != "px" && o.coords != "norm" && o.coords != "deg") fail("--coords: expected px, norm or deg, got '{}'", o.coords);
  r.csv_normalised = o.coords == "norm";
  r.csv_degrees = o.coords == "deg";
  r.display_width_cm = display.width_cm;
  r.display_height_cm = display.height_cm;
  r.display_distance_cm = display.distance_cm;
  if (o.origin != "top-left" && o.origin != "bottom-left") fail("--origin: expected top-left or bottom-left, got '{}'", o.origin);
  r.csv_origin_bottom_left = o.origin == "bottom-left";
  r.fixations_file = o.fixations_file;
  r.blinks_file = o.blinks_file;
  return r;
}

Recording read_recording_warned(const std::string& path, const ReadOptions& options) {
  Recording r = read_recording(path, options);
  for (const std::string& warning : r.warnings) fmt::print(stderr, "foveal: warning: {}\n", warning);
  return r;
}

FixationParams resolve_fixation_params(const GazeOptions& o) {
  // The options in milliseconds are checked here, in the command line's words and unit; the
  // library checks its seconds (errors naming its fields, which the front ends rename)
  require_positive(o.velocity_window_ms, "--velocity-window-ms");
  require_non_negative(o.gap_fill_ms, "--gap-fill-ms");
  require_non_negative(o.merge_gap_ms, "--merge-gap-ms");
  require_non_negative(o.min_fixation_ms, "--min-fixation-ms");
  require_non_negative(o.idt_duration_ms, "--idt-duration-ms");
  require_positive(o.pursuit_window_ms, "--pursuit-window-ms");
  require_non_negative(o.min_pursuit_ms, "--min-pursuit-ms");
  FixationParams p;
  p.velocity_threshold_deg_s = o.ivt_threshold;
  p.velocity_window_s = o.velocity_window_ms / 1000;
  p.gap_fill_s = o.gap_fill_ms / 1000;
  p.merge_gap_s = o.merge_gap_ms / 1000;
  p.merge_angle_deg = o.merge_angle;
  p.min_fixation_s = o.min_fixation_ms / 1000;
  p.dispersion_deg = o.idt_dispersion;
  p.min_duration_s = o.idt_duration_ms / 1000;
  p.median_window = o.median_window;
  p.pursuit.velocity_deg_s = o.pursuit_velocity;
  p.pursuit.window_s = o.pursuit_window_ms / 1000;
  p.pursuit.min_s = o.min_pursuit_ms / 1000;
  validate(p);
  return p;
}

namespace {

// The command's options as typed.
struct GazeCommandOptions {
  std::string recording, json, samples, scanpath = "scanpath.png", display, events, samples_out, events_out, evaluate, coder2, landings_out;
  std::string to_bids;  // --to-bids DIR, with the entities below
  BidsEntities bids;
  GazeOptions gaze;
  std::optional<double> filter_window_ms;  // default: the detector's (6 ms nh/nhp, 10 ms nhr)
  double detection_window_ms = 20, ek_lambda = 6, blink_flank_ms = 100, max_blink_ms = 2000;
  bool no_scanpath = false, quiet = false;
};

// --events: the labels of every sample (a detector's, or another tool's from a file), scored
// against an expert coder's with --evaluate (and against a second coder's, with the coders'
// agreement as the ceiling, with --coder2).
struct EventsRun {
  std::optional<EventDetection> detection;
  std::string detector;  // the method's name (auto resolved), or file:PATH
  double detect_ms = 0;
  std::optional<Evaluation> evaluation, second, ceiling;
  std::vector<LandingReport> landings;  // each saccade's landing as the live predictor saw it
};

// Median and 90th percentile (NaN: not predicted, left out).
std::pair<double, double> median_p90(const std::vector<double>& v) { return {quantile(v, 0.5), quantile(v, 0.9)}; }

EventsRun detect_and_score(const GazeCommandOptions& o, const Recording& recording, const Display& display, const FixationParams& params) {
  EventsRun run;
  if (o.events.empty()) return run;
  EventParams ep;
  ep.pursuit = params.pursuit;  // the options --fixation ivvt reads too
  if (o.filter_window_ms) ep.filter_window_s = ep.robust_filter_window_s = *o.filter_window_ms / 1000;
  ep.detection_window_s = o.detection_window_ms / 1000;
  ep.ek_lambda = o.ek_lambda;
  ep.blink_flank_s = o.blink_flank_ms / 1000;
  ep.max_blink_s = o.max_blink_ms / 1000;
  std::vector<double> t(recording.samples.size());
  for (size_t i = 0; i < t.size(); ++i) t[i] = recording.samples[i].t_s;
  auto read_labels = [&](const std::string& path) { return align_labels(read_label_file(path), t); };  // matched to the samples by time
  const auto started = std::chrono::steady_clock::now();
  const GazeGeometry geometry(display, recording.screen_px);
  if (o.events.rfind("file:", 0) == 0)  // another tool's labels of these samples: listed and scored like a detector's
    run.detection = events_from_labels(recording, geometry, read_labels(o.events.substr(5)).label);
  else
    run.detection = detect_events(recording, geometry, parse_event_method(o.events), ep, params);
  run.detect_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - started).count();
  run.detector = run.detection->method ? to_string(*run.detection->method) : o.events;
  run.landings = evaluate_landings(recording, geometry, *run.detection);
  if (!o.evaluate.empty()) {
    std::optional<LabelFile> second;
    if (!o.coder2.empty()) second = read_label_file(o.coder2);
    CoderEvaluation scores = evaluate_against_coders(run.detection->labels, t, read_label_file(o.evaluate), second);
    run.evaluation = std::move(scores.evaluation);
    run.second = std::move(scores.second);
    run.ceiling = std::move(scores.ceiling);
  }
  return run;
}

// --samples-out (each sample's label) and --events-out (BIDS-style events.tsv).
void write_event_files(const GazeCommandOptions& o, const Recording& recording, const EventsRun& run) {
  if (!run.detection) return;
  const std::vector<EventLabel>& labels = run.detection->labels;
  if (!o.samples_out.empty()) {
    std::string text = "t_s,x,y,label\n";
    for (size_t i = 0; i < labels.size(); ++i)
      text += fmt::format("{:.17g},{:.17g},{:.17g},{}\n", recording.samples[i].t_s, recording.samples[i].px.x, recording.samples[i].px.y,
                          to_string(labels[i]));
    write_text_file(o.samples_out, text);
  }
  if (!o.events_out.empty()) write_text_file(o.events_out, events_tsv(*run.detection, recording));
  if (!o.landings_out.empty()) write_text_file(o.landings_out, landings_tsv(run.landings));
}

// The "landings" entry of --json: per saccade and summarised.
nlohmann::json landings_json(const std::vector<LandingReport>& reports) {
  auto number = [](double v) { return std::isfinite(v) ? nlohmann::json(v) : nlohmann::json(nullptr); };
  nlohmann::json list = nlohmann::json::array();
  std::vector<double> first, third, gained;
  for (const LandingReport& r : reports) {
    list.push_back({{"onset_s", r.onset_s},
                    {"landing_s", r.landing_s},
                    {"amplitude_deg", number(r.amplitude_deg)},
                    {"end_deg", {number(r.landing_deg.x), number(r.landing_deg.y)}},
                    {"predicted", r.predicted},
                    {"predicted_deg", {number(r.first_deg.x), number(r.first_deg.y)}},
                    {"error_deg", number(r.first_error_deg)},
                    {"two_thirds_error_deg", number(r.two_thirds_error_deg)},
                    {"gained_ms", number(r.gained_ms)}});
    first.push_back(r.first_error_deg);
    third.push_back(r.two_thirds_error_deg);
    gained.push_back(r.gained_ms);
  }
  const auto [fm, f90] = median_p90(first);
  const auto [tm, t90] = median_p90(third);
  const auto [gm, g90] = median_p90(gained);
  (void)g90;
  return {{"model", "mirrored velocity profile (gaze/landing.h)"},
          {"saccades", reports.size()},
          {"predicted", std::count_if(reports.begin(), reports.end(), [](const LandingReport& r) { return r.predicted; })},
          {"error_deg_median", number(fm)},
          {"error_deg_p90", number(f90)},
          {"two_thirds_error_deg_median", number(tm)},
          {"two_thirds_error_deg_p90", number(t90)},
          {"gained_ms_median", number(gm)},
          {"list", list}};
}

// The "events" entry of --json: detector, thresholds, counts per class, and the scores.
nlohmann::json events_json(const GazeCommandOptions& o, const EventsRun& run) {
  auto number = [](double v) { return std::isfinite(v) ? nlohmann::json(v) : nlohmann::json(nullptr); };
  auto scores = [](const Evaluation& e) { return evaluation_json(e); };
  const EventDetection& d = *run.detection;
  nlohmann::json counts = nlohmann::json::object();
  for (EventLabel c : kEventClasses) counts[to_string(c)] = 0;
  for (const DetectedEvent& e : d.events) counts[to_string(e.label)] = counts[to_string(e.label)].get<int>() + 1;
  nlohmann::json ev = {{"detector", run.detector},
                       {"detect_ms", run.detect_ms},
                       {"sampling_hz", d.sampling_hz},
                       {"peak_threshold_deg_s", number(d.peak_threshold_deg_s)},
                       {"onset_threshold_deg_s", number(d.onset_threshold_deg_s)},
                       {"counts", counts}};
  if (run.evaluation) {
    ev.update(scores(*run.evaluation));
    ev["labels"] = o.evaluate;
    ev["matching"] = "Hooge et al. 2018: earliest overlapping event of the same class";
  }
  if (run.second) ev["coder2"] = scores(*run.second), ev["coder2"]["labels"] = o.coder2;
  if (run.ceiling) ev["ceiling"] = scores(*run.ceiling), ev["ceiling"]["labels"] = o.coder2;
  ev["landings"] = landings_json(run.landings);
  if (const std::string slow = late_landing_note(run.detection->sampling_hz); !slow.empty()) ev["landings"]["note"] = slow;
  return ev;
}

// --samples: the samples as read.
void write_samples_csv(const std::string& path, const Recording& recording) {
  std::string text = "t_s,x,y,confidence,valid\n";
  for (const GazeSample& s : recording.samples)
    text += fmt::format("{:.17g},{:.17g},{:.17g},{:.9g},{}\n", s.t_s, s.px.x, s.px.y, s.confidence, s.valid ? 1 : 0);
  write_text_file(path, text);
}

// The summary, the event counts and the scores on stdout.
void print_gaze(const GazeCommandOptions& o, const Recording& recording, const GazeSummary& summary, FixationMethod method,
                const EventsRun& run) {
  fmt::print("{}", format_summary(recording, summary));
  if (method == FixationMethod::mean || method == FixationMethod::ivvt)
    fmt::print("  ({} is a causal filter for the fovea: the scan path shows I-VT's fixations; --events auto labels pursuit)\n",
               to_string(method));
  for (const std::string* written : {&o.json, &o.samples, &o.samples_out, &o.events_out, &o.landings_out})
    if (!written->empty()) fmt::print("  wrote     {}\n", *written);
  if (run.detection) {
    const EventDetection& d = *run.detection;
    std::string counts;
    for (EventLabel c : kEventClasses) {
      const auto k = std::count_if(d.events.begin(), d.events.end(), [c](const DetectedEvent& e) { return e.label == c; });
      counts += fmt::format("{}{} {}", counts.empty() ? "" : ", ", k, to_string(c));
    }
    fmt::print("  events    {} ({:.0f} Hz{}): {}\n", run.detector, d.sampling_hz,
               std::isfinite(d.peak_threshold_deg_s)
                   ? fmt::format(", thresholds {:.1f}/{:.1f} deg/s", d.peak_threshold_deg_s, d.onset_threshold_deg_s)
                   : "",
               counts);
  }
  auto print_scores = [&](const Evaluation& e, const std::string& what) {
    fmt::print("  {}: sample kappa {:.3f} (accuracy {:.3f}){}\n", what, e.kappa, e.accuracy,
               e.samples < recording.samples.size()
                   ? fmt::format(", over the {} of {} samples every coder labelled", e.samples, recording.samples.size())
                   : "");
    for (const ClassScore& c : e.classes) {
      if (c.reference_samples == 0 && c.test_samples == 0) continue;
      fmt::print("    {:<9} kappa {:6.3f}  events F1 {:5.3f} ({} hits, {} misses, {} false alarms)  RTO {:+.1f} ms  RTD {:+.1f} ms\n",
                 to_string(c.label), c.kappa, c.f1, c.hits, c.misses, c.false_alarms, c.rto_ms, c.rtd_ms);
    }
  };
  if (run.detection) {
    std::vector<double> first, third, gained;
    size_t predicted = 0;
    for (const LandingReport& r : run.landings) {
      predicted += r.predicted ? 1 : 0;
      first.push_back(r.first_error_deg);
      third.push_back(r.two_thirds_error_deg);
      gained.push_back(r.gained_ms);
    }
    const auto [fm, f90] = median_p90(first);
    const auto [tm, t90] = median_p90(third);
    const double gm = median_p90(gained).first;
    const std::string note = late_landing_note(run.detection->sampling_hz);
    if (!run.landings.empty())
      fmt::print(
          "  landings  {} of {} saccades predicted live: error at the first prediction median {:.2f} deg (p90 {:.2f}), two "
          "thirds in {:.2f} deg (p90 {:.2f}); within 1 deg for good {:.0f} ms before landing (median){}\n",
          predicted, run.landings.size(), fm, f90, tm, t90, gm, note.empty() ? "" : "; " + note);
  }
  if (run.evaluation) print_scores(*run.evaluation, fmt::format("scores    {} against {}", run.detector, o.evaluate));
  if (run.second) print_scores(*run.second, fmt::format("scores    {} against {}", run.detector, o.coder2));
  if (run.ceiling) print_scores(*run.ceiling, fmt::format("ceiling   {} against {}", o.coder2, o.evaluate));
  if (!o.no_scanpath) fmt::print("  wrote     {}\n", o.scanpath);
}

int run_gaze(const GazeCommandOptions& o) {
  // The detectors' options, checked whether or not --events uses them (a value out of range is a
  // mistake either way)
  if (o.filter_window_ms) require_positive(*o.filter_window_ms, "--filter-window-ms");
  require_non_negative(o.detection_window_ms, "--detection-window-ms");
  require_positive(o.ek_lambda, "--ek-lambda");
  require_non_negative(o.blink_flank_ms, "--blink-flank-ms");
  require_positive(o.max_blink_ms, "--max-blink-ms");
  // The options that go together, checked before the recording is read
  if (o.events.empty() && (!o.samples_out.empty() || !o.evaluate.empty() || !o.events_out.empty() || !o.landings_out.empty()))
    fail("--samples-out, --events-out, --landings-out and --evaluate need --events");
  if (!o.coder2.empty() && o.evaluate.empty()) fail("--coder2 needs --evaluate (the first coder's labels)");
  if (o.to_bids.empty() && (!o.bids.subject.empty() || !o.bids.task.empty() || !o.bids.session.empty() || !o.bids.run.empty()))
    fail("--subject, --task, --session and --run name a recording in the dataset of --to-bids DIR");
  if (!o.to_bids.empty()) bids_stem(o.bids);  // the entities checked before anything is read
  // The display: as given, else the recording's own (a BIDS sidecar states it), else 47.5 x 30 cm at 60 cm
  const std::string display_text = o.display.empty() ? "47.5,30,60" : o.display;
  Display display = parse_display(display_text, Display{});
  const bool display_has_resolution = parse_numbers("--display", display_text).size() == 5;
  const ReadOptions read = resolve_read_options(o.gaze, display);
  const FixationParams params = resolve_fixation_params(o.gaze);
  const FixationMethod method = parse_fixation_method(o.gaze.fixation);
  const Recording recording = read_recording_warned(o.recording, read);
  if (o.display.empty() && recording.screen_cm) {
    display.width_cm = recording.screen_cm->x;
    display.height_cm = recording.screen_cm->y;
    display.distance_cm = recording.screen_cm->z;
  }
  if (!display_has_resolution) {
    display.res_x = recording.screen_px.x;
    display.res_y = recording.screen_px.y;
  }
  const GazeSummary summary = summarize_recording(recording, display, params);
  const EventsRun run = detect_and_score(o, recording, display, params);
  write_event_files(o, recording, run);
  if (!o.to_bids.empty()) {
    const std::string physio =
        write_bids_recording(recording, o.bids, o.to_bids, {display.width_cm, display.height_cm, display.distance_cm});
    if (!o.quiet) fmt::print("  bids      {}\n", physio);
    if (run.detection) {
      const std::string events = write_bids_events(*run.detection, o.bids, o.to_bids, events_json(o, run));
      if (!o.quiet) fmt::print("  bids      {}\n", events);
    }
  }
  if (!o.json.empty()) {
    nlohmann::json j = summary.json;
    if (run.detection) j["events"] = events_json(o, run);
    write_json_file(o.json, j);
  }
  if (!o.samples.empty()) write_samples_csv(o.samples, recording);
  if (!o.no_scanpath) {
    const FixationResult& shown = method == FixationMethod::idt ? summary.filters[1].result : summary.filters[0].result;
    ScanpathStyle style;
    style.title = fmt::format("{} - {} fixations ({})", std::filesystem::path(recording.source).filename().string(), shown.fixations.size(),
                              method == FixationMethod::idt ? "I-DT" : "I-VT");
    write_scanpath(recording, shown, o.scanpath, style);
  }
  if (!o.quiet) print_gaze(o, recording, summary, method, run);
  return 0;
}

}  // namespace

std::function<int()> add_gaze_command(CLI::App& app) {
  auto* cmd = app.add_subcommand(
      "gaze", "summarise an eye-tracker recording: samples, fixations (I-VT, I-DT), agreement with the tracker, scan path");

  auto o = std::make_shared<GazeCommandOptions>();
  cmd->add_option("RECORDING", o->recording, "EyeLink .asc, Pupil gaze_positions.csv, Tobii .tsv or a t,x,y CSV")->required();
  add_gaze_options(*cmd, o->gaze);
  cmd->add_option("--display", o->display,
                  "the recording's screen W_CM,H_CM,DIST_CM[,RES_X,RES_Y] (angles for the filters; default: what the recording "
                  "states, a BIDS sidecar's screen, else 47.5,30,60); the resolution defaults to the recording's screen");
  cmd->add_option("--to-bids", o->to_bids,
                  "also write the recording into the BIDS dataset DIR (created where absent): sub-S/[ses-X/]beh/…_physio.tsv.gz with "
                  "its sidecar, the tracker's events and the screen; with --events, the events as a derivative "
                  "(derivatives/foveal/…_desc-foveal_physioevents.tsv.gz)");
  cmd->add_option("--subject", o->bids.subject, "--to-bids: the participant's label (letters and digits)");
  cmd->add_option("--task", o->bids.task, "--to-bids: the task's label");
  cmd->add_option("--session", o->bids.session, "--to-bids: the session's label (optional)");
  cmd->add_option("--run", o->bids.run, "--to-bids: the run number (optional)");
  cmd->add_option("--json", o->json, "write the summary as JSON")->check(output_file());
  cmd->add_option("--events", o->events,
                  "label every sample and list the events: nhr (saccades on local robust thresholds + PSO + pursuit in context + "
                  "blinks; the recommended, = auto), nhp (nh + pursuit, tuned on fixation tasks), "
                  "nh (Nystrom & Holmqvist 2010: saccades, PSO, fixations, blinks), ek (Engbert & Kliegl 2003 saccades), "
                  "ivt or idt (fixation filters: other valid samples saccades, lost ones blinks), ivvt (the causal filter replay and "
                  "view follow the eye with: its fixations, pursuits and saccades), "
                  "or file:LABELS.csv (another tool's labels of these samples, listed and scored the same way)");
  cmd->add_option("--samples-out", o->samples_out, "--events: write t_s,x,y,label per sample (CSV)")->check(output_file());
  cmd->add_option("--landings-out", o->landings_out,
                  "--events: write each saccade's landing as the live predictor saw it (TSV: the true and predicted landing, the "
                  "error in degrees at the first prediction and two thirds in, the time gained; docs/realtime.md)")
      ->check(output_file());
  cmd->add_option("--events-out", o->events_out,
                  "--events: write the events as a BIDS-style events.tsv (onset, duration, trial_type, amplitude, peak velocity, "
                  "start and end positions in degrees)")
      ->check(output_file());
  cmd->add_option("--evaluate", o->evaluate,
                  "--events: score the labels against an expert's (CSV with t/t_s and label columns, e.g. the IRF recordings): "
                  "sample-level Cohen's kappa per class and overall, event F1 (Hooge et al. 2018 matching), RTO/RTD");
  cmd->add_option("--coder2", o->coder2,
                  "--evaluate: a second coder's labels of the same samples: the labels are scored against them too, and their agreement "
                  "with the first coder's is the ceiling");
  cmd->add_option("--filter-window-ms", o->filter_window_ms,
                  "nh, nhp, nhr: Savitzky-Golay window of the velocity, ms (default 6 nh, nhp; 10 nhr)");
  cmd->add_option(
         "--detection-window-ms", o->detection_window_ms,
         "nh, nhp, nhr: window of the smoother velocity whose peaks also start saccades (small ones in noise), ms (0: off, the paper's)")
      ->capture_default_str();
  cmd->add_option("--ek-lambda", o->ek_lambda, "ek: threshold in median-based standard deviations of the velocity")->capture_default_str();
  cmd->add_option("--blink-flank-ms", o->blink_flank_ms,
                  "ek, nh, nhp, nhr: a blink takes in the lid's artefacts up to this long either side of the loss, ms")
      ->capture_default_str();
  cmd->add_option("--max-blink-ms", o->max_blink_ms, "ek, nh, nhp, nhr: longer losses are undefined, not blinks, ms")
      ->capture_default_str();
  cmd->add_option("--samples", o->samples,
                  "write the samples as read (t_s,x,y,confidence,valid: seconds, screen pixels, NaN where the eye was lost) as CSV")
      ->check(output_file());
  cmd->add_option("--scanpath", o->scanpath, "scan-path picture (PNG) of the --fixation filter's fixations")
      ->capture_default_str()
      ->check(output_file(std::vector<std::string>{".png"}));
  cmd->add_flag("--no-scanpath", o->no_scanpath, "do not draw the scan path");
  cmd->add_flag("-q,--quiet", o->quiet, "print nothing on success");

  return [o] { return run_gaze(*o); };
}

}  // namespace foveal::app
