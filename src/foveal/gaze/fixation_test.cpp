// Fixation filters on synthetic gaze with known fixations, their agreement with real trackers'
// own events, and the causal tracker's holding behaviour.
#include "foveal/gaze/fixation.h"
#include "foveal/gaze/summary.h"
#include "foveal/util/error.h"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <random>

using namespace foveal;

namespace {

const Display kDisplay{47.5, 30, 60, 1680, 1050};

// 500 Hz gaze: fixations at `points` lasting `durations` seconds, joined by 40 ms linear saccades,
// with a small deterministic jitter (±0.5 px). Returns the recording and the true fixation events.
Recording synthetic(const std::vector<glm::dvec2>& points, const std::vector<double>& durations, std::vector<GazeEvent>* truth,
                    double saccade_s = 0.040) {
  Recording r;
  r.screen_px = {1680, 1050};
  r.format = GazeFormat::csv;
  double t = 0;
  const double dt = 0.002;
  int k = 0;
  for (size_t i = 0; i < points.size(); ++i) {
    GazeEvent e;
    e.start_s = t;
    e.px = points[i];
    for (double end = t + durations[i]; t < end - 1e-9; t += dt, ++k) {
      GazeSample s;
      s.t_s = t;
      s.px = points[i] + glm::dvec2(0.5 * std::sin(k * 1.7), 0.5 * std::cos(k * 2.3));
      s.valid = true;
      r.samples.push_back(s);
    }
    e.end_s = t - dt;
    if (truth) truth->push_back(e);
    if (i + 1 == points.size()) break;
    for (double a = dt; a < saccade_s; a += dt, t += dt) {  // saccade
      GazeSample s;
      s.t_s = t;
      s.px = glm::mix(points[i], points[i + 1], a / saccade_s);
      s.valid = true;
      r.samples.push_back(s);
    }
  }
  return r;
}

}  // namespace

TEST(Fixation, GeometryMatchesTheDisplayModel) {
  const GazeGeometry g(kDisplay, {1680, 1050});
  EXPECT_NEAR(g.pixels_per_degree(), pixels_per_degree(kDisplay), 1e-9);
  // The angle across the whole screen width is the display's horizontal field of view
  EXPECT_NEAR(angle_between_deg(g.direction({0, 525}), g.direction({1680, 525})), field_of_view_x_deg(kDisplay), 1e-9);
  EXPECT_NEAR(angle_between_deg(g.direction({840, 525}), g.direction({840, 525})), 0, 1e-12);
  // Another screen resolution spans the same physical screen
  const GazeGeometry small(kDisplay, {840, 525});
  EXPECT_NEAR(angle_between_deg(small.direction({0, 262.5}), small.direction({840, 262.5})), field_of_view_x_deg(kDisplay), 1e-9);
}

TEST(Fixation, FiltersFindKnownFixations) {
  std::vector<GazeEvent> truth;
  const std::vector<glm::dvec2> points{{300, 300}, {900, 500}, {1400, 800}, {500, 900}};
  const Recording r = synthetic(points, {0.300, 0.250, 0.400, 0.200}, &truth);
  const GazeGeometry g(kDisplay, r.screen_px);
  for (const FixationResult& result : {detect_ivt(r, g, {}), detect_idt(r, g, {})}) {
    ASSERT_EQ(result.fixations.size(), points.size());
    for (size_t i = 0; i < points.size(); ++i) {
      EXPECT_LT(glm::length(result.fixations[i].px - points[i]), 1.0);
      EXPECT_NEAR(result.fixations[i].duration_s(), truth[i].end_s - truth[i].start_s, 0.030);
    }
    const Agreement a = agreement_with_events(r, fixation_mask(result), truth);
    EXPECT_GT(a.agreement, 0.95);
    EXPECT_GT(a.kappa, 0.8);
  }
}

TEST(Fixation, IvtGapFillMergeAndDiscard) {
  const GazeGeometry g(kDisplay, {1680, 1050});
  // One 400 ms fixation with a 50 ms loss in the middle: filled, still one fixation
  Recording r = synthetic({{800, 500}}, {0.400}, nullptr);
  for (GazeSample& s : r.samples)
    if (s.t_s > 0.2 && s.t_s < 0.25) {
      s.valid = false;
      s.px = glm::dvec2(NAN);
    }
  EXPECT_EQ(detect_ivt(r, g, {}).fixations.size(), 1u);
  EXPECT_EQ(detect_idt(r, g, {}).fixations.size(), 1u);
  // A 150 ms loss is longer than the 75 ms gap fill: two fixations
  for (GazeSample& s : r.samples)
    if (s.t_s > 0.1 && s.t_s < 0.25) s.valid = false;
  EXPECT_EQ(detect_ivt(r, g, {}).fixations.size(), 2u);
  // Two fixations 0.3° apart, with a 20 ms excursion between them, merge into one (< 0.5°, 75 ms)
  const Recording near = synthetic({{800, 500}, {1000, 500}, {810, 500}}, {0.200, 0.0, 0.200}, nullptr, 0.010);
  EXPECT_EQ(detect_ivt(near, g, {}).fixations.size(), 1u);
  FixationParams no_merge;
  no_merge.merge_angle_deg = 0;
  EXPECT_EQ(detect_ivt(near, g, no_merge).fixations.size(), 2u);
  // A 40 ms fixation is shorter than the 60 ms minimum: discarded
  const Recording brief = synthetic({{300, 300}, {1300, 300}, {300, 800}}, {0.200, 0.040, 0.200}, nullptr);
  EXPECT_EQ(detect_ivt(brief, g, {}).fixations.size(), 2u);
}

TEST(Fixation, MedianWindowRemovesASingleSampleSpike) {
  const GazeGeometry g(kDisplay, {1680, 1050});
  Recording r = synthetic({{800, 500}}, {0.400}, nullptr);
  r.samples[100].px += glm::dvec2(120, 0);               // one 3° outlier in the middle of the fixation
  EXPECT_EQ(detect_idt(r, g, {}).fixations.size(), 2u);  // the dispersion breaks at the spike
  FixationParams median;
  median.median_window = 3;
  EXPECT_EQ(detect_idt(r, g, median).fixations.size(), 1u);
  // The causal filter too: without the median the fixation ends at the spike, with it it does not
  for (int window : {1, 3}) {
    FixationParams p;
    p.median_window = window;
    FixationTracker tracker(FixationMethod::idt, p, g);
    int ends = 0;
    bool was = false;
    for (const GazeSample& s : r.samples) {
      tracker.push(s);
      ends += was && !tracker.in_fixation();
      was = tracker.in_fixation();
    }
    EXPECT_EQ(ends, window == 1 ? 1 : 0) << "median window " << window;
  }
  median.median_window = 4;
  EXPECT_THROW(detect_idt(r, g, median), Error);  // even windows have no middle sample
}

TEST(Fixation, AgreementAndKappaAtKnownValues) {
  Recording r;
  for (int i = 0; i < 10; ++i) {
    GazeSample s;
    s.t_s = i;
    s.px = {0, 0};
    s.valid = true;
    r.samples.push_back(s);
  }
  r.samples.push_back(GazeSample{10, glm::dvec2(NAN), 0, false, {}});  // invalid: not compared
  const std::vector<GazeEvent> reference{{0, 4.5, {}}};                // samples 0..4
  const std::vector<bool> filter{true, true, true, true, false, false, false, false, false, false, true};
  const Agreement a = agreement_with_events(r, filter, reference);
  EXPECT_EQ(a.samples, 10u);
  EXPECT_DOUBLE_EQ(a.agreement, 0.9);
  EXPECT_DOUBLE_EQ(a.filter_fraction, 0.4);
  EXPECT_DOUBLE_EQ(a.reference_fraction, 0.5);
  EXPECT_NEAR(a.kappa, (0.9 - 0.5) / 0.5, 1e-12);  // p_e = 0.4·0.5 + 0.6·0.5
}

TEST(Fixation, CausalTrackerHoldsTheLastFixation) {
  const GazeGeometry g(kDisplay, {1680, 1050});
  const Recording r = synthetic({{300, 300}, {1300, 800}}, {0.300, 0.300}, nullptr);
  for (FixationMethod m : {FixationMethod::ivt, FixationMethod::idt, FixationMethod::ivvt}) {
    FixationTracker tracker(m, {}, g);
    std::optional<glm::dvec2> first_fixation;
    for (const GazeSample& s : r.samples) {
      tracker.push(s);
      if (s.t_s < 0.3 && tracker.current()) first_fixation = tracker.current();
      // During the saccade the output stays on the first fixation
      if (s.t_s > 0.3 && s.t_s < 0.34) EXPECT_LT(glm::length(*tracker.current() - glm::dvec2(300, 300)), 1.0) << to_string(m);
    }
    ASSERT_TRUE(first_fixation);
    EXPECT_LT(glm::length(*first_fixation - glm::dvec2(300, 300)), 1.0);
    EXPECT_LT(glm::length(*tracker.frame_gaze() - glm::dvec2(1300, 800)), 1.0);
    // Lost eye and low confidence never move it
    tracker.push(GazeSample{1.0, glm::dvec2(NAN), 0, false, {}});
    tracker.push(GazeSample{1.01, glm::dvec2(0, 0), 0.1f, false, {}});
    EXPECT_LT(glm::length(*tracker.frame_gaze() - glm::dvec2(1300, 800)), 1.0);
  }
  // mean: the average of the valid samples since the last frame; held when none arrived
  FixationTracker mean(FixationMethod::mean, {}, g);
  EXPECT_FALSE(mean.frame_gaze());
  mean.push(GazeSample{0.000, {100, 100}, 1, true, {}});
  mean.push(GazeSample{0.004, {200, 300}, 1, true, {}});
  mean.push(GazeSample{0.008, {9999, 9999}, 0.1f, false, {}});
  EXPECT_EQ(*mean.frame_gaze(), glm::dvec2(150, 200));
  EXPECT_EQ(*mean.frame_gaze(), glm::dvec2(150, 200));
  mean.push(GazeSample{0.020, {400, 400}, 1, true, {}});
  EXPECT_EQ(*mean.frame_gaze(), glm::dvec2(400, 400));
}

// 1000 Hz gaze along y = 0 with 0.05° RMS noise: a fixation at −5°, a 10 °/s pursuit for 1 s, a
// fixation at +5°. I-VVT follows the eye through the pursuit (within 0.3° once established, 120 ms
// after it starts); I-VT holds a running mean that lags degrees behind.
TEST(Fixation, IvvtFollowsSmoothPursuit) {
  const GazeGeometry g(kDisplay, {1680, 1050});
  std::mt19937 rng(5);
  std::normal_distribution<double> noise(0, 0.05 / std::sqrt(2.0));
  auto at = [](double t) { return t < 0.5 ? -5.0 : t < 1.5 ? -5.0 + 10 * (t - 0.5) : 5.0; };
  // Degrees → screen pixels through the display's geometry (x right, y down)
  auto px = [&](glm::dvec2 deg) {
    const glm::dvec2 cm = glm::tan(glm::radians(deg)) * kDisplay.distance_cm;
    return glm::dvec2(840, 525) + cm / glm::dvec2(kDisplay.width_cm / 1680, kDisplay.height_cm / 1050);
  };
  auto deg_x = [&](glm::dvec2 p) { return GazeGeometry::angles_deg(g.direction(p)).x; };
  FixationTracker ivvt(FixationMethod::ivvt, {}, g), ivt(FixationMethod::ivt, {}, g);
  double worst_ivvt = 0, worst_ivt_lag = 0;
  int pursuit_samples = 0, pursuit_outside = 0;
  for (int i = 0; i < 2000; ++i) {
    const double t = i / 1000.0;
    GazeSample s;
    s.t_s = t;
    s.valid = true;
    s.px = px({at(t) + noise(rng), noise(rng)});
    ivvt.push(s);
    ivt.push(s);
    const bool in_pursuit = t >= 0.5 && t < 1.5;
    pursuit_samples += ivvt.in_pursuit();
    pursuit_outside += ivvt.in_pursuit() && !(t >= 0.5 && t < 1.56);
    if (in_pursuit && t >= 0.62) {
      ASSERT_TRUE(ivvt.in_pursuit()) << t;
      worst_ivvt = std::max(worst_ivvt, std::abs(deg_x(*ivvt.current()) - at(t)));
      worst_ivt_lag = std::max(worst_ivt_lag, std::abs(deg_x(*ivt.current()) - at(t)));
    }
  }
  EXPECT_LT(worst_ivvt, 0.3);
  EXPECT_GT(worst_ivt_lag, 3.0);
  EXPECT_GT(pursuit_samples, 850);
  EXPECT_EQ(pursuit_outside, 0);
  // After the pursuit I-VVT settles on the last fixation; to I-VT (no saccade) it was all one
  // fixation, whose mean is far from where the eye ended
  EXPECT_NEAR(deg_x(*ivvt.frame_gaze()), 5, 0.1);
  EXPECT_GT(std::abs(deg_x(*ivt.frame_gaze()) - 5), 3.0);
}

// On a noisy fixation I-VVT never calls pursuit and gives I-VT's output.
TEST(Fixation, IvvtIsIvtWithoutPursuit) {
  const GazeGeometry g(kDisplay, {1680, 1050});
  std::mt19937 rng(9);
  std::normal_distribution<double> noise(0, 1.5);  // pixels: about 0.05° RMS
  FixationTracker ivvt(FixationMethod::ivvt, {}, g), ivt(FixationMethod::ivt, {}, g);
  for (int i = 0; i < 3000; ++i) {
    GazeSample s;
    s.t_s = i / 1000.0;
    s.valid = true;
    s.px = glm::dvec2(700 + noise(rng), 400 + noise(rng));
    ivvt.push(s);
    ivt.push(s);
    ASSERT_FALSE(ivvt.in_pursuit()) << s.t_s;
    ASSERT_EQ(ivvt.current().has_value(), ivt.current().has_value());
    if (ivt.current()) ASSERT_EQ(*ivvt.current(), *ivt.current());
  }
  FixationParams p;
  p.pursuit.velocity_deg_s = 40;  // above the saccade threshold
  EXPECT_THROW(FixationTracker(FixationMethod::ivvt, p, g), Error);
}

TEST(Fixation, ScreenMapping) {
  const ScreenMapping whole = make_screen_mapping({1024, 768}, {840, 525});
  EXPECT_EQ(whole.to_render({0, 0}), glm::dvec2(0, 0));
  EXPECT_EQ(whole.to_render({1024, 768}), glm::dvec2(840, 525));
  EXPECT_EQ(whole.to_render({512, 384}), glm::dvec2(420, 262.5));
  const ScreenMapping centred = make_screen_mapping({1024, 768}, {840, 525}, "92,121.5,840,525");
  EXPECT_EQ(centred.to_render({92, 121.5}), glm::dvec2(0, 0));
  EXPECT_EQ(centred.to_render({0, 0}), glm::dvec2(-92, -121.5));  // off the render: allowed
  EXPECT_THROW(make_screen_mapping({1024, 768}, {840, 525}, "0,0,0,10"), Error);
  EXPECT_THROW(make_screen_mapping({1024, 768}, {840, 525}, "0,0,10"), Error);
}

// The bar: on the EyeLink recordings I-VT and I-DT agree with EyeLink's own EFIX events
// on at least 85 % of valid samples; on the Pupil recording, the same comparison with fixations.csv.
TEST(Fixation, RealRecordingsAgreeWithTheTrackersOwnFixations) {
  const std::string gaze = std::string(FOVEAL_DATA_DIR) + "/gaze";
  bool any = false;
  for (const char* name : {"/eyelink/monoRemote500.asc", "/eyelink/bino1000.asc"}) {
    if (!std::filesystem::exists(gaze + name)) continue;
    any = true;
    const Recording r = read_recording(gaze + name);
    Display d{47.5, 30, 60, r.screen_px.x, r.screen_px.y};
    const GazeSummary s = summarize_recording(r, d, {});
    for (const FilterSummary& f : s.filters) {
      ASSERT_TRUE(f.agreement);
      EXPECT_GE(f.agreement->agreement, 0.85) << name << " " << to_string(f.method);
      EXPECT_GT(f.agreement->kappa, 0.4) << name << " " << to_string(f.method);
      std::printf("%s %s: agreement %.3f kappa %.3f (causal %.3f / %.3f)\n", name, to_string(f.method), f.agreement->agreement,
                  f.agreement->kappa, f.causal_agreement->agreement, f.causal_agreement->kappa);
    }
  }
  const std::string pupil = gaze + "/pupil_labs/tutorial10/gaze_positions.csv";
  if (std::filesystem::exists(pupil)) {
    any = true;
    const Recording r = read_recording(pupil);
    // Pupil's detector: largest pairwise angle ≤ 1.5° for ≥ 80 ms, on its 3-D gaze directions;
    // a 1.5° pairwise spread is about 2° of I-DT's x-range + y-range.
    FixationParams pupil_like;
    pupil_like.dispersion_deg = 2.0;
    pupil_like.min_duration_s = 0.080;
    const GazeSummary s = summarize_recording(r, kDisplay, pupil_like);
    const FilterSummary& idt = s.filters[1];
    EXPECT_GE(idt.agreement->agreement, 0.85);
    std::printf("pupil tutorial10 idt (2 deg, 80 ms): agreement %.3f kappa %.3f; ivt %.3f / %.3f\n", idt.agreement->agreement,
                idt.agreement->kappa, s.filters[0].agreement->agreement, s.filters[0].agreement->kappa);
  }
  if (!any) GTEST_SKIP() << "skipped: no recordings under " << gaze;
}

// The filters' time windows must not depend on where the clock started: the same recording with
// every timestamp shifted by 10⁶ s gives the same fixations, sample for sample (offline and causal).
TEST(Fixation, ShiftingTheClockChangesNoLabel) {
  const std::string path = std::string(FOVEAL_DATA_DIR) + "/gaze/eyelink/monoRemote500.asc";
  if (!std::filesystem::exists(path)) GTEST_SKIP() << "skipped: " << path << " is absent";
  const Recording r = read_recording(path);
  Recording shifted = r;
  for (GazeSample& s : shifted.samples) s.t_s += 1e6;
  const Display d{47.5, 30, 60, r.screen_px.x, r.screen_px.y};
  const GazeGeometry g(d, r.screen_px);
  for (FixationMethod m : {FixationMethod::ivt, FixationMethod::idt}) {
    const FixationResult a = m == FixationMethod::ivt ? detect_ivt(r, g, {}) : detect_idt(r, g, {});
    const FixationResult b = m == FixationMethod::ivt ? detect_ivt(shifted, g, {}) : detect_idt(shifted, g, {});
    size_t differ = 0;
    for (size_t i = 0; i < a.label.size(); ++i) differ += a.label[i] != b.label[i];
    EXPECT_EQ(differ, 0u) << to_string(m) << ": " << differ << " of " << a.label.size() << " samples change label";
    ASSERT_EQ(a.fixations.size(), b.fixations.size()) << to_string(m);
    for (size_t k = 0; k < a.fixations.size(); ++k) {
      EXPECT_EQ(a.fixations[k].first, b.fixations[k].first);
      EXPECT_EQ(a.fixations[k].last, b.fixations[k].last);
    }
    const std::vector<bool> ca = causal_fixation_mask(r, m, {}, g), cb = causal_fixation_mask(shifted, m, {}, g);
    EXPECT_TRUE(ca == cb) << to_string(m) << " (causal)";
  }
}

// Screen-based recordings of fixation tasks (EyeLink's, IRF's looking at points): I-VVT finds
// (almost) no pursuit in them, so the fovea is I-VT's (to within the slow samples I-VVT leaves out
// of a fixation's mean).
TEST(Fixation, IvvtFindsNoPursuitInFixationTasks) {
  const std::string data = std::string(FOVEAL_DATA_DIR);
  const std::vector<std::pair<std::string, Display>> cases = {
      {data + "/gaze/eyelink/monoRemote500.asc", {47.5, 30, 60, 0, 0}},
      {data + "/gaze/eyelink/bino1000.asc", {47.5, 30, 60, 0, 0}},
      {data + "/eye-movements/irf/lookAtPoint_EL_S2.csv", {53.3, 30.1, 56.5, 1920, 1080}},
      {data + "/eye-movements/irf/lookAtPoint_EL_S5.csv", {53.3, 30.1, 56.5, 1920, 1080}}};
  bool any = false;
  for (const auto& [path, display] : cases) {
    if (!std::filesystem::exists(path)) continue;
    any = true;
    ReadOptions read;
    if (display.res_x) read.screen_px = {display.res_x, display.res_y};
    read.display_width_cm = display.width_cm;
    read.display_height_cm = display.height_cm;
    read.display_distance_cm = display.distance_cm;
    const Recording r = read_recording(path, read);
    const GazeGeometry g(display, r.screen_px);
    FixationTracker ivvt(FixationMethod::ivvt, {}, g), ivt(FixationMethod::ivt, {}, g);
    size_t valid = 0, pursuit = 0, same = 0;
    for (const GazeSample& s : r.samples) {
      ivvt.push(s);
      ivt.push(s);
      if (!s.valid) continue;
      ++valid;
      pursuit += ivvt.in_pursuit();
      same += ivvt.current() && ivt.current() && angle_between_deg(g.direction(*ivvt.current()), g.direction(*ivt.current())) < 0.1;
    }
    std::printf("%s: %.2f %% of valid samples pursuit, %.2f %% with the fovea within 0.1 deg of I-VT's\n", path.c_str(),
                100.0 * pursuit / valid, 100.0 * same / valid);
    EXPECT_LT(pursuit, valid / 200) << path;
    EXPECT_GT(same, valid * 9 / 10) << path;
  }
  if (!any) GTEST_SKIP() << "skipped: no recordings under " << data;
}
