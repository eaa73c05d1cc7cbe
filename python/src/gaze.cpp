// python/src/gaze.cpp — foveal._core's gaze part: the recording readers, the fixation filters and
// the live Pupil source, with samples handed over as columns (foveal.gaze makes them one NumPy
// structured array).
#include "bindings.h"

#include "foveal/gaze/detect.h"
#include "foveal/gaze/fixation.h"
#include "foveal/gaze/landing.h"
#include "foveal/gaze/recording.h"
#include "foveal/gaze/source.h"
#include "foveal/util/error.h"
#include "foveal/util/files.h"
#include "foveal/util/gzip.h"
#include "foveal/util/stats.h"

#include <nanobind/stl/array.h>
#include <nanobind/stl/optional.h>
#include <nanobind/stl/string.h>
#include <nanobind/stl/unique_ptr.h>
#include <nanobind/stl/vector.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <iterator>
#include <memory>
#include <utility>

namespace foveal::python {

namespace {

template <class T>
nb::ndarray<nb::numpy, T> column(std::vector<T>&& values) {
  auto* data = new std::vector<T>(std::move(values));
  nb::capsule owner(data, [](void* p) noexcept { delete static_cast<std::vector<T>*>(p); });
  return nb::ndarray<nb::numpy, T>(data->data(), {data->size()}, owner);
}

// Samples as columns: t_s, x, y, confidence, valid.
nb::dict sample_columns(const std::vector<GazeSample>& samples) {
  std::vector<double> t, x, y;
  std::vector<float> confidence, pupil;
  std::vector<uint8_t> valid;
  for (const GazeSample& s : samples) {
    t.push_back(s.t_s);
    x.push_back(s.px.x);
    y.push_back(s.px.y);
    confidence.push_back(s.confidence);
    valid.push_back(s.valid ? 1 : 0);
    pupil.push_back(s.pupil);
  }
  nb::dict d;
  d["t_s"] = column(std::move(t));
  d["x"] = column(std::move(x));
  d["y"] = column(std::move(y));
  d["confidence"] = column(std::move(confidence));
  d["valid"] = column(std::move(valid));
  d["pupil"] = column(std::move(pupil));
  return d;
}

nb::dict event_columns(const std::vector<GazeEvent>& events) {
  std::vector<double> start, end, x, y;
  for (const GazeEvent& e : events) {
    start.push_back(e.start_s);
    end.push_back(e.end_s);
    x.push_back(e.px.x);
    y.push_back(e.px.y);
  }
  nb::dict d;
  d["start_s"] = column(std::move(start));
  d["end_s"] = column(std::move(end));
  d["x"] = column(std::move(x));
  d["y"] = column(std::move(y));
  return d;
}

using Column = nb::ndarray<const double, nb::ndim<1>, nb::c_contig, nb::device::cpu>;

}  // namespace

// A recording rebuilt from the columns foveal.gaze hands over (gaze.py's _columns): t_s, x, y,
// confidence, valid, pupil (float64 arrays of one length), screen (W, H), and optionally
// directions (3 per sample) and block_starts.
Recording recording_from(const nb::dict& columns) {
  auto get = [&](const char* name) { return nb::cast<Column>(columns[name]); };
  const Column t = get("t_s"), x = get("x"), y = get("y"), confidence = get("confidence"), valid = get("valid"), pupil = get("pupil");
  const auto screen = nb::cast<std::array<int, 2>>(columns["screen"]);
  std::optional<Column> directions;
  if (columns.contains("directions") && !columns["directions"].is_none()) directions = get("directions");
  const size_t n = t.shape(0);
  if (directions && directions->shape(0) != 3 * n) fail("directions: expected 3 values per sample");
  if (x.shape(0) != n || y.shape(0) != n || confidence.shape(0) != n || valid.shape(0) != n || pupil.shape(0) != n)
    fail("samples: the columns t_s, x, y, confidence, valid and pupil must have the same length");
  if (screen[0] <= 0 || screen[1] <= 0) fail("screen: must be positive pixels, got {}x{}", screen[0], screen[1]);
  Recording r;
  r.source = "samples";
  r.screen_px = {screen[0], screen[1]};
  r.samples.resize(n);
  for (size_t i = 0; i < n; ++i) {
    GazeSample& s = r.samples[i];
    s.t_s = t.data()[i];
    if (!std::isfinite(s.t_s)) fail("samples: t_s[{}] is not a finite time", i);
    if (i > 0 && s.t_s < r.samples[i - 1].t_s) fail("samples: t_s[{}] = {} goes back in time (after {})", i, s.t_s, r.samples[i - 1].t_s);
    s.px = {x.data()[i], y.data()[i]};
    s.confidence = static_cast<float>(confidence.data()[i]);
    s.valid = valid.data()[i] != 0 && std::isfinite(s.px.x) && std::isfinite(s.px.y);
    s.pupil = static_cast<float>(pupil.data()[i]);
    if (directions) {
      const double* d = directions->data() + 3 * i;
      if (std::isfinite(d[0]) && std::isfinite(d[1]) && std::isfinite(d[2])) s.direction = glm::dvec3(d[0], d[1], d[2]);
    }
  }
  // The tracker's own fixations (for fixation='tracker')
  if (columns.contains("fixations") && !columns["fixations"].is_none()) {
    const nb::dict f = nb::cast<nb::dict>(columns["fixations"]);
    const Column start = nb::cast<Column>(f["start_s"]), end = nb::cast<Column>(f["end_s"]), fx = nb::cast<Column>(f["x"]),
                 fy = nb::cast<Column>(f["y"]);
    if (end.shape(0) != start.shape(0) || fx.shape(0) != start.shape(0) || fy.shape(0) != start.shape(0))
      fail("fixations: the columns start_s, end_s, x and y must have the same length");
    for (size_t i = 0; i < start.shape(0); ++i) r.fixations.push_back({start.data()[i], end.data()[i], {fx.data()[i], fy.data()[i]}});
    r.has_tracker_fixations = nb::cast<bool>(columns["has_tracker_fixations"]);
    r.tracker = nb::cast<std::string>(columns["tracker"]);
  }
  r.block_starts = {0};
  if (columns.contains("block_starts") && !columns["block_starts"].is_none()) {
    const auto blocks = nb::cast<std::vector<size_t>>(columns["block_starts"]);
    for (size_t b : blocks)
      if (b >= n && n > 0) fail("samples: block start {} is past the last sample", b);
    if (!blocks.empty()) r.block_starts = blocks;
  }
  return r;
}

LandingParams landing_params(const nb::dict& params, LandingParams p) {
  for (auto [key, value] : params) {
    const std::string k = nb::cast<std::string>(key);
    double v = 0;  // (a NumPy scalar is a number too; a bool or a string is not)
    if (nb::isinstance<nb::bool_>(value) || nb::isinstance<nb::str>(value) || !nb::try_cast<double>(value, v))
      fail("{}: expected a number, got {}", k, nb::cast<std::string>(nb::str(value.type().attr("__name__"))));
    set_landing_parameter(p, k, v);
  }
  validate(p);
  return p;
}

LandingParams landing_params_of(const nb::handle& landing) {
  if (landing.is_none()) return {};
  if (nb::isinstance<nb::str>(landing)) return parse_landing_params(nb::cast<std::string>(landing));
  if (nb::isinstance<nb::dict>(landing)) return landing_params(nb::borrow<nb::dict>(landing));
  throw nb::type_error(fmt::format("landing: expected a dict of the landing predictor's parameters or their text "
                                   "('NAME=VALUE,…', as --landing), got {}",
                                   nb::cast<std::string>(nb::str(landing.type().attr("__name__"))))
                           .c_str());
}

// The filters' and detectors' parameters by keyword (seconds and degrees, as the library's fields).
void set_parameters(const nb::dict& params, FixationParams& f, EventParams* e) {
  for (auto [key, value] : params) {
    const std::string k = nb::cast<std::string>(key);
    const double v = nb::cast<double>(value);
    if (k == "velocity_threshold_deg_s")
      f.velocity_threshold_deg_s = v;
    else if (k == "velocity_window_s")
      f.velocity_window_s = v;
    else if (k == "gap_fill_s")
      f.gap_fill_s = v;
    else if (k == "merge_gap_s")
      f.merge_gap_s = v;
    else if (k == "merge_angle_deg")
      f.merge_angle_deg = v;
    else if (k == "min_fixation_s")
      f.min_fixation_s = v;
    else if (k == "median_window")
      f.median_window = static_cast<int>(v);
    else if (k == "dispersion_deg")
      f.dispersion_deg = v;
    else if (k == "min_duration_s")
      f.min_duration_s = v;
    else if (k == "pursuit_velocity_deg_s")
      f.pursuit.velocity_deg_s = v;
    else if (k == "pursuit_window_s")
      f.pursuit.window_s = v;
    else if (k == "min_pursuit_s")
      f.pursuit.min_s = v;
    else if (e && k == "filter_window_s")
      e->filter_window_s = e->robust_filter_window_s = v;
    else if (e && k == "detection_window_s")
      e->detection_window_s = v;
    else if (e && k == "ek_lambda")
      e->ek_lambda = v;
    else if (e && k == "blink_flank_s")
      e->blink_flank_s = v;
    else if (e && k == "max_blink_s")
      e->max_blink_s = v;
    else
      fail("params: unknown parameter '{}'", k);
  }
  validate(f);
  if (e) {
    e->pursuit = f.pursuit;
    validate(*e);
  }
}

namespace {

struct PyPupilSource {
  std::unique_ptr<PupilSource> source;
  PupilSource& open() const {
    if (!source) fail("PupilSource: the source is closed");
    return *source;
  }
};

}  // namespace

void bind_gaze(nb::module_& m) {
  m.def(
      "_read_recording",
      [](const std::string& path, const std::string& format, std::optional<std::array<int, 2>> screen, const std::string& eye,
         double min_confidence, double time_scale, const std::string& coords, bool origin_bottom_left, const std::string& fixations_file,
         const std::string& blinks_file, const Display& display) {
        ReadOptions o;
        o.format = parse_gaze_format(format);
        validate(display);
        o.screen_px = {display.res_x, display.res_y};
        o.display_width_cm = display.width_cm;
        o.display_height_cm = display.height_cm;
        o.display_distance_cm = display.distance_cm;
        if (screen) {
          if ((*screen)[0] <= 0 || (*screen)[1] <= 0) fail("screen: must be positive pixels, got {}x{}", (*screen)[0], (*screen)[1]);
          o.screen_px = {(*screen)[0], (*screen)[1]};
          o.screen_from_user = true;
        }
        o.eye = parse_eye_selection(eye);
        if (!(min_confidence >= 0 && min_confidence <= 1)) fail("min_confidence: must be in [0, 1], got {}", min_confidence);
        o.min_confidence = static_cast<float>(min_confidence);
        o.csv_time_scale = time_scale;
        if (coords != "px" && coords != "norm" && coords != "deg") fail("coords: expected px, norm or deg, got '{}'", coords);
        o.csv_normalised = coords == "norm";
        o.csv_degrees = coords == "deg";
        o.csv_origin_bottom_left = origin_bottom_left;
        o.fixations_file = fixations_file;
        o.blinks_file = blinks_file;
        Recording r;
        {
          nb::gil_scoped_release release;
          r = read_recording(path, o);
        }
        nb::dict d;
        d["samples"] = sample_columns(r.samples);
        // The tracker's 3-D gaze directions where it gives them (Pupil's gaze_point_3d): the filters use them
        std::vector<double> directions;
        const bool any_direction =
            std::any_of(r.samples.begin(), r.samples.end(), [](const GazeSample& s) { return s.direction.has_value(); });
        if (any_direction)
          for (const GazeSample& s : r.samples)
            for (int k = 0; k < 3; ++k) directions.push_back(s.direction ? (*s.direction)[k] : NAN);
        d["directions"] = any_direction ? nb::cast(column(std::move(directions))) : nb::none();
        d["fixations"] = event_columns(r.fixations);
        d["blinks"] = event_columns(r.blinks);
        d["source"] = r.source;
        d["format"] = std::string(to_string(r.format));
        d["tracker"] = r.tracker;
        d["screen"] = nb::make_tuple(r.screen_px.x, r.screen_px.y);
        d["screen_cm"] = r.screen_cm ? nb::object(nb::make_tuple(r.screen_cm->x, r.screen_cm->y, r.screen_cm->z)) : nb::none();
        d["eyes"] = r.eyes;
        d["nominal_rate_hz"] = r.nominal_rate_hz;
        d["rate_hz"] = r.rate_hz();
        d["has_tracker_fixations"] = r.has_tracker_fixations;
        d["block_starts"] = std::vector<size_t>(r.block_starts);
        d["notes"] = r.notes;
        d["warnings"] = r.warnings;
        return d;
      },
      "path"_a, "format"_a, "screen"_a, "eye"_a, "min_confidence"_a, "time_scale"_a, "coords"_a, "origin_bottom_left"_a, "fixations_file"_a,
      "blinks_file"_a, "display"_a);

  m.def(
      "_fixations",
      [](const nb::dict& columns, const Display& display, const std::string& method, const nb::dict& params) {
        FixationParams p;
        set_parameters(params, p, nullptr);
        validate(display);
        const FixationMethod fm = parse_fixation_method(method);
        if (fm == FixationMethod::mean) fail("method: 'mean' is a per-frame average, not a fixation filter: use ivt or idt");
        if (fm == FixationMethod::ivvt)
          fail(
              "method: 'ivvt' is the causal filter for the fovea (FixationTracker); for offline fixations use ivt or idt, "
              "for pursuit the event detectors (foveal.gaze.events(recording, method='auto'))");
        const Recording r = recording_from(columns);
        FixationResult result;
        {
          nb::gil_scoped_release release;
          const GazeGeometry geometry(display, r.screen_px);
          result = fm == FixationMethod::idt ? detect_idt(r, geometry, p) : detect_ivt(r, geometry, p);
        }
        // The fixations as events (start, end, centre), with their first and last sample
        std::vector<GazeEvent> events;
        std::vector<int64_t> first, last;
        for (const Fixation& f : result.fixations) {
          events.push_back({f.start_s, f.end_s, f.px});
          first.push_back(static_cast<int64_t>(f.first));
          last.push_back(static_cast<int64_t>(f.last));
        }
        nb::dict d = event_columns(events);
        d["first"] = column(std::move(first));
        d["last"] = column(std::move(last));
        std::vector<int32_t> label(result.label.begin(), result.label.end());
        d["label"] = column(std::move(label));
        return d;
      },
      "columns"_a, "display"_a, "method"_a, "params"_a);

  m.def(
      "_events",
      [](const nb::dict& columns, const Display& display, const std::string& method, const nb::dict& params) {
        FixationParams fp;
        EventParams ep;
        set_parameters(params, fp, &ep);
        validate(display);
        const EventMethod em = parse_event_method(method);
        const Recording r = recording_from(columns);
        EventDetection d;
        std::string tsv, landings_text;
        std::vector<LandingReport> landings;
        {
          nb::gil_scoped_release release;
          const GazeGeometry geometry(display, r.screen_px);
          d = detect_events(r, geometry, em, ep, fp);
          tsv = events_tsv(d, r);
          landings = evaluate_landings(r, geometry, d);  // as gaze --events does (--landings-out)
          landings_text = landings_tsv(landings);
        }
        std::vector<uint8_t> labels(d.labels.size());
        for (size_t i = 0; i < labels.size(); ++i) labels[i] = static_cast<uint8_t>(d.labels[i]);
        // The events as columns, one per field
        nb::dict table;
        auto add = [&](const char* name, auto field) {
          std::vector<decltype(field(DetectedEvent{}))> values;
          for (const DetectedEvent& e : d.events) values.push_back(field(e));
          table[name] = column(std::move(values));
        };
        add("label", [](const DetectedEvent& e) { return static_cast<uint8_t>(e.label); });
        add("first", [](const DetectedEvent& e) { return static_cast<int64_t>(e.first); });
        add("last", [](const DetectedEvent& e) { return static_cast<int64_t>(e.last); });
        add("onset_s", [](const DetectedEvent& e) { return e.onset_s; });
        add("duration_s", [](const DetectedEvent& e) { return e.duration_s; });
        add("amplitude_deg", [](const DetectedEvent& e) { return e.amplitude_deg; });
        add("peak_velocity_deg_s", [](const DetectedEvent& e) { return e.peak_velocity_deg_s; });
        add("start_x_deg", [](const DetectedEvent& e) { return e.start_deg.x; });
        add("start_y_deg", [](const DetectedEvent& e) { return e.start_deg.y; });
        add("end_x_deg", [](const DetectedEvent& e) { return e.end_deg.x; });
        add("end_y_deg", [](const DetectedEvent& e) { return e.end_deg.y; });
        nb::dict out;
        out["labels"] = column(std::move(labels));
        out["table"] = table;
        out["velocity_deg_s"] = column(std::vector<float>(d.velocity_deg_s));
        out["method"] = std::string(to_string(em));
        out["sampling_hz"] = d.sampling_hz;
        out["peak_threshold_deg_s"] = d.peak_threshold_deg_s;
        out["onset_threshold_deg_s"] = d.onset_threshold_deg_s;
        out["tsv"] = tsv;
        // Each saccade's landing as the live predictor saw it (gaze/landing.h), one column per field
        nb::dict landing_table;
        auto add_landing = [&](const char* name, auto field) {
          std::vector<decltype(field(LandingReport{}))> values;
          for (const LandingReport& l : landings) values.push_back(field(l));
          landing_table[name] = column(std::move(values));
        };
        add_landing("event", [](const LandingReport& l) { return static_cast<int64_t>(l.event); });
        add_landing("onset_s", [](const LandingReport& l) { return l.onset_s; });
        add_landing("landing_s", [](const LandingReport& l) { return l.landing_s; });
        add_landing("amplitude_deg", [](const LandingReport& l) { return l.amplitude_deg; });
        add_landing("end_x_deg", [](const LandingReport& l) { return l.landing_deg.x; });
        add_landing("end_y_deg", [](const LandingReport& l) { return l.landing_deg.y; });
        add_landing("predicted", [](const LandingReport& l) { return static_cast<uint8_t>(l.predicted); });
        add_landing("predicted_x_deg", [](const LandingReport& l) { return l.first_deg.x; });
        add_landing("predicted_y_deg", [](const LandingReport& l) { return l.first_deg.y; });
        add_landing("error_deg", [](const LandingReport& l) { return l.first_error_deg; });
        add_landing("two_thirds_x_deg", [](const LandingReport& l) { return l.two_thirds_deg.x; });
        add_landing("two_thirds_y_deg", [](const LandingReport& l) { return l.two_thirds_deg.y; });
        add_landing("two_thirds_error_deg", [](const LandingReport& l) { return l.two_thirds_error_deg; });
        add_landing("gained_ms", [](const LandingReport& l) { return l.gained_ms; });
        out["landings"] = landing_table;
        out["landings_tsv"] = landings_text;
        return out;
      },
      "columns"_a, "display"_a, "method"_a, "params"_a);

  // The live landing predictor (gaze/landing.h) over a whole stream: every saccade it saw land, with
  // each prediction of its flight
  m.def(
      "_predict_landings",
      [](const Column& t, const Column& x, const Column& y, const nb::dict& params) {
        const size_t n = t.shape(0);
        if (x.shape(0) != n || y.shape(0) != n) fail("deg: {} and {} positions for {} times", x.shape(0), y.shape(0), n);
        const LandingParams p = landing_params(params);
        std::vector<double> times(t.data(), t.data() + n);
        std::vector<glm::dvec2> deg(n);
        for (size_t i = 0; i < n; ++i) {
          if (!std::isfinite(times[i])) fail("t_s: t_s[{}] = {} is no time", i, times[i]);
          if (i > 0 && !(times[i] > times[i - 1])) fail("t_s: must rise, but t_s[{}] = {} follows {}", i, times[i], times[i - 1]);
          deg[i] = {x.data()[i], y.data()[i]};
        }
        // Samples under 20 Hz show no saccade: the predictor would return nothing, without a word,
        // most often for times in milliseconds (an EyeLink's clock) where seconds are asked.
        if (n >= 3) {
          std::vector<double> intervals(n - 1);
          for (size_t i = 1; i < n; ++i) intervals[i - 1] = times[i] - times[i - 1];
          const double interval = median(std::move(intervals));
          if (const std::string unseen = unseen_saccades_note(interval, "predict_landings"); !unseen.empty())
            fail("t_s: samples come {:.3g} s apart (median): {}", interval, unseen);
        }
        std::vector<PredictedSaccade> flights;
        {
          nb::gil_scoped_release release;
          flights = predict_landings(times, deg, p);
        }
        nb::list out;
        for (PredictedSaccade& f : flights) {
          nb::dict d;
          d["onset_s"] = f.onset_s;
          d["detected_s"] = f.detected_s;
          d["first_prediction_s"] = f.first_prediction_s;
          d["first_landing_deg"] = nb::make_tuple(f.first_landing_deg.x, f.first_landing_deg.y);
          d["settled_s"] = f.settled_s;
          d["landing_s"] = f.landing_s;
          d["landing_deg"] = nb::make_tuple(f.landing_deg.x, f.landing_deg.y);
          d["amplitude_deg"] = f.amplitude_deg;
          std::vector<double> px, py;
          for (const glm::dvec2& q : f.prediction_deg) {
            px.push_back(q.x);
            py.push_back(q.y);
          }
          d["prediction_s"] = column(std::move(f.prediction_s));
          d["prediction_x_deg"] = column(std::move(px));
          d["prediction_y_deg"] = column(std::move(py));
          out.append(d);
        }
        return out;
      },
      "t_s"_a, "x_deg"_a, "y_deg"_a, "params"_a);

  // Every parameter of the landing predictor: the defaults, `text`'s (as --landing) and `params`
  // over them, checked
  m.def(
      "_landing_params",
      [](const std::string& text, const nb::dict& params) {
        nb::dict out;
        for (const auto& [name, value] : landing_parameters(landing_params(params, parse_landing_params(text)))) out[name.c_str()] = value;
        return out;
      },
      "text"_a, "params"_a);

  // The Python writers' one path: every writer's rules (never over an input or a read-only file;
  // an existing file replaced only once the new one is whole)
  m.def(
      "_write_text", [](const std::string& path, const std::string& text) { write_file_atomically(path, text, false); }, "path"_a,
      "text"_a);
  // … and the check every command makes before its work (util/files.h: the folder exists, the path
  // is no folder and may be written, read-only refused)
  m.def(
      "_check_output_file", [](const std::string& path) { check_output_file(path); }, "path"_a);

  m.def(
      "_evaluate",
      [](const nb::ndarray<const uint8_t, nb::ndim<1>, nb::c_contig, nb::device::cpu>& labels, const Column& t, const nb::object& coder,
         const nb::object& coder2) {
        const size_t n = labels.shape(0);
        if (t.shape(0) != n) fail("t_s: {} times for {} labels", t.shape(0), n);
        std::vector<EventLabel> test(n);
        std::vector<double> times(t.data(), t.data() + n);
        for (size_t i = 0; i < n; ++i) {
          if (labels.data()[i] > static_cast<uint8_t>(EventLabel::blink))
            fail("labels: labels[{}] = {} is no label (0–5)", i, labels.data()[i]);
          test[i] = static_cast<EventLabel>(labels.data()[i]);
        }
        // A coder: a label file's path, or its labels of these samples (codes 0–5)
        auto coder_file = [&](const nb::object& c, const char* name) {
          if (nb::isinstance<nb::str>(c)) return read_label_file(nb::cast<std::string>(c));
          const auto a = nb::cast<nb::ndarray<const uint8_t, nb::ndim<1>, nb::c_contig, nb::device::cpu>>(c);
          if (a.shape(0) != n) fail("{}: {} labels for {} samples", name, a.shape(0), n);
          LabelFile f;
          f.name = name;
          f.t_s = times;
          for (size_t i = 0; i < n; ++i) {
            if (a.data()[i] > static_cast<uint8_t>(EventLabel::blink))
              fail("{}: {}[{}] = {} is no label (0–5)", name, name, i, a.data()[i]);
            f.label.push_back(static_cast<EventLabel>(a.data()[i]));
            f.line.push_back(i);
          }
          return f;
        };
        std::optional<LabelFile> second;
        if (!coder2.is_none()) second = coder_file(coder2, "coder2");
        const CoderEvaluation e = evaluate_against_coders(test, times, coder_file(coder, "coder"), second);
        nlohmann::json j = evaluation_json(e.evaluation);
        if (e.second) j["coder2"] = evaluation_json(*e.second);
        if (e.ceiling) j["ceiling"] = evaluation_json(*e.ceiling);
        j["matching"] = "Hooge et al. 2018: earliest overlapping event of the same class";
        return to_python(j);
      },
      "labels"_a, "t_s"_a, "coder"_a, "coder2"_a = nb::none());

  nb::class_<PyPupilSource>(m, "_PupilSource")
      .def(
          "__init__",
          [](PyPupilSource* s, const std::string& url, std::array<int, 2> screen, double min_confidence) {
            if (screen[0] <= 0 || screen[1] <= 0) fail("screen: must be positive pixels, got {}x{}", screen[0], screen[1]);
            std::unique_ptr<PupilSource> source;
            {
              nb::gil_scoped_release release;
              source = std::make_unique<PupilSource>(url, glm::ivec2(screen[0], screen[1]), static_cast<float>(min_confidence));
            }
            new (s) PyPupilSource{std::move(source)};
          },
          "url"_a, "screen"_a, "min_confidence"_a)
      .def("poll",
           [](PyPupilSource& s) {
             std::vector<GazeSample> samples;
             s.open().poll(samples);
             return sample_columns(samples);
           })
      .def_prop_ro("state", [](const PyPupilSource& s) { return std::string(to_string(s.open().state())); })
      .def_prop_ro("silent_s", [](const PyPupilSource& s) { return s.open().silent_s(); })
      .def_prop_ro("received", [](const PyPupilSource& s) { return s.open().received(); })
      .def_prop_ro("malformed", [](const PyPupilSource& s) { return s.open().malformed(); })
      .def_prop_ro("name", [](const PyPupilSource& s) { return s.open().name(); })
      .def("close", [](PyPupilSource& s) { s.source.reset(); });
}

}  // namespace foveal::python
