// foveal/gaze/events.cpp — labels, runs, the expert-label reader and the evaluation (see events.h).
#include "foveal/gaze/events.h"

#include "foveal/util/text.h"
#include "foveal/util/error.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace foveal {

const char* to_string(EventLabel label) {
  switch (label) {
    case EventLabel::fixation:
      return "fixation";
    case EventLabel::saccade:
      return "saccade";
    case EventLabel::pso:
      return "pso";
    case EventLabel::pursuit:
      return "pursuit";
    case EventLabel::blink:
      return "blink";
    default:
      return "undefined";
  }
}

std::optional<EventLabel> parse_event_label(std::string_view text) {
  text = text::trim(text);
  for (EventLabel l :
       {EventLabel::undefined, EventLabel::fixation, EventLabel::saccade, EventLabel::pso, EventLabel::pursuit, EventLabel::blink})
    if (text == to_string(l)) return l;
  if (const auto v = text::to_number(text); v && *v == std::floor(*v) && *v >= 0 && *v <= 5) return static_cast<EventLabel>(*v);
  return std::nullopt;
}

std::vector<LabelledEvent> label_runs(const std::vector<EventLabel>& labels, const std::vector<double>& t) {
  if (labels.size() != t.size()) fail("label_runs: {} labels for {} sample times", labels.size(), t.size());
  std::vector<LabelledEvent> runs;
  for (size_t i = 0; i < labels.size(); ++i) {
    if (runs.empty() || runs.back().label != labels[i]) runs.push_back({labels[i], i, i, t[i], t[i]});
    runs.back().last = i;
    runs.back().offset_s = t[i];
  }
  return runs;
}

std::vector<EventLabel> labels_from_fixations(const Recording& r, const FixationResult& f) {
  std::vector<EventLabel> out(r.samples.size(), EventLabel::saccade);
  for (size_t i = 0; i < out.size(); ++i) {
    if (!r.samples[i].valid) out[i] = EventLabel::blink;
    if (i < f.label.size() && f.label[i] >= 0) out[i] = EventLabel::fixation;
  }
  return out;
}

LabelFile parse_label_file(const std::string& content, const std::string& name) {
  if (text::has_bom(content)) return parse_label_file(content.substr(3), name);
  text::Lines lines(content);
  std::string_view line;
  int c_t = -1, c_label = -1;
  size_t columns = 0;
  LabelFile out;
  out.name = name;
  while (lines.next(line)) {
    if (text::trim(line).empty()) continue;
    const auto f = text::split(line, ',');
    if (columns == 0) {
      for (size_t i = 0; i < f.size(); ++i) {
        const std::string_view col = text::trim(f[i]);
        if (col == "t" || col == "t_s" || col == "time") c_t = static_cast<int>(i);
        if (col == "label") c_label = static_cast<int>(i);
      }
      if (c_t < 0 || c_label < 0) fail("{}:{}: the header needs a time column (t, t_s or time) and a label column", name, lines.number());
      columns = f.size();
      continue;
    }
    if (f.size() != columns) fail("{}:{}: {} fields, expected {}", name, lines.number(), f.size(), columns);
    const auto t = text::to_number(f[c_t]);
    if (!t) fail("{}:{}: time '{}' is not a number", name, lines.number(), text::trim(f[c_t]));
    if (!out.t_s.empty() && *t < out.t_s.back()) fail("{}:{}: time goes back ({} after {})", name, lines.number(), *t, out.t_s.back());
    const auto label = parse_event_label(f[c_label]);
    if (!label)
      fail("{}:{}: unknown label '{}' (fixation, saccade, pso, pursuit, blink, undefined, or 0-5)", name, lines.number(),
           text::trim(f[c_label]));
    out.t_s.push_back(*t);
    out.label.push_back(*label);
    out.line.push_back(lines.number());
  }
  if (out.label.empty()) fail("{}: no labelled samples", name);
  return out;
}

LabelFile read_label_file(const std::string& path) { return parse_label_file(text::read_file(path), path); }

AlignedLabels align_labels(const LabelFile& file, const std::vector<double>& t) {
  AlignedLabels out;
  out.label.assign(t.size(), EventLabel::undefined);
  out.covered.assign(t.size(), false);
  // A quarter of the median interval (of at most 4096 evenly spread intervals)
  std::vector<double> intervals;
  for (size_t i = 1; i < t.size(); i += 1 + t.size() / 4096)
    if (t[i] > t[i - 1]) intervals.push_back(t[i] - t[i - 1]);
  double tolerance = 0;
  if (!intervals.empty()) {
    std::nth_element(intervals.begin(), intervals.begin() + intervals.size() / 2, intervals.end());
    tolerance = 0.25 * intervals[intervals.size() / 2];
  }
  tolerance = std::max(tolerance, 1e-9);
  size_t i = 0;
  for (size_t j = 0; j < file.label.size(); ++j) {
    const double tj = file.t_s[j];
    const size_t line = j < file.line.size() ? file.line[j] : j + 2;
    while (i < t.size() && t[i] < tj - tolerance) ++i;
    if (i == t.size() || std::abs(t[i] - tj) > tolerance)
      fail(
          "{}:{}: the label at t = {:.6g} s matches no sample of the recording (its samples run from {:.6g} to {:.6g} s): "
          "the labels must be of this recording's samples, on the same clock",
          file.name, line, tj, t.empty() ? NAN : t.front(), t.empty() ? NAN : t.back());
    if (out.covered[i]) fail("{}:{}: a second label for the sample at t = {:.6g} s", file.name, line, t[i]);
    out.covered[i] = true;
    out.label[i] = file.label[j];
    ++out.count;
  }
  return out;
}

const ClassScore& Evaluation::of(EventLabel label) const {
  for (const ClassScore& c : classes)
    if (c.label == label) return c;
  fail("evaluation: no score for '{}'", to_string(label));
}

namespace {

// Cohen's kappa from a confusion matrix (rows: test, columns: reference).
template <size_t N>
double cohen_kappa(const std::array<std::array<double, N>, N>& m) {
  double total = 0, agree = 0, chance = 0;
  std::array<double, N> rows{}, cols{};
  for (size_t i = 0; i < N; ++i)
    for (size_t j = 0; j < N; ++j) {
      total += m[i][j];
      rows[i] += m[i][j];
      cols[j] += m[i][j];
    }
  if (total == 0) return std::numeric_limits<double>::quiet_NaN();
  for (size_t i = 0; i < N; ++i) {
    agree += m[i][i];
    chance += rows[i] * cols[i];
  }
  agree /= total;
  chance /= total * total;
  return chance < 1 ? (agree - chance) / (1 - chance) : (agree == 1 ? 1.0 : std::numeric_limits<double>::quiet_NaN());
}

}  // namespace

Evaluation evaluate_labels(const std::vector<EventLabel>& test, const std::vector<EventLabel>& reference, const std::vector<double>& t) {
  if (test.size() != reference.size() || test.size() != t.size())
    fail("evaluate: {} labels against {} reference labels ({} sample times): the streams must cover the same samples", test.size(),
         reference.size(), t.size());
  Evaluation e;
  e.samples = test.size();
  std::array<std::array<double, 6>, 6> all{};
  for (size_t i = 0; i < test.size(); ++i) all[static_cast<size_t>(test[i])][static_cast<size_t>(reference[i])] += 1;
  e.kappa = cohen_kappa(all);
  double same = 0;
  for (size_t k = 0; k < 6; ++k) same += all[k][k];
  e.accuracy = e.samples ? same / e.samples : 0;
  const std::vector<LabelledEvent> test_events = label_runs(test, t), reference_events = label_runs(reference, t);
  for (EventLabel c : kEventClasses) {
    ClassScore s;
    s.label = c;
    std::array<std::array<double, 2>, 2> m{};
    for (size_t i = 0; i < test.size(); ++i) {
      const bool a = test[i] == c, b = reference[i] == c;
      s.test_samples += a;
      s.reference_samples += b;
      m[a][b] += 1;
    }
    s.kappa = s.test_samples + s.reference_samples > 0 ? cohen_kappa(m) : std::numeric_limits<double>::quiet_NaN();
    // Events of this class in each stream, and Hooge et al.'s earliest-overlap matching
    std::vector<const LabelledEvent*> te, re;
    for (const LabelledEvent& ev : test_events)
      if (ev.label == c) te.push_back(&ev);
    for (const LabelledEvent& ev : reference_events)
      if (ev.label == c) re.push_back(&ev);
    s.test_events = te.size();
    s.reference_events = re.size();
    std::vector<bool> used(te.size(), false);
    size_t start = 0;  // test events ending before the current reference event can match no later one
    double rto = 0, rtd = 0;
    for (const LabelledEvent* r : re) {
      while (start < te.size() && te[start]->last < r->first) ++start;
      for (size_t k = start; k < te.size() && te[k]->first <= r->last; ++k)
        if (!used[k] && te[k]->last >= r->first) {  // overlaps
          used[k] = true;
          ++s.hits;
          rto += te[k]->onset_s - r->onset_s;
          rtd += te[k]->duration_s() - r->duration_s();
          break;
        }
    }
    s.misses = s.reference_events - s.hits;
    s.false_alarms = s.test_events - s.hits;
    const double denominator = 2.0 * s.hits + s.misses + s.false_alarms;
    s.f1 = denominator > 0 ? 2.0 * s.hits / denominator : std::numeric_limits<double>::quiet_NaN();
    s.rto_ms = s.hits ? 1000 * rto / s.hits : 0;
    s.rtd_ms = s.hits ? 1000 * rtd / s.hits : 0;
    e.classes.push_back(s);
  }
  return e;
}

Evaluation evaluate_labels(const std::vector<EventLabel>& test, const std::vector<EventLabel>& reference, const std::vector<double>& t,
                           const std::vector<bool>& scored) {
  if (scored.size() != t.size() || test.size() != t.size() || reference.size() != t.size())
    fail("evaluate: {} labels against {} reference labels ({} sample times, {} scored flags): the streams must cover the same samples",
         test.size(), reference.size(), t.size(), scored.size());
  if (std::all_of(scored.begin(), scored.end(), [](bool b) { return b; })) return evaluate_labels(test, reference, t);
  std::vector<EventLabel> a, b;
  std::vector<double> u;
  for (size_t i = 0; i < t.size(); ++i)
    if (scored[i]) {
      a.push_back(test[i]);
      b.push_back(reference[i]);
      u.push_back(t[i]);
    }
  return evaluate_labels(a, b, u);
}

CoderEvaluation evaluate_against_coders(const std::vector<EventLabel>& test, const std::vector<double>& t_s, const LabelFile& coder,
                                        const std::optional<LabelFile>& coder2) {
  if (test.size() != t_s.size()) fail("labels: {} labels for {} samples", test.size(), t_s.size());
  const AlignedLabels expert = align_labels(coder, t_s);
  std::vector<bool> scored = expert.covered;
  std::optional<AlignedLabels> second;
  if (coder2) {
    second = align_labels(*coder2, t_s);
    for (size_t i = 0; i < scored.size(); ++i) scored[i] = scored[i] && second->covered[i];
  }
  CoderEvaluation out{evaluate_labels(test, expert.label, t_s, scored), std::nullopt, std::nullopt};
  if (second) {
    out.second = evaluate_labels(test, second->label, t_s, scored);
    out.ceiling = evaluate_labels(second->label, expert.label, t_s, scored);
  }
  return out;
}

nlohmann::json evaluation_json(const Evaluation& e) {
  auto number = [](double v) { return std::isfinite(v) ? nlohmann::json(v) : nlohmann::json(nullptr); };
  nlohmann::json classes = nlohmann::json::object();
  for (const ClassScore& c : e.classes)
    classes[to_string(c.label)] = {{"kappa", number(c.kappa)},
                                   {"f1", number(c.f1)},
                                   {"hits", c.hits},
                                   {"misses", c.misses},
                                   {"false_alarms", c.false_alarms},
                                   {"reference_events", c.reference_events},
                                   {"test_events", c.test_events},
                                   {"rto_ms", c.rto_ms},
                                   {"rtd_ms", c.rtd_ms}};
  return nlohmann::json{{"samples", e.samples}, {"kappa", number(e.kappa)}, {"accuracy", e.accuracy}, {"classes", classes}};
}

}  // namespace foveal
