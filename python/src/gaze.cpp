// python/src/gaze.cpp — foveal._core's gaze part: the recording readers, the fixation filters and
// the live Pupil source, with samples handed over as columns (foveal.gaze makes them one NumPy
// structured array).
#include "bindings.h"

#include "foveal/gaze/fixation.h"
#include "foveal/gaze/recording.h"
#include "foveal/gaze/source.h"
#include "foveal/util/error.h"

#include <nanobind/stl/array.h>
#include <nanobind/stl/optional.h>
#include <nanobind/stl/string.h>
#include <nanobind/stl/unique_ptr.h>
#include <nanobind/stl/vector.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <memory>

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
  std::vector<float> confidence;
  std::vector<uint8_t> valid;
  for (const GazeSample& s : samples) {
    t.push_back(s.t_s);
    x.push_back(s.px.x);
    y.push_back(s.px.y);
    confidence.push_back(s.confidence);
    valid.push_back(s.valid ? 1 : 0);
  }
  nb::dict d;
  d["t_s"] = column(std::move(t));
  d["x"] = column(std::move(x));
  d["y"] = column(std::move(y));
  d["confidence"] = column(std::move(confidence));
  d["valid"] = column(std::move(valid));
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

// A recording rebuilt from columns (what foveal.gaze.fixations is given).
Recording recording_from(const Column& t, const Column& x, const Column& y, const Column& confidence, const Column& valid,
                         std::array<int, 2> screen, const std::optional<Column>& directions) {
  const size_t n = t.shape(0);
  if (directions && directions->shape(0) != 3 * n) fail("directions: expected 3 values per sample");
  if (x.shape(0) != n || y.shape(0) != n || confidence.shape(0) != n || valid.shape(0) != n)
    fail("samples: the columns t_s, x, y, confidence and valid must have the same length");
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
    if (directions) {
      const double* d = directions->data() + 3 * i;
      if (std::isfinite(d[0]) && std::isfinite(d[1]) && std::isfinite(d[2])) s.direction = glm::dvec3(d[0], d[1], d[2]);
    }
  }
  r.block_starts = {0};
  return r;
}

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
         double min_confidence, double time_scale, bool normalised, bool origin_bottom_left, const std::string& fixations_file,
         const std::string& blinks_file, std::array<int, 2> default_screen) {
        ReadOptions o;
        o.format = parse_gaze_format(format);
        o.screen_px = {default_screen[0], default_screen[1]};
        if (screen) {
          if ((*screen)[0] <= 0 || (*screen)[1] <= 0) fail("screen: must be positive pixels, got {}x{}", (*screen)[0], (*screen)[1]);
          o.screen_px = {(*screen)[0], (*screen)[1]};
          o.screen_from_user = true;
        }
        o.eye = parse_eye_selection(eye);
        if (!(min_confidence >= 0 && min_confidence <= 1)) fail("min_confidence: must be in [0, 1], got {}", min_confidence);
        o.min_confidence = static_cast<float>(min_confidence);
        o.csv_time_scale = time_scale;
        o.csv_normalised = normalised;
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
        d["eyes"] = r.eyes;
        d["nominal_rate_hz"] = r.nominal_rate_hz;
        d["rate_hz"] = r.rate_hz();
        d["has_tracker_fixations"] = r.has_tracker_fixations;
        d["block_starts"] = std::vector<size_t>(r.block_starts);
        d["notes"] = r.notes;
        d["warnings"] = r.warnings;
        return d;
      },
      "path"_a, "format"_a, "screen"_a, "eye"_a, "min_confidence"_a, "time_scale"_a, "normalised"_a, "origin_bottom_left"_a,
      "fixations_file"_a, "blinks_file"_a, "default_screen"_a);

  m.def(
      "_fixations",
      [](const Column& t, const Column& x, const Column& y, const Column& confidence, const Column& valid, std::array<int, 2> screen,
         const Display& display, const std::string& method, const nb::dict& params, std::optional<std::vector<size_t>> block_starts,
         std::optional<Column> directions) {
        FixationParams p;
        for (auto [key, value] : params) {
          const std::string k = nb::cast<std::string>(key);
          const double v = nb::cast<double>(value);
          if (k == "velocity_threshold_deg_s")
            p.velocity_threshold_deg_s = v;
          else if (k == "velocity_window_s")
            p.velocity_window_s = v;
          else if (k == "gap_fill_s")
            p.gap_fill_s = v;
          else if (k == "merge_gap_s")
            p.merge_gap_s = v;
          else if (k == "merge_angle_deg")
            p.merge_angle_deg = v;
          else if (k == "min_fixation_s")
            p.min_fixation_s = v;
          else if (k == "median_window")
            p.median_window = static_cast<int>(v);
          else if (k == "dispersion_deg")
            p.dispersion_deg = v;
          else if (k == "min_duration_s")
            p.min_duration_s = v;
          else
            fail(
                "fixations: unknown parameter '{}' (velocity_threshold_deg_s, velocity_window_s, gap_fill_s, merge_gap_s, "
                "merge_angle_deg, min_fixation_s, median_window, dispersion_deg, min_duration_s)",
                k);
        }
        validate(p);
        validate(display);
        const FixationMethod fm = parse_fixation_method(method);
        if (fm == FixationMethod::mean) fail("fixations: 'mean' is a per-frame average, not a fixation filter: use ivt or idt");
        if (fm == FixationMethod::ivvt)
          fail(
              "fixations: 'ivvt' is the causal filter for the fovea (FixationTracker); for offline fixations use ivt or idt, "
              "for pursuit the event detector (foveal gaze RECORDING --events auto)");
        Recording r = recording_from(t, x, y, confidence, valid, screen, directions);
        if (block_starts && !block_starts->empty()) {
          for (size_t b : *block_starts)
            if (b >= r.samples.size() && !r.samples.empty()) fail("fixations: block start {} is past the last sample", b);
          r.block_starts = *block_starts;
        }
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
      "t"_a, "x"_a, "y"_a, "confidence"_a, "valid"_a, "screen"_a, "display"_a, "method"_a, "params"_a, "block_starts"_a = nb::none(),
      "directions"_a = nb::none());

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
