// foveal/gaze/events.h — eye-movement events per sample, and their evaluation against expert labels.
//
// Labels per sample (fixation, saccade, PSO, pursuit, blink, undefined), events as runs of one
// label, and the two scores the field uses to judge a detector against human coders:
//   - sample level: Cohen's kappa of each class against the rest, and over all classes;
//   - event level: F1 with the matching rule of Hooge, Niehorster, Nyström, Andersson & Hessels
//     (2018, "Is human classification by experienced untrained observers a gold standard in
//     fixation detection?", Behavior Research Methods 50:1864–1881): each reference event, in
//     time order, is matched by the earliest not yet matched event of the same class in the other
//     stream that overlaps it in time; matched pairs are hits, unmatched reference events misses,
//     unmatched events of the other stream false alarms; F1 = 2·hits / (2·hits + misses + false
//     alarms). For the hits, the relative timing offset (RTO, onset − reference onset) and
//     relative timing difference (RTD, duration − reference duration), means in ms.
#pragma once

#include "foveal/gaze/fixation.h"

#include <nlohmann/json.hpp>

#include <array>
#include <cstdint>
#include <optional>
#include <string_view>
#include <string>
#include <vector>

namespace foveal {

enum class EventLabel : uint8_t { undefined = 0, fixation, saccade, pso, pursuit, blink };
inline constexpr std::array<EventLabel, 5> kEventClasses{EventLabel::fixation, EventLabel::saccade, EventLabel::pso, EventLabel::pursuit,
                                                         EventLabel::blink};
const char* to_string(EventLabel label);
// A label's name (fixation, saccade, pso, pursuit, blink, undefined) or its number in the coding
// of Zemblys et al. 2018 (1 fixation, 2 saccade, 3 PSO, 4 pursuit, 5 blink, 0 undefined).
std::optional<EventLabel> parse_event_label(std::string_view text);

// A run of samples with one label; times in seconds (onset = the first sample's time, offset =
// the last's).
struct LabelledEvent {
  EventLabel label = EventLabel::undefined;
  size_t first = 0, last = 0;
  double onset_s = 0, offset_s = 0;
  double duration_s() const { return offset_s - onset_s; }
};
// The runs of equal labels (undefined runs included); `t_s` gives each sample's time.
std::vector<LabelledEvent> label_runs(const std::vector<EventLabel>& labels, const std::vector<double>& t_s);

// Labels from a fixation filter: its fixations' samples are fixations, lost samples (invalid:
// the tracker lost the eye) blinks, the other valid samples saccades.
std::vector<EventLabel> labels_from_fixations(const Recording& recording, const FixationResult& fixations);

// Expert labels: a CSV with a header naming a time column (t, t_s or time) and a `label` column
// (names or Zemblys et al.'s numbers), other columns ignored — such as the IRF recordings
// (t_s,x_deg,y_deg,status,label). Throws Error naming file:line.
struct LabelFile {
  std::string name;  // the file's path (or the name given to parse_label_file), for errors
  std::vector<double> t_s;
  std::vector<EventLabel> label;
  std::vector<size_t> line;  // each label's line in the file
};
LabelFile read_label_file(const std::string& path);
LabelFile parse_label_file(const std::string& text, const std::string& name);

// A label file's labels put on a recording's samples by time: each label's time must be a sample's
// (within a quarter of the median sampling interval) and no two labels may fall on one sample —
// labels shifted in time, or of another recording, are refused (Error naming file:line), not scored
// as if aligned. A coder may label a part of the samples (a recording's lost tail left out): the
// samples without a label are undefined and not `covered`.
struct AlignedLabels {
  std::vector<EventLabel> label;  // one per sample
  std::vector<bool> covered;      // the file labels this sample
  size_t count = 0;               // samples covered
};
AlignedLabels align_labels(const LabelFile& file, const std::vector<double>& sample_t_s);

struct ClassScore {
  EventLabel label = EventLabel::fixation;
  size_t reference_samples = 0, test_samples = 0;
  double kappa = 0;  // sample level, this class against the rest (NaN when neither stream has it)
  size_t reference_events = 0, test_events = 0, hits = 0, misses = 0, false_alarms = 0;
  double f1 = 0;      // event level (NaN when neither stream has an event of the class)
  double rto_ms = 0;  // mean onset difference of the hits (test − reference)
  double rtd_ms = 0;  // mean duration difference of the hits (test − reference)
};
struct Evaluation {
  size_t samples = 0;
  double kappa = 0;                 // sample level, all classes at once (Cohen's kappa of the two labellings)
  double accuracy = 0;              // share of samples labelled alike
  std::vector<ClassScore> classes;  // kEventClasses order
  const ClassScore& of(EventLabel label) const;
};
// `test` against `reference` (same length, same sample times `t_s`).
Evaluation evaluate_labels(const std::vector<EventLabel>& test, const std::vector<EventLabel>& reference, const std::vector<double>& t_s);
// The same over the samples where `scored` is true only (the samples every coder labelled).
Evaluation evaluate_labels(const std::vector<EventLabel>& test, const std::vector<EventLabel>& reference, const std::vector<double>& t_s,
                           const std::vector<bool>& scored);

// `test` (labels of the samples at `t_s`) against a coder's label file and, where a second coder's
// is given, against that one too, with the second coder's agreement with the first (the ceiling);
// all over the samples every coder labelled (a coder may leave a recording's lost tail out).
// Files are aligned by align_labels.
struct CoderEvaluation {
  Evaluation evaluation;
  std::optional<Evaluation> second;   // `test` against the second coder
  std::optional<Evaluation> ceiling;  // the second coder against the first
};
CoderEvaluation evaluate_against_coders(const std::vector<EventLabel>& test, const std::vector<double>& t_s, const LabelFile& coder,
                                        const std::optional<LabelFile>& coder2 = std::nullopt);

// An evaluation as JSON (what `foveal gaze --json` and foveal.gaze.evaluate give): samples, kappa,
// accuracy and per class kappa, f1, hits, misses, false_alarms, reference_events, test_events,
// rto_ms, rtd_ms (null where undefined).
nlohmann::json evaluation_json(const Evaluation& evaluation);

}  // namespace foveal
