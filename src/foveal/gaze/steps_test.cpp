// Real gaze as simulation steps: fixations of recordings (filters and the tracker's own events),
// blinks between them, and fixations of a live source as they are established.
#include "foveal/gaze/steps.h"
#include "foveal/util/error.h"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>

using namespace foveal;

namespace {

const Display kStepsDisplay{47.5, 30, 60, 1680, 1050};

// 500 Hz gaze: a fixation at each point for `fixation_s`; between fixations either a 40 ms
// saccade or, where `blink_s[i]` > 0, that long a run of invalid samples (the eye closed) with
// the gaze jumping to the next point.
Recording gaze(const std::vector<glm::dvec2>& points, double fixation_s, const std::vector<double>& blink_s) {
  Recording r;
  r.source = "synthetic";
  r.screen_px = {1680, 1050};
  const double dt = 0.002;
  double t = 0;
  int k = 0;
  auto add = [&](glm::dvec2 p, bool valid) {
    GazeSample s;
    s.t_s = t;
    s.px = valid ? p + glm::dvec2(0.4 * std::sin(k * 1.3), 0.4 * std::cos(k * 2.1)) : glm::dvec2(NAN);
    s.valid = valid;
    r.samples.push_back(s);
    t += dt;
    ++k;
  };
  for (size_t i = 0; i < points.size(); ++i) {
    GazeEvent e{t, 0, points[i]};
    for (double end = t + fixation_s; t < end - 1e-9;) add(points[i], true);
    e.end_s = t - dt;
    r.fixations.push_back(e);
    if (i + 1 == points.size()) break;
    if (blink_s[i] > 0) {
      r.blinks.push_back({t, t + blink_s[i], glm::dvec2(NAN)});
      for (double end = t + blink_s[i]; t < end - 1e-9;) add({}, false);
    } else {
      for (double a = dt; a < 0.040; a += dt) add(glm::mix(points[i], points[i + 1], a / 0.040), true);
    }
  }
  r.has_tracker_fixations = true;
  return r;
}

// A live source that hands out a script of samples, then ends.
class ScriptedSource final : public GazeSource {
 public:
  explicit ScriptedSource(std::vector<GazeSample> samples, size_t per_poll) : samples_(std::move(samples)), per_poll_(per_poll) {}
  void poll(std::vector<GazeSample>& out) override {
    for (size_t n = 0; n < per_poll_ && next_ < samples_.size(); ++n) out.push_back(samples_[next_++]);
  }
  SourceState state() const override { return next_ < samples_.size() ? SourceState::live : SourceState::ended; }
  double silent_s() const override { return 0; }
  std::string name() const override { return "scripted"; }
  glm::ivec2 screen_px() const override { return {1680, 1050}; }

 private:
  std::vector<GazeSample> samples_;
  size_t per_poll_, next_ = 0;
};

const std::vector<glm::dvec2> kPoints{{300, 300}, {1300, 300}, {800, 800}, {400, 700}};

}  // namespace

TEST(GazeSteps, OneStepPerFixationOfEachFilter) {
  const Recording r = gaze(kPoints, 0.300, {0, 0.150, 0});
  const GazeGeometry geometry(kStepsDisplay, r.screen_px);
  for (StepFixations from : {StepFixations::nhp, StepFixations::ivt, StepFixations::idt, StepFixations::tracker}) {
    const std::vector<GazeStep> steps = recording_steps(r, geometry, from, {});
    ASSERT_EQ(steps.size(), kPoints.size()) << to_string(from);
    for (size_t i = 0; i < steps.size(); ++i) {
      EXPECT_LT(glm::distance(steps[i].screen_px, kPoints[i]), 1.0) << to_string(from) << " fixation " << i;
      EXPECT_NEAR(steps[i].start_s, r.fixations[i].start_s, 0.060) << to_string(from) << " fixation " << i;
      EXPECT_GT(steps[i].duration_s, 0.200);
      if (i > 0) EXPECT_GT(steps[i].start_s, steps[i - 1].start_s);
    }
    // The blink between the second and third fixation, and no other
    EXPECT_FALSE(steps[0].blink_before);
    EXPECT_FALSE(steps[1].blink_before);
    EXPECT_TRUE(steps[2].blink_before) << to_string(from);
    EXPECT_FALSE(steps[3].blink_before);
  }
}

TEST(GazeSteps, BlinksFromInvalidRunsWhenTheTrackerReportsNone) {
  Recording r = gaze(kPoints, 0.300, {0.030, 0.150, 0.900});  // lost samples, a blink, the eye away
  const std::vector<GazeEvent> blinks = invalid_gap_blinks(r.samples);
  ASSERT_EQ(blinks.size(), 1u);  // only the 150 ms run has a blink's duration
  EXPECT_NEAR(blinks[0].start_s, r.blinks[1].start_s, 0.003);
  EXPECT_NEAR(blinks[0].end_s, r.blinks[1].end_s, 0.003);
  r.blinks.clear();
  const std::vector<GazeStep> steps = recording_steps(r, GazeGeometry(kStepsDisplay, r.screen_px), StepFixations::tracker, {});
  ASSERT_EQ(steps.size(), 4u);
  EXPECT_FALSE(steps[1].blink_before);
  EXPECT_TRUE(steps[2].blink_before);
  EXPECT_FALSE(steps[3].blink_before);
}

TEST(GazeSteps, NamesWhatIsMissing) {
  Recording r = gaze(kPoints, 0.300, {0, 0, 0});
  r.fixations.clear();
  r.has_tracker_fixations = false;
  r.tracker = "CSV";
  const GazeGeometry geometry(kStepsDisplay, r.screen_px);
  try {
    recording_steps(r, geometry, StepFixations::tracker, {});
    FAIL() << "no error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("synthetic: fixation tracker"), std::string::npos) << e.what();
  }
  EXPECT_THROW(parse_step_fixations("mean"), Error);
  EXPECT_THROW(parse_step_fixations("fast"), Error);
  EXPECT_EQ(parse_step_fixations("idt"), StepFixations::idt);
}

TEST(GazeSteps, LiveFixationsAsTheyAreEstablished) {
  const Recording r = gaze(kPoints, 0.300, {0, 0.150, 0});
  for (size_t per_poll : {size_t(1), size_t(7), size_t(1000)}) {  // however the samples arrive
    ScriptedSource source(r.samples, per_poll);
    LiveSteps live(source, FixationMethod::ivt, {}, GazeGeometry(kStepsDisplay, r.screen_px));
    std::vector<GazeStep> steps;
    while (auto s = live.next(1.0)) steps.push_back(*s);
    ASSERT_EQ(steps.size(), kPoints.size()) << per_poll;
    for (size_t i = 0; i < steps.size(); ++i) {
      EXPECT_LT(glm::distance(steps[i].screen_px, kPoints[i]), 1.0) << i;
      // Known once the minimum fixation time (60 ms) has passed, not before
      EXPECT_GE(steps[i].start_s, r.fixations[i].start_s + 0.060 - 1e-9);
      EXPECT_LT(steps[i].start_s, r.fixations[i].start_s + 0.120);
      EXPECT_EQ(steps[i].blink_before, i == 2) << i;
    }
    EXPECT_NE(live.why().find("ended"), std::string::npos) << live.why();
    EXPECT_EQ(live.samples(), r.samples.size());
  }
}

TEST(GazeSteps, RealEyeLinkFixationsAndBlinks) {
  const std::filesystem::path path = std::filesystem::path(FOVEAL_DATA_DIR) / "gaze/eyelink/monoRemote500.asc";
  if (!std::filesystem::exists(path)) GTEST_SKIP() << "skipped: " << path << " absent";
  const Recording r = read_recording(path.string());
  const GazeGeometry geometry(kStepsDisplay, r.screen_px);
  const std::vector<GazeStep> steps = recording_steps(r, geometry, StepFixations::tracker, {});
  // ../shared/data/README.md: 300 EFIX and 3 EBLINK events; each blink lies between two fixations
  EXPECT_EQ(steps.size(), 300u);
  EXPECT_EQ(std::count_if(steps.begin(), steps.end(), [](const GazeStep& s) { return s.blink_before; }), 3);
  // The I-VT filter finds about as many fixations as the tracker
  const size_t ivt = recording_steps(r, geometry, StepFixations::ivt, {}).size();
  EXPECT_GT(ivt, 270u);
  EXPECT_LT(ivt, 340u);
}

// nhp's steps: a fixation, a 1 s pursuit at 400 px/s (about 11 °/s on this display), a fixation:
// the pursuit becomes a step every 100 ms where the eye then is; I-VT makes one "fixation" of it.
TEST(GazeSteps, NhpStepsFollowAPursuit) {
  Recording r;
  r.source = "synthetic";
  r.screen_px = {1680, 1050};
  auto eye = [](double t) { return t < 0.4 ? 300.0 : t < 1.4 ? 300 + 400 * (t - 0.4) : 700.0; };
  for (int k = 0; k < 1800; ++k) {
    GazeSample s;
    s.t_s = k * 0.001;
    s.px = {eye(s.t_s) + 0.4 * std::sin(k * 1.3), 500 + 0.4 * std::cos(k * 2.1)};
    s.valid = true;
    r.samples.push_back(s);
  }
  const GazeGeometry geometry(kStepsDisplay, r.screen_px);
  const std::vector<GazeStep> steps = recording_steps(r, geometry, StepFixations::nhp, {});
  ASSERT_GE(steps.size(), 2u + 8u);
  EXPECT_NEAR(steps.front().screen_px.x, 300, 1);
  EXPECT_NEAR(steps.back().screen_px.x, 700, 1);
  size_t along = 0;
  for (size_t i = 1; i + 1 < steps.size(); ++i) {
    EXPECT_GT(steps[i].start_s, steps[i - 1].start_s);
    EXPECT_NEAR(steps[i].screen_px.x, eye(steps[i].start_s), 2.0) << i;  // where the eye is at the step's start
    along += steps[i].screen_px.x > 320 && steps[i].screen_px.x < 680;
  }
  EXPECT_GE(along, 8u);
  EXPECT_LE(recording_steps(r, geometry, StepFixations::ivt, {}).size(), 2u);
}
