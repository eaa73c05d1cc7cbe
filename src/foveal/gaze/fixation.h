// foveal/gaze/fixation.h — fixation filters (I-VT, I-DT, the paper's per-frame mean), their
// agreement with a tracker's own events, a causal filter for live gaze, and the screen → render map.
//
// Angles come from the display geometry: a screen pixel is a point on a W×H cm screen seen from
// d cm by an eye in front of its centre (the recording's screen fills the display), so a gaze
// sample is a direction and the distance between two samples is the exact angle between them.
// Where the tracker gives a 3-D gaze direction (Pupil's gaze_point_3d) that is used instead.
#pragma once

#include "foveal/gaze/recording.h"
#include "foveal/perception/foveation.h"

#include <deque>
#include <optional>
#include <string>
#include <vector>

namespace foveal {

// Screen pixels ↔ gaze directions for one screen.
class GazeGeometry {
 public:
  // The display's physical size and distance; the screen's pixels span its full width and height.
  GazeGeometry(const Display& display, glm::ivec2 screen_px);
  // Unit direction from the eye through a screen point (+z towards the screen, +y down). Inline:
  // the detectors call it once per sample.
  glm::dvec3 direction(glm::dvec2 px) const {
    const glm::dvec2 cm = (px - 0.5 * glm::dvec2(screen_)) * cm_per_px_;
    return glm::normalize(glm::dvec3(cm.x, cm.y, distance_cm_));
  }
  // Direction of a sample: the tracker's own where it has one, else through its screen point.
  glm::dvec3 direction(const GazeSample& sample) const { return sample.direction ? *sample.direction : direction(sample.px); }
  // Horizontal and vertical angles of a direction from straight ahead, degrees.
  static glm::dvec2 angles_deg(glm::dvec3 direction);
  // Pixels per degree at the screen centre (horizontal).
  double pixels_per_degree() const;
  glm::ivec2 screen_px() const { return screen_; }

 private:
  glm::ivec2 screen_;
  glm::dvec2 cm_per_px_;
  double distance_cm_;
};

// Angle between two unit directions, degrees (exact also for tiny angles).
double angle_between_deg(glm::dvec3 a, glm::dvec3 b);

enum class FixationMethod { mean, ivt, idt, ivvt };
const char* to_string(FixationMethod method);
FixationMethod parse_fixation_method(const std::string& name);  // throws Error
// The causal filter foveal recommends for the fovea (replay, view, the live path).
inline constexpr FixationMethod kRecommendedFixationMethod = FixationMethod::ivvt;

// Smooth pursuit, one test for the offline nhp (detect.h) and the causal I-VVT: the slope of a
// least-squares line over `window_s` faster than `velocity_deg_s` for at least `min_s`, the run
// covering at least half the distance that speed implies.
struct PursuitParams {
  double velocity_deg_s = 6;
  double window_s = 0.040;
  double min_s = 0.080;
  double travel_fraction = 0.5;  // a pursuit covers at least this fraction of the distance its speed implies
};
// Check parameters; throws Error naming the option.
void validate(const PursuitParams& params);

// Filter parameters. I-VT defaults are Tobii Pro's I-VT (fixation) filter (Olsen 2012) without
// its optional noise reduction; I-DT follows Salvucci & Goldberg (2000), with a 1° dispersion and
// Pupil Labs' 80 ms minimum duration.
struct FixationParams {
  double velocity_threshold_deg_s = 30;  // I-VT: slower samples are fixation samples
  double velocity_window_s = 0.020;      // I-VT: velocity over the samples less than ±10 ms away (times to 1 µs)
  double gap_fill_s = 0.075;             // both: invalid gaps up to this long are interpolated
  double merge_gap_s = 0.075;            // I-VT: fixations closer in time than this …
  double merge_angle_deg = 0.5;          // … and in angle than this are merged
  double min_fixation_s = 0.060;         // I-VT: shorter fixations are discarded
  int median_window = 1;                 // both: moving median over this many samples (odd; 1 = off)
  double dispersion_deg = 1.0;           // I-DT: (max−min) x + (max−min) y of a fixation, degrees
  double min_duration_s = 0.080;         // I-DT: minimum fixation duration (Pupil Labs' default)
  PursuitParams pursuit;                 // I-VVT: below the saccade threshold, pursuit by this test
};
// Check parameters; throws Error naming the option.
void validate(const FixationParams& params);

struct Fixation {
  double start_s = 0, end_s = 0;  // first and last sample's time
  glm::dvec2 px{0};               // mean of its valid samples, screen pixels
  size_t first = 0, last = 0;     // sample indices, inclusive
  double duration_s() const { return end_s - start_s; }
};

struct FixationResult {
  std::vector<Fixation> fixations;
  std::vector<int> label;  // per sample: its fixation's index, or −1 (saccade, gap, unclassified)
};

// Offline filters over a whole recording.
FixationResult detect_ivt(const Recording& recording, const GazeGeometry& geometry, const FixationParams& params);
FixationResult detect_idt(const Recording& recording, const GazeGeometry& geometry, const FixationParams& params);

// Sample-by-sample agreement of fixation/non-fixation labels over the recording's valid samples.
struct Agreement {
  size_t samples = 0;             // valid samples compared
  double agreement = 0;           // fraction classified alike
  double kappa = 0;               // Cohen's kappa
  double filter_fraction = 0;     // fraction the filter calls fixation
  double reference_fraction = 0;  // fraction the reference calls fixation
};
// `is_fixation[i]` for each sample against "sample i lies inside one of `events`".
Agreement agreement_with_events(const Recording& recording, const std::vector<bool>& is_fixation, const std::vector<GazeEvent>& events);
std::vector<bool> fixation_mask(const FixationResult& result);

// A causal filter: samples go in, in time order, as they would arrive from a tracker; the output
// is the gaze point to render with. Invalid samples (lost eye, low confidence, blink) never move it.
//   mean: the mean of the valid samples since the last frame (the paper's method);
//   ivt:  the running mean of the current fixation once its samples have stayed below the velocity
//         threshold for the minimum fixation time;
//   idt:  the centroid of the current window once it has stayed within the dispersion limit for
//         the minimum duration;
//   ivvt: I-VVT (Komogortsev & Karpov 2013, "Automated classification and scoring of smooth
//         pursuit eye movements in the presence of fixations and saccades", BRM 45:203–215):
//         I-VT's saccades and fixations, and between the two velocity thresholds smooth pursuit —
//         the slope of a least-squares line over the last pursuit window above the pursuit
//         velocity for the minimum pursuit time, having covered at least half the distance that
//         speed implies (the offline nhp's test, made causal). In pursuit the output follows the
//         eye: the line's position at the latest sample.
// Between fixations (saccades, gaps) the last fixation (or pursuit position) is held.
class FixationTracker {
 public:
  FixationTracker(FixationMethod method, const FixationParams& params, const GazeGeometry& geometry);
  void push(const GazeSample& sample);
  // The gaze point for a frame that starts now (after pushing the samples up to its start time);
  // nullopt until the first fixation (or valid sample, for mean).
  std::optional<glm::dvec2> frame_gaze();
  // Whether the latest sample belongs to an established fixation (mean: whether it was valid).
  bool in_fixation() const { return in_fixation_; }
  // ivvt: whether the latest sample belongs to an established smooth pursuit.
  bool in_pursuit() const { return in_pursuit_; }
  // The last output without consuming the frame's samples.
  std::optional<glm::dvec2> current() const { return output_; }

 private:
  struct Entry {
    double t;
    glm::dvec3 dir;
    glm::dvec2 px;
    glm::dvec2 angles;
  };
  void reset_candidate();
  std::optional<double> window_velocity(const Entry& e);  // I-VT's velocity, once the window has two samples
  void add_to_fixation(const Entry& e);
  void end_fixation();
  void push_ivt(const Entry& e);
  void push_idt(const Entry& e);
  void push_ivvt(const Entry& e);

  FixationMethod method_;
  FixationParams params_;
  GazeGeometry geometry_;
  std::optional<glm::dvec2> output_;
  bool in_fixation_ = false;
  double last_valid_t_ = -INFINITY;
  // mean
  glm::dvec2 frame_sum_{0};
  int frame_count_ = 0;
  // ivt / idt
  std::deque<Entry> window_;  // ivt: the velocity window; idt: the candidate fixation
  std::deque<Entry> recent_;  // the last samples, for the moving median
  glm::dvec2 candidate_sum_{0};
  size_t candidate_count_ = 0;
  double candidate_start_ = 0;
  glm::dvec2 lo_{0}, hi_{0};  // idt: angular bounds of an established fixation
  // ivvt
  std::deque<Entry> line_;  // the pursuit window's samples
  bool in_pursuit_ = false;
  double pursuit_start_t_ = NAN;  // the current run of pursuit-fast samples: its start …
  glm::dvec3 pursuit_start_dir_{0};
  double pursuit_distance_ = 0;  // … and the sum of its speeds × intervals (the distance implied)
  double pursuit_last_t_ = NAN;
};

// Where the render sits on the recording's screen: a rectangle (default: the whole screen, the
// render stretched to fill it). Screen points map linearly into render pixels; points outside
// the rectangle map outside the render (gaze off the image is allowed).
struct ScreenMapping {
  glm::dvec2 screen_px{1680, 1050};
  glm::dvec4 rect{0, 0, 1680, 1050};  // x, y, width, height on the screen, pixels
  glm::ivec2 render_px{840, 525};
  glm::dvec2 to_render(glm::dvec2 screen) const;
};
// From "X,Y,W,H" (empty: the whole screen); throws Error naming the option.
ScreenMapping make_screen_mapping(glm::ivec2 screen_px, glm::ivec2 render_px, const std::string& rect = {});

}  // namespace foveal
