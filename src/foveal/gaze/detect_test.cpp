// The event detectors on synthetic signals with known events: saccades with main-sequence
// durations and minimum-jerk profiles, a post-saccadic wobble, a pursuit ramp, a blink gap,
// 0.05° RMS noise; the adaptive thresholds on a known distribution; the BIDS table; the IRF data.
#include "foveal/gaze/detect.h"
#include "foveal/gaze/synthetic.h"
#include "foveal/util/error.h"
#include "foveal/util/units.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <random>

#include <fmt/format.h>

using namespace foveal;

namespace {

const Display kDisplay = synthetic_display();  // the IRF set's display

using Synthetic = SyntheticSignal;
using TrueEvent = SyntheticEvent;

Synthetic standard_signal() {
  Synthetic s(1000, -10);
  s.fixation(0.3);
  s.saccade(10, 0.4);
  s.fixation(0.3);
  s.saccade(5);
  s.fixation(0.3);
  s.pursuit(10, 0.5);
  s.fixation(0.3);
  s.blink(0.1);
  s.fixation(0.3);
  s.saccade(-15, 0.3);
  s.fixation(0.3);
  s.saccade(2);
  s.fixation(0.3);
  return s;
}

std::vector<const DetectedEvent*> of(const EventDetection& d, EventLabel label) {
  std::vector<const DetectedEvent*> out;
  for (const DetectedEvent& e : d.events)
    if (e.label == label) out.push_back(&e);
  return out;
}

EventDetection run(const Recording& r, EventMethod method) {
  return detect_events(r, GazeGeometry(kDisplay, r.screen_px), method, EventParams{}, FixationParams{});
}

}  // namespace

TEST(Detect, AdaptiveThresholdsOfAKnownDistribution) {
  // Half-normal noise speeds plus a few fast samples: the iteration drops the fast ones and
  // settles at μ + 6σ of the rest
  std::mt19937 rng(3);
  std::normal_distribution<float> normal(0, 1);
  std::vector<float> v;
  double sum = 0, sum2 = 0;
  for (int i = 0; i < 100000; ++i) {
    const float x = 10 + 2 * normal(rng);
    v.push_back(x);
    sum += x;
    sum2 += double(x) * x;
  }
  for (int i = 0; i < 500; ++i) v.push_back(300 + i);  // saccades
  v.push_back(NAN);
  const double mean = sum / 100000, sd = std::sqrt(sum2 / 100000 - mean * mean);
  const auto [peak, onset] = adaptive_velocity_thresholds(v, 100);
  EXPECT_NEAR(peak, mean + 6 * sd, 0.05);
  EXPECT_NEAR(onset, mean + 3 * sd, 0.05);
}

TEST(Detect, NystromHolmqvistFindsSaccadesPsoAndBlinksOnASyntheticSignal) {
  const Synthetic s = standard_signal();
  const Recording r = s.recording({0.05});
  for (EventMethod m : {EventMethod::nh, EventMethod::nhp}) {
    SCOPED_TRACE(to_string(m));
    const EventDetection d = run(r, m);
    const auto saccades = of(d, EventLabel::saccade);
    std::vector<TrueEvent> true_saccades;
    for (const TrueEvent& e : s.truth)
      if (e.label == EventLabel::saccade) true_saccades.push_back(e);
    ASSERT_EQ(saccades.size(), true_saccades.size());
    for (size_t k = 0; k < saccades.size(); ++k) {
      SCOPED_TRACE(k);
      EXPECT_NEAR(saccades[k]->onset_s - 100, true_saccades[k].onset_s, 0.002);
      // The amplitude from the saccade's first to last sample: the PSO's wobble is not in it
      EXPECT_NEAR(saccades[k]->amplitude_deg, true_saccades[k].amplitude_deg, 0.1 + 0.05 * true_saccades[k].amplitude_deg);
      EXPECT_GT(saccades[k]->peak_velocity_deg_s, 1.5 * true_saccades[k].amplitude_deg / true_saccades[k].duration_s);
    }
    // The two wobbles are PSOs, right after their saccades
    const auto psos = of(d, EventLabel::pso);
    ASSERT_EQ(psos.size(), 2u);
    EXPECT_EQ(psos[0]->first, saccades[0]->last + 1);
    EXPECT_EQ(psos[1]->first, saccades[2]->last + 1);
    const auto blinks = of(d, EventLabel::blink);
    ASSERT_EQ(blinks.size(), 1u);
    EXPECT_NEAR(blinks[0]->onset_s - 100, s.truth[4].onset_s, 0.002);
    EXPECT_NEAR(blinks[0]->duration_s, 0.1, 0.01);
    // Pursuit only from nhp, and there as one event covering the ramp
    const auto pursuits = of(d, EventLabel::pursuit);
    if (m == EventMethod::nh) {
      EXPECT_TRUE(pursuits.empty());
    } else {
      ASSERT_EQ(pursuits.size(), 1u);
      EXPECT_NEAR(pursuits[0]->onset_s - 100, s.truth[3].onset_s, 0.025);
      EXPECT_NEAR(pursuits[0]->duration_s, 0.5, 0.05);
      EXPECT_NEAR(pursuits[0]->amplitude_deg, 5, 0.5);
    }
    // Fixations between them: 7 segments, of which nh joins the two around the pursuit into one
    EXPECT_EQ(of(d, EventLabel::fixation).size(), m == EventMethod::nh ? 6u : 7u);
  }
}

TEST(Detect, EngbertKlieglFindsTheSaccadesAndNoPso) {
  const Synthetic s = standard_signal();
  const EventDetection d = run(s.recording({0.05}), EventMethod::ek);
  const auto saccades = of(d, EventLabel::saccade);
  ASSERT_EQ(saccades.size(), 4u);
  const double truth[] = {10, 5, 15, 2};
  for (size_t k = 0; k < 4; ++k) EXPECT_NEAR(saccades[k]->amplitude_deg, truth[k], 0.1 + 0.05 * truth[k]);
  EXPECT_TRUE(of(d, EventLabel::pso).empty());
  EXPECT_EQ(of(d, EventLabel::blink).size(), 1u);
}

TEST(Detect, NoiselessFixationHasNoEvents) {
  Synthetic s(1000, 3);
  s.fixation(2);
  const EventDetection d = run(s.recording({0.01}), EventMethod::nhp);
  ASSERT_EQ(d.events.size(), 1u);
  EXPECT_EQ(d.events[0].label, EventLabel::fixation);
  EXPECT_NEAR(d.events[0].duration_s, 2.001, 1e-9);
}

TEST(Detect, LongLossIsUndefinedNotABlink) {
  Synthetic s(1000, 0);
  s.fixation(0.5);
  s.blink(3);  // the eye left the tracker
  s.fixation(0.5);
  const EventDetection d = run(s.recording({0.02}), EventMethod::nh);
  EXPECT_TRUE(of(d, EventLabel::blink).empty());
  EXPECT_EQ(of(d, EventLabel::fixation).size(), 2u);
}

TEST(Detect, EventsTableIsBidsStyle) {
  const Synthetic s = standard_signal();
  const Recording r = s.recording({0.05});
  const EventDetection d = run(r, EventMethod::nhp);
  const std::string tsv = events_tsv(d, r);
  EXPECT_EQ(tsv.substr(0, tsv.find('\n')),
            "onset\tduration\ttrial_type\tamplitude_deg\tpeak_velocity_deg_s\tstart_x_deg\tstart_y_deg\tend_x_deg\tend_y_deg");
  EXPECT_EQ(size_t(std::count(tsv.begin(), tsv.end(), '\n')), d.events.size() + 1);
  // The first event starts at the first sample and is the fixation at (−10, 0)
  const std::string first = tsv.substr(tsv.find('\n') + 1, tsv.find('\n', tsv.find('\n') + 1) - tsv.find('\n') - 1);
  EXPECT_EQ(first.substr(0, first.find('\t')), "0.000000");
  EXPECT_NE(first.find("\tfixation\t"), std::string::npos);
  EXPECT_NE(first.find("\t-10.0"), std::string::npos) << first;
  // Blinks have no amplitude
  EXPECT_NE(tsv.find("\tblink\tn/a\tn/a"), std::string::npos);
}

TEST(Detect, MethodNamesAndBadParameters) {
  EXPECT_EQ(parse_event_method("auto"), kRecommendedEventMethod);
  EXPECT_EQ(parse_event_method("ek"), EventMethod::ek);
  try {
    parse_event_method("hmm");
    FAIL();
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("events: unknown detector 'hmm'"), std::string::npos);
  }
  EventParams p;
  p.pursuit.velocity_deg_s = 0;
  EXPECT_THROW(validate(p), Error);
  for (auto bad : {+[](EventParams& q) { q.saccade_trough = 1.5; }, +[](EventParams& q) { q.saccade_trough = -0.1; },
                   +[](EventParams& q) { q.pursuit_edge_s = -0.1; }, +[](EventParams& q) { q.pursuit_edge_s = NAN; }}) {
    EventParams q;
    bad(q);
    EXPECT_THROW(validate(q), Error);
  }
}

// nhr with no minimum pursuit duration, on noise up to 0.3° RMS: candidate runs whose edges (the
// shorter line's speed) leave nothing of them (two here) are not pursuit, every sample keeps a
// label, and the edges cut nothing off the ramp's true pursuit.
TEST(Detect, PursuitEdgesThatLeaveNothingOfARun) {
  const Synthetic s = standard_signal();
  EventParams p;
  p.slow_pursuit.min_s = 0;
  p.context_min_fraction = 0;
  for (double noise : {0.0, 0.05, 0.3}) {
    const Recording r = s.recording({noise});
    const EventDetection d = detect_events(r, GazeGeometry(kDisplay, r.screen_px), EventMethod::nhr, p, FixationParams{});
    ASSERT_EQ(d.labels.size(), r.samples.size());
    for (const DetectedEvent& e : d.events) EXPECT_LE(e.first, e.last);
    EXPECT_FALSE(std::ranges::none_of(d.labels, [](EventLabel l) { return l == EventLabel::pursuit; })) << noise;
    const auto ramp = d.labels.begin() + std::lround(s.truth[3].onset_s * 1000);
    EXPECT_TRUE(std::all_of(ramp, ramp + 500, [](EventLabel l) { return l == EventLabel::pursuit; })) << noise;
  }
}

TEST(Detect, SameLabelsWhateverTheClockOffset) {
  const Synthetic s = standard_signal();
  Recording a = s.recording({0.05}), b = a;
  for (GazeSample& x : b.samples) x.t_s += 1e6;
  EXPECT_EQ(run(a, EventMethod::nhp).labels, run(b, EventMethod::nhp).labels);
}

// Sample times a thousand times too fine (a clock in µs read as ms): the windows are capped at
// 256 samples either side instead of asking for millions (found by the recording fuzz target).
TEST(Detect, TinySamplingIntervalsKeepTheWindowsBounded) {
  Synthetic s(1000, 0);
  s.fixation(0.5);
  s.saccade(8);
  s.fixation(0.5);
  Recording r = s.recording({0.02});
  for (size_t i = 0; i < r.samples.size(); ++i) r.samples[i].t_s = 1e-9 * i;
  for (EventMethod m : {EventMethod::ek, EventMethod::nh, EventMethod::nhp}) {
    const EventDetection d = run(r, m);
    EXPECT_EQ(d.labels.size(), r.samples.size());
    EXPECT_NEAR(d.sampling_hz, 1e9, 1e3);
  }
}

// Saccades of 0.4° in 0.05° RMS noise peak near the 6 ms velocity's peak threshold (about 34 °/s
// against 39): the paper's detector finds a few; the smoother (20 ms) velocity's own peaks find
// most, every one a true saccade, with the edges still from the 6 ms velocity.
TEST(Detect, SmallSaccadesInNoiseAreFoundByTheSmootherVelocity) {
  Synthetic s(1000, 0);
  s.fixation(0.4);
  for (int k = 0; k < 20; ++k) {
    s.saccade(k % 2 ? -0.4 : 0.4);
    s.fixation(0.4);
  }
  const Recording r = s.recording({0.05});
  EventParams paper_params;
  paper_params.detection_window_s = 0;
  const EventDetection paper = detect_events(r, GazeGeometry(kDisplay, r.screen_px), EventMethod::nh, paper_params, FixationParams{});
  const EventDetection d = run(r, EventMethod::nh);
  const auto saccades = of(d, EventLabel::saccade);
  EXPECT_LE(of(paper, EventLabel::saccade).size(), 8u);
  EXPECT_GE(saccades.size(), 10u);
  for (const DetectedEvent* e : saccades) {
    // Each found saccade starts inside a true one: a small minimum-jerk saccade crosses the onset
    // threshold a few ms after it starts and falls below the offset threshold a few ms before it
    // ends, so its measured amplitude is its central part (waiting for the velocity's local
    // minima instead lowers the saccades' kappa on the IRF data from 0.887 to 0.862)
    const double t = e->onset_s - 100;
    const auto truth = std::find_if(s.truth.begin(), s.truth.end(),
                                    [&](const TrueEvent& x) { return t >= x.onset_s - 0.002 && t < x.onset_s + x.duration_s; });
    ASSERT_NE(truth, s.truth.end()) << "a saccade at " << t << " s where there is none";
    EXPECT_GT(e->amplitude_deg, 0.4 / 3) << t;
    EXPECT_LT(e->amplitude_deg, 0.4 + 0.1) << t;
  }
}

// A movement within 25 ms of a loss is the lid's, part of the blink; one 100 ms later is a saccade.
TEST(Detect, LidMovementNextToALossIsPartOfTheBlink) {
  for (double gap : {0.010, 0.100}) {
    SCOPED_TRACE(gap);
    Synthetic s(1000, 0);
    s.fixation(0.4);
    s.blink(0.1);
    s.fixation(gap);
    s.saccade(3);
    s.fixation(0.4);
    const EventDetection d = run(s.recording({0.05}), EventMethod::nhp);
    const auto blinks = of(d, EventLabel::blink);
    ASSERT_EQ(blinks.size(), 1u);
    if (gap < 0.025) {
      EXPECT_TRUE(of(d, EventLabel::saccade).empty());
      // The blink runs from the loss to the movement's end
      EXPECT_GT(blinks[0]->duration_s, 0.1 + gap + 0.015);
    } else {
      ASSERT_EQ(of(d, EventLabel::saccade).size(), 1u);
      EXPECT_NEAR(of(d, EventLabel::saccade)[0]->onset_s - 100, s.truth[1].onset_s, 0.002);
      EXPECT_NEAR(blinks[0]->duration_s, 0.1, 0.01);
    }
  }
}

// The degradation study (issue: a detector that holds across data): a minute of synthetic free
// viewing with pursuit, at 250–2000 Hz, scored against its truth. At 0.1° RMS noise with 10 % of
// the samples lost in bursts of 5–15 ms (dropouts; losses over 25 ms are blinks) the recommended detector finds the saccades with event
// F1 ≥ 0.9 at every rate; at 0.3° with 15 % lost it still finds most (no collapse), where the
// global thresholds of nhp collapse at 500 Hz.
TEST(Detect, RecommendedDetectorHoldsUnderNoiseAndLossAtEveryRate) {
  auto score = [](double rate, double noise, double loss, EventMethod m) {
    const SyntheticSignal s = synthetic_viewing(60, rate, true, 11);
    const Recording r = s.recording({noise, loss, 0.010, 5});
    std::vector<double> t;
    for (const GazeSample& x : r.samples) t.push_back(x.t_s);
    return evaluate_labels(run(r, m).labels, s.label, t);
  };
  for (double rate : {250.0, 500.0, 1000.0, 2000.0}) {
    SCOPED_TRACE(rate);
    const Evaluation clean = score(rate, 0.02, 0, kRecommendedEventMethod);
    EXPECT_GE(clean.of(EventLabel::saccade).f1, 0.98);
    EXPECT_GE(clean.of(EventLabel::pursuit).kappa, 0.85);
    EXPECT_GE(clean.of(EventLabel::fixation).kappa, 0.85);
    const Evaluation bound = score(rate, 0.1, 0.10, kRecommendedEventMethod);
    EXPECT_GE(bound.of(EventLabel::saccade).f1, 0.9);
    EXPECT_GE(bound.of(EventLabel::pursuit).kappa, 0.8);
    const Evaluation worst = score(rate, 0.3, 0.15, kRecommendedEventMethod);
    EXPECT_GE(worst.of(EventLabel::saccade).f1, 0.6);
    EXPECT_GE(worst.of(EventLabel::pursuit).kappa, 0.6);
  }
  EXPECT_LT(score(500, 0.3, 0, EventMethod::nhp).of(EventLabel::saccade).f1, 0.2);
}

// Two seconds, one blink, three saccades: enough for the local thresholds.
TEST(Detect, ShortRecordingWithABlink) {
  Synthetic s(500, -5);
  s.fixation(0.3);
  s.saccade(8, 0.3);
  s.fixation(0.4);
  s.blink(0.15);
  s.fixation(0.4);
  s.saccade(-4);
  s.fixation(0.3);
  s.saccade(2);
  s.fixation(0.3);
  const EventDetection d = run(s.recording({0.05, 0, 0.02, 3}), EventMethod::nhr);
  ASSERT_EQ(of(d, EventLabel::saccade).size(), 3u);
  ASSERT_EQ(of(d, EventLabel::blink).size(), 1u);
  EXPECT_NEAR(of(d, EventLabel::blink)[0]->duration_s, 0.15, 0.03);
  EXPECT_TRUE(of(d, EventLabel::pursuit).empty());
}

// A loss shorter than a blink is the tracker's dropout: filled in, the saccade through it found
// whole; a loss of 150 ms stays a blink.
TEST(Detect, DropoutsAreFilledBlinksAreNot) {
  Synthetic s(1000, 0);
  s.fixation(0.5);
  s.saccade(10);
  s.fixation(0.5);
  Recording r = s.recording({0.02});
  const size_t mid = static_cast<size_t>(std::lround((0.5 + 0.022) * 1000));  // inside the saccade
  for (size_t k = mid; k < mid + 15; ++k) r.samples[k].valid = false;
  const EventDetection d = run(r, EventMethod::nhr);
  ASSERT_EQ(of(d, EventLabel::saccade).size(), 1u);
  EXPECT_NEAR(of(d, EventLabel::saccade)[0]->amplitude_deg, 10, 0.6);
  EXPECT_TRUE(of(d, EventLabel::blink).empty());
  for (size_t k = mid - 200; k < mid + 150; ++k) r.samples[k].valid = false;  // 350 ms: a blink
  EXPECT_EQ(of(run(r, EventMethod::nhr), EventLabel::blink).size(), 1u);
}

// Samples an hour apart are two fixations, not one spanning the gap (issue 36's finding 10).
TEST(Detect, AGapInTimeEndsTheFixation) {
  Synthetic s(500, 2);
  s.fixation(1);
  Recording r = s.recording({0.03});
  Recording later = s.recording({0.03, 0, 0.02, 9}, 100 + 3600);
  r.samples.insert(r.samples.end(), later.samples.begin(), later.samples.end());
  for (EventMethod m : {EventMethod::nh, EventMethod::nhp, EventMethod::nhr}) {
    SCOPED_TRACE(to_string(m));
    const EventDetection d = run(r, m);
    const auto fixations = of(d, EventLabel::fixation);
    ASSERT_EQ(fixations.size(), 2u);
    for (const DetectedEvent* f : fixations) EXPECT_LT(f->duration_s, 1.01);
  }
}

// A million identical samples: the robust thresholds rest on their floors instead of collapsing to
// 1e-12 °/s (issue 36's finding 16), and the recording is one fixation.
TEST(Detect, ConstantSamplesKeepTheThresholdsAtTheirFloors) {
  Synthetic s(1000, 1);
  s.fixation(1000);
  const Recording r = s.recording({0});
  for (EventMethod m : {EventMethod::nh, EventMethod::nhp, EventMethod::nhr}) {
    SCOPED_TRACE(to_string(m));
    const EventDetection d = run(r, m);
    EXPECT_DOUBLE_EQ(d.peak_threshold_deg_s, EventParams{}.min_peak_deg_s);
    EXPECT_DOUBLE_EQ(d.onset_threshold_deg_s, 0.5 * EventParams{}.min_peak_deg_s);
    ASSERT_EQ(d.events.size(), 1u);
    EXPECT_EQ(d.events[0].label, EventLabel::fixation);
  }
}

// The recommended detector on the standard signal: its saccades, PSOs, the pursuit ramp, the blink.
TEST(Detect, RecommendedDetectorOnTheStandardSignal) {
  const Synthetic s = standard_signal();
  const EventDetection d = run(s.recording({0.05}), kRecommendedEventMethod);
  EXPECT_EQ(to_string(kRecommendedEventMethod), std::string("nhr"));
  const auto saccades = of(d, EventLabel::saccade);
  ASSERT_EQ(saccades.size(), 4u);
  const double truth[] = {10, 5, 15, 2};
  for (size_t k = 0; k < 4; ++k) EXPECT_NEAR(saccades[k]->amplitude_deg, truth[k], 0.1 + 0.05 * truth[k]);
  EXPECT_EQ(of(d, EventLabel::pso).size(), 2u);
  EXPECT_EQ(of(d, EventLabel::blink).size(), 1u);
  const auto pursuits = of(d, EventLabel::pursuit);
  ASSERT_EQ(pursuits.size(), 1u);
  // The 400 ms line's velocity rises 200 ms before the ramp does (its edges alone came 93 ms early);
  // the edges are the 100 ms line's, up to 30 ms early/late
  fmt::print("pursuit from {:.3f} s for {:.3f} s (the ramp: {:.3f} s, 0.5 s)\n", pursuits[0]->onset_s - 100, pursuits[0]->duration_s,
             s.truth[3].onset_s);
  EXPECT_NEAR(pursuits[0]->onset_s - 100, s.truth[3].onset_s, 0.03);
  EXPECT_NEAR(pursuits[0]->duration_s, 0.5, 0.06);
}

// ivvt as a labelling: the causal filter's view of the standard signal — pursuit once the ramp has
// lasted its minimum, lost samples blinks, and no labels from the future (a prefix of the
// recording labels its samples the same).
TEST(Detect, TheCausalFilterAsALabelling) {
  const Synthetic s = standard_signal();
  const Recording r = s.recording({0.05});
  const EventDetection d = run(r, EventMethod::ivvt);
  size_t pursuit = 0;
  const size_t ramp = static_cast<size_t>(std::lround(s.truth[3].onset_s * 1000));
  for (size_t k = ramp; k < ramp + 500; ++k) pursuit += d.labels[k] == EventLabel::pursuit;
  EXPECT_GT(pursuit, 300u);
  for (size_t k = 0; k < r.samples.size(); ++k)
    if (!r.samples[k].valid) EXPECT_EQ(d.labels[k], EventLabel::blink);
  Recording prefix = r;
  prefix.samples.resize(ramp + 250);
  const EventDetection p = run(prefix, EventMethod::ivvt);
  EXPECT_TRUE(std::equal(p.labels.begin(), p.labels.end(), d.labels.begin()));
}

namespace {

// nhr against the coders of the IRF and Lund 2013 training recordings: the mean over recordings and
// coders (as the benchmark's tables average) of the saccades' onset differences (test − coder, ms)
// and of the saccade and PSO sample κ (PSO: where the coder marks PSO), with `params`; `scored` = 0
// where no labelled recording is present.
struct CoderAgreement {
  double onset_ms = 0, saccade_kappa = 0, pso_kappa = 0;
  int scored = 0, pso_scored = 0;
};
CoderAgreement against_the_coders(const EventParams& params) {
  const std::string data = std::string(FOVEAL_DATA_DIR) + "/eye-movements";
  struct Case {
    std::string samples;
    std::vector<std::string> coders;
    Display display;
  };
  std::vector<Case> cases;
  for (int s = 1; s <= 6; ++s) {
    const std::string path = fmt::format("{}/irf/lookAtPoint_EL_S{}.csv", data, s);
    cases.push_back({path, {path}, {53.3, 30.1, 56.5, 1920, 1080}});
  }
  for (const std::string stimulus : {"img", "dots", "video"}) {
    const std::filesystem::path dir = data + "/lund2013-train/" + stimulus;
    if (!std::filesystem::is_directory(dir)) continue;
    for (const auto& entry : std::filesystem::directory_iterator(dir)) {
      const std::string name = entry.path().string();
      if (!name.ends_with("_MN.csv")) continue;
      cases.push_back({name, {name, name.substr(0, name.size() - 7) + "_RA.csv"}, {38, 30, 67, 1024, 768}});
    }
  }
  CoderAgreement out;
  for (const Case& c : cases) {
    if (!std::filesystem::exists(c.samples)) continue;
    ReadOptions read;
    read.screen_px = {c.display.res_x, c.display.res_y};
    read.screen_from_user = true;
    read.display_width_cm = c.display.width_cm;
    read.display_height_cm = c.display.height_cm;
    read.display_distance_cm = c.display.distance_cm;
    const Recording r = read_recording(c.samples, read);
    const EventDetection d = detect_events(r, GazeGeometry(c.display, r.screen_px), kRecommendedEventMethod, params, FixationParams{});
    std::vector<double> t(r.samples.size());
    for (size_t i = 0; i < t.size(); ++i) t[i] = r.samples[i].t_s;
    for (const std::string& coder : c.coders) {
      const CoderEvaluation scored_against = evaluate_against_coders(d.labels, t, read_label_file(coder));
      const ClassScore& saccades = scored_against.evaluation.of(EventLabel::saccade);
      EXPECT_GE(saccades.hits, 1u) << coder;
      out.onset_ms += saccades.rto_ms;
      out.saccade_kappa += saccades.kappa;
      ++out.scored;
      const ClassScore& psos = scored_against.evaluation.of(EventLabel::pso);
      if (psos.reference_samples > 0) out.pso_kappa += psos.kappa, ++out.pso_scored;
    }
  }
  if (out.scored > 0) out.onset_ms /= out.scored, out.saccade_kappa /= out.scored;
  if (out.pso_scored > 0) out.pso_kappa /= out.pso_scored;
  return out;
}

// The recommended settings' agreement, computed once for the tests that read it
const CoderAgreement& recommended_against_the_coders() {
  static const CoderAgreement agreement = against_the_coders(EventParams{});
  return agreement;
}

}  // namespace

// nhr's saccades begin at the first sample above the onset threshold, not at the crossing's sample
// below it (nh's rule): with its 10 ms velocity filter the saccade's rise reaches that sample early,
// and against the coders of the IRF and Lund 2013 training recordings its onsets came 1.7 ms early
// on average (every recording and coder between −0.3 and −4 ms). Now the mean is within 0.75 ms.
TEST(Detect, RecommendedSaccadeOnsetsAgreeWithTheCodersInTime) {
  const CoderAgreement& timing = recommended_against_the_coders();
  if (timing.scored == 0) GTEST_SKIP() << "skipped: no labelled recordings under " << FOVEAL_DATA_DIR;
  EXPECT_LT(std::abs(timing.onset_ms), 0.75) << "mean saccade onset difference " << timing.onset_ms << " ms over " << timing.scored;
}

// nhr's saccades end at their first velocity trough below a quarter of their own peak velocity
// (nh: below the recording's peak threshold, which a large saccade's first dip can lie above, and
// the saccade then ran on into its PSO). Against the same coders, where the saccade ends and the PSO
// begins agrees better: PSO κ higher, saccade κ no lower.
TEST(Detect, RecommendedSaccadesEndWhereTheCodersPsoBegins) {
  EventParams nh_rule;
  nh_rule.saccade_trough = 0;
  const CoderAgreement& timing = recommended_against_the_coders();
  const CoderAgreement before = against_the_coders(nh_rule);
  if (timing.scored == 0) GTEST_SKIP() << "skipped: no labelled recordings under " << FOVEAL_DATA_DIR;
  fmt::print("PSO kappa {:.3f} (nh's rule {:.3f}) over {}; saccade kappa {:.3f} ({:.3f}) over {}\n", timing.pso_kappa, before.pso_kappa,
             timing.pso_scored, timing.saccade_kappa, before.saccade_kappa, timing.scored);
  EXPECT_GT(timing.pso_kappa, before.pso_kappa + 0.01);
  EXPECT_GE(timing.saccade_kappa, before.saccade_kappa);
}

// Every detector's velocity is Savitzky–Golay's first derivative (= the slope of the least-squares
// line) over the largest centred window inside each run of samples, taken from sums over blocks of
// 512 samples (O(1) per sample). Against the filter's weights summed sample by sample, here, from the
// samples' directions: equal to float rounding inside long runs (several blocks), next to losses
// (the narrower windows at a run's edges, the one-sided difference at its ends), at 250 to 2000 Hz,
// for nh's 6-ms filter and nhr's 10-ms one.
TEST(Detect, VelocityBySumsEqualsTheFiltersWeights) {
  for (double rate : {250.0, 1000.0, 2000.0})
    for (EventMethod method : {EventMethod::nh, EventMethod::nhr}) {
      SCOPED_TRACE(fmt::format("{} Hz, {}", rate, to_string(method)));
      const Recording r = synthetic_viewing(20, rate, true, 3).recording({0.05, 0.01, 0.010, 9});
      EventParams p;
      p.max_dropout_s = 0;  // (nhr: no dropouts filled, so that the runs are the recording's)
      const GazeGeometry g(kDisplay, r.screen_px);
      const EventDetection d = detect_events(r, g, method, p, FixationParams{});
      const double dt = 1 / d.sampling_hz;
      const double window = method == EventMethod::nhr ? p.robust_filter_window_s : p.filter_window_s;
      const int h = std::clamp(static_cast<int>(std::lround(0.5 * window / dt)), 1, 256);
      const size_t n = r.samples.size();
      size_t compared = 0, edges = 0, longest = 0;
      for (size_t a = 0; a < n;) {  // each run [a, b) of valid samples
        if (!r.samples[a].valid) {
          EXPECT_TRUE(std::isnan(d.velocity_deg_s[a])) << a;
          ++a;
          continue;
        }
        size_t b = a;
        while (b < n && r.samples[b].valid) ++b;
        longest = std::max(longest, b - a);
        for (size_t i = a; i < b; ++i) {
          const int w = std::min({h, static_cast<int>(i - a), static_cast<int>(b - 1 - i)});
          double expected = NAN;
          if (b - a >= 2 && w == 0) {
            expected = kDeg * glm::length(g.direction(r.samples[i == a ? i + 1 : i - 1]) - g.direction(r.samples[i])) / dt;
          } else if (w > 0) {
            glm::dvec3 moment(0);
            double k2 = 0;
            for (int k = -w; k <= w; ++k) {
              moment += double(k) * g.direction(r.samples[static_cast<size_t>(static_cast<std::ptrdiff_t>(i) + k)]);
              k2 += double(k) * k;
            }
            expected = kDeg * glm::length(moment) / (k2 * dt);
          }
          if (std::isnan(expected)) {
            EXPECT_TRUE(std::isnan(d.velocity_deg_s[i])) << i;
            continue;
          }
          ASSERT_NEAR(d.velocity_deg_s[i], expected, 1e-4 * std::max(1.0, expected)) << i;
          ++compared;
          edges += w < h;
        }
        a = b;
      }
      EXPECT_GT(compared, n * 9 / 10);
      EXPECT_GT(edges, 20u);  // runs begin and end at losses: their edges were compared too
      if (rate >= 1000)
        EXPECT_GT(longest, size_t(2 * 512));  // and runs span several blocks of sums (at 250 Hz a blink every 3 s ends them first)
    }
}
