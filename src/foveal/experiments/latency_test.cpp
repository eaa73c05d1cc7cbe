// bench latency's account of late frames: where the machine's pause fell (the loop's own timings
// of each frame against its plan).
#include "foveal/experiments/latency.h"

#include "foveal/gaze/recording.h"
#include "foveal/scene/scene.h"
#include "foveal/util/error.h"

#include <gtest/gtest.h>

#include <cmath>
#include <unistd.h>
#include <filesystem>
#include <fstream>
#include <sstream>

#include <fmt/format.h>

namespace foveal {
namespace {

// A small view of the box on the model clock (the same figures on any machine).
LatencyParams model_clock_params(int width, int height, int max_rays, double fixed_ms, double duration_s) {
  LatencyParams p;
  p.render.width = width;
  p.render.height = height;
  p.render.foveation.max_rays = max_rays;
  p.clock = LoopClock::model;
  p.model_rays_per_ms = 2000;
  p.model_fixed_ms = fixed_ms;
  p.duration_s = duration_s;
  return p;
}

LatencyFramePart frame(int index, double ms, double maps, double plan, double trace, double compose, double rays_over,
                       double compose_over) {
  return {index, index / 60.0, ms, maps, plan, trace, compose, rays_over, compose_over, ""};
}

TEST(LatencyLateFrames, EachLateFrameNamesThePartItsPauseFellInto) {
  std::vector<LatencyFramePart> frames;
  for (int k = 0; k < 20; ++k)  // on time: maps every other frame, ~1 ms composing
    frames.push_back(frame(k, 15, k % 2 ? 4.3 : 0, 0.1, k % 2 ? 9 : 13, 0.8, 0, 0));
  frames.push_back(frame(20, 19.7, 0, 0.1, 12.5, 7.0, 0, 6.1));     // composing 7 ms against ~1 planned
  frames.push_back(frame(21, 19.6, 0, 0.1, 15.8, 1.0, 3.0, 0.2));   // rays 3 ms past their deadline, tracing long
  frames.push_back(frame(22, 17.3, 7.2, 0.1, 8.0, 1.0, 1.1, 0.1));  // the maps paused
  frames.push_back(frame(23, 16.9, 0, 6.9, 8.0, 1.0, 0.6, 0.0));    // a planning pass paused
  frames.push_back(frame(24, 16.5, 0, 0.1, 13.5, 2.9, 0, 2.0));     // a long composing, but on time: not listed
  frames.push_back(frame(25, 17.3, 4.4, 0.1, 12.0, 0.7, 2.9, 0));   // the usual maps, then rays 2.9 ms late
  const std::vector<LatencyFramePart> late = late_frame_parts(frames, 1000.0 / 60);
  ASSERT_EQ(late.size(), 5u);
  EXPECT_EQ(late[0].index, 20);
  EXPECT_EQ(late[0].part, "composing");
  EXPECT_EQ(late[1].part, "tracing");
  EXPECT_EQ(late[2].part, "maps");
  EXPECT_EQ(late[3].part, "planning");
  EXPECT_EQ(late[4].part, "tracing");
  EXPECT_TRUE(late_frame_parts({}, 16.7).empty());
}

// The late frames' threads: a frame that a wait for a CPU explains would have been on time without
// it (19.7 − 7.9 ≤ 16.7; 19.6 − 1.2 > 16.7); a frame whose threads were not read is left out
TEST(LatencyLateFrames, TheThreadsSayWhetherTheKernelKeptThemWaiting) {
  std::vector<LatencyFramePart> late{frame(20, 19.7, 0, 0.1, 12.5, 7.0, 0, 6.1), frame(21, 19.6, 0, 0.1, 15.8, 1.0, 3.0, 0.2),
                                     frame(22, 17.3, 7.2, 0.1, 8.0, 1.0, 1.1, 0.1)};
  const auto threads = [](LatencyFramePart& f, double wait, double share, double faults) {
    f.cpu_wait_ms = wait;
    f.cpu_share = share;
    f.faults = faults;
  };
  threads(late[0], 7.94, 0.6, 0);
  threads(late[1], 1.2, 1.0, 3);
  EXPECT_EQ(late_threads_summary(late, 1000.0 / 60),
            "run delay ≤ 7.9 ms (1 of 2 on time without it), page faults 0–3, the calling thread on a CPU 0.6–1.0 of the time");
  threads(late[0], 0.0, 0.96, 0);
  threads(late[1], NAN, NAN, NAN);
  threads(late[2], 0.7, 1.0, 0);  // 17.3 − 0.7 ≤ 16.7
  EXPECT_EQ(late_threads_summary(late, 1000.0 / 60),
            "run delay ≤ 0.7 ms (1 of 2 on time without it), page faults 0, the calling thread on a CPU 1.0 of the time");
  // A range whose ends read alike is one figure (0.96 and 1.01: not "1.0–1.0")
  threads(late[0], 0.0, 0.96, 0);
  threads(late[2], 0.0, 1.01, 0);
  EXPECT_EQ(late_threads_summary(late, 1000.0 / 60),
            "run delay ≤ 0.0 ms (0 of 2 on time without it), page faults 0, the calling thread on a CPU 1.0 of the time");
  threads(late[0], NAN, NAN, NAN);
  threads(late[2], NAN, NAN, NAN);
  EXPECT_EQ(late_threads_summary(late, 1000.0 / 60), "");
  // late_frame_parts keeps each frame's threads
  std::vector<LatencyFramePart> frames{frame(0, 15, 0, 0.1, 13, 0.8, 0, 0), frame(1, 18, 0, 0.1, 13, 4.5, 0, 3.6)};
  threads(frames[1], 3.7, 0.8, 2);
  const std::vector<LatencyFramePart> kept = late_frame_parts(frames, 1000.0 / 60);
  ASSERT_EQ(kept.size(), 1u);
  EXPECT_DOUBLE_EQ(kept[0].cpu_wait_ms, 3.7);
  EXPECT_DOUBLE_EQ(kept[0].cpu_share, 0.8);
  EXPECT_DOUBLE_EQ(kept[0].faults, 2);
  // … and the other process busiest in each late frame, where the bench watched any
  threads(late[0], 4.0, 0.9, 0);
  threads(late[2], 0.1, 1.0, 0);
  late[0].other = "kdamond.0";
  late[0].other_ms = 4.14;
  late[2].other_ms = 0;  // watched, none ran
  EXPECT_EQ(late_threads_summary(late, 1000.0 / 60),
            "run delay ≤ 4.0 ms (1 of 2 on time without it), page faults 0, the calling thread on a CPU 0.9–1.0 of the time; the "
            "other process busiest in each: kdamond.0 4.1 ms, none");
}

// The loop's own plan of a wall-clock frame, which the account reads: the deadline inside the
// budget, composing planned, the rays' end between the maps and the frame's end
TEST(LatencyLateFrames, TheLoopReportsItsPlanForEachFrame) {
  const Scene scene = make_builtin_scene("box");
  const std::unique_ptr<FrameRenderer> renderer = make_frame_renderer(scene, ComputeDevice::cpu);
  RenderParams params;
  params.width = 160;
  params.height = 100;
  params.foveation.max_rays = 400;
  RealtimeLoop loop(*renderer, scene, params, LoopSettings{});
  loop.frame(scene.cameras.front());  // the view's surfaces
  for (int k = 0; k < 5; ++k) {
    loop.push_gaze(k / 60.0, glm::dvec2(40 + 15 * k, 50));
    const LoopFrame f = loop.frame(scene.cameras.front());
    EXPECT_GT(f.deadline_ms, 0);
    EXPECT_LT(f.deadline_ms, 1000.0 / 60);
    EXPECT_GT(f.compose_planned_ms, 0);
    EXPECT_GE(f.rays_end_ms, f.maps_ms);
    EXPECT_LE(f.rays_end_ms, f.ms);
    EXPECT_GE(f.ms - f.rays_end_ms, f.compose_ms);
  }
}

// The timeline picture draws its saccade's own fovea in every frame: before the landing the
// followed fovea is the saccade before's, another place. With a perfect predictor that fovea's
// error already falls before the eye lands. Without a picture asked for, no frame judges it.
TEST(LatencyTimeline, EveryFrameJudgesTheDrawnSaccadesFovea) {
  std::string csv = "t,x,y\n";  // 500 Hz: 800 px right at 0.4 s, back at 1.0 s (65 ms saccades)
  auto bell = [](double tau) { return tau <= 0 ? 0.0 : tau >= 1 ? 1.0 : tau - std::sin(2 * M_PI * tau) / (2 * M_PI); };
  for (int i = 0; i < 800; ++i) {
    const double t = i / 500.0;
    csv += fmt::format("{},{},{}\n", t, 400 + 800 * bell((t - 0.4) / 0.065) - 800 * bell((t - 1.0) / 0.065) + 0.3 * (i % 3), 520);
  }
  const Scene scene = make_builtin_scene("box");
  LatencyParams p = model_clock_params(168, 105, 64, 3, 1.5);
  p.min_amplitude_deg = 5;
  p.loops = {"deadline", "deadline+oracle"};
  const std::vector<Recording> recordings = {parse_recording(csv, "saccades.csv")};
  const auto run = [&](std::optional<size_t> drawn) {
    p.timeline_saccade = drawn;
    return bench_latency(scene, "builtin:box", scene.cameras.front(), ComputeDevice::cpu, 1, recordings, p, [](const std::string&) {});
  };
  const LatencyReport report = run(5);  // beyond the last: the last, the second saccade
  const LatencyRecording& r = report.recordings.front();
  ASSERT_EQ(r.loops.size(), 2u);
  ASSERT_EQ(r.loops[0].saccades.size(), 2u);
  ASSERT_EQ(r.drawn, std::optional<size_t>(1));
  const double first = r.loops[0].saccades[0].landing_s, second = r.loops[0].saccades[1].landing_s;
  for (const LatencyLoop& loop : r.loops) {
    SCOPED_TRACE(loop.name);
    size_t after = 0;
    for (const LatencyFrame& f : loop.timeline) {
      EXPECT_TRUE(std::isfinite(f.drawn_error)) << f.shown_s;
      // After the second landing the followed fovea is the drawn one: the same figure
      if (f.shown_s >= second) {
        EXPECT_DOUBLE_EQ(f.fovea_error, f.drawn_error);
        ++after;
      }
    }
    EXPECT_GT(after, 10u);
    // The loop's own account of each frame: the model clock times no part of it
    uint64_t rays = 0, sweeps = 0;
    size_t converged = 0, refining = 0;
    for (const LatencyFrame& f : loop.timeline) {
      EXPECT_EQ(f.scale, 1.0);
      ASSERT_TRUE(f.fovea_converged >= 0 && f.fovea_converged <= 1) << f.shown_s;
      EXPECT_TRUE(std::isnan(f.maps_ms) && std::isnan(f.plan_ms) && std::isnan(f.trace_ms) && std::isnan(f.compose_ms));
      rays += f.rays;
      sweeps += f.sweeps;
      (f.fovea_converged == 1 ? converged : refining) += 1;
    }
    EXPECT_GT(rays, 0u);
    EXPECT_GT(sweeps, 0u);     // (the periphery's, once a fovea converged)
    EXPECT_GT(converged, 0u);  // (a fovea converged, and a fresh one after each jump)
    EXPECT_GT(refining, 0u);
  }
  // On the wall clock each frame says what its maps, its planning, its rays and its composing took
  {
    LatencyParams wall = p;
    wall.clock = LoopClock::wall;
    wall.model_rays_per_ms = wall.model_fixed_ms = {};
    wall.loops = {"deadline"};
    const LatencyReport timed =
        bench_latency(scene, "builtin:box", scene.cameras.front(), ComputeDevice::cpu, 1, recordings, wall, [](const std::string&) {});
    size_t traced = 0, swept = 0;
    for (const LatencyFrame& f : timed.recordings.front().loops.front().timeline) {
      ASSERT_TRUE(f.maps_ms >= 0 && f.plan_ms >= 0 && f.trace_ms >= 0 && f.compose_ms > 0) << f.shown_s;
      EXPECT_LE(f.maps_ms + f.plan_ms + f.trace_ms + f.compose_ms, f.cost_ms);
      traced += f.rays > 0 && f.trace_ms > 0;
      swept += f.sweeps > 0 && f.plan_ms > 0;
    }
    EXPECT_GT(traced, 0u);
    EXPECT_GT(swept, 0u);
    // … and the frames that left chunks to paused threads are counted, with those waiting would have made late
    const LatencyLoop& loop = timed.recordings.front().loops.front();
    EXPECT_LE(loop.late_had_they_waited, loop.frames_left_behind);
    const nlohmann::json& j = timed.json["recordings"][0]["deadline"];
    EXPECT_EQ(j.at("frames_left_behind"), loop.frames_left_behind);
    EXPECT_EQ(j.at("late_had_they_waited"), loop.late_had_they_waited);
  }
  // Before the second landing the drawn fovea is not the followed one (the first saccade's,
  // elsewhere)
  auto last_before = [](const LatencyLoop& loop, double t) -> const LatencyFrame& {
    const LatencyFrame* last = &loop.timeline.front();
    for (const LatencyFrame& f : loop.timeline)
      if (f.shown_s < t) last = &f;
    return *last;
  };
  EXPECT_GT(last_before(r.loops[0], second).shown_s, first);
  EXPECT_NE(last_before(r.loops[0], second).drawn_error, last_before(r.loops[0], second).fovea_error);
  // Drawing the first saccade: the oracle's frames shown before its landing already lower its
  // fovea's error; the loop without prediction's last one does not
  const LatencyReport at_first = run(0);
  const LatencyRecording& f0 = at_first.recordings.front();
  EXPECT_LT(last_before(f0.loops[1], first).drawn_error, last_before(f0.loops[0], first).drawn_error);
  // The picture: drawn from the run, refused for a run that judged no saccade for it
  const std::string path = (std::filesystem::temp_directory_path() / ("foveal_timeline_" + std::to_string(getpid()) + ".svg")).string();
  EXPECT_EQ(write_latency_timeline(report, 5, path), 1u);
  EXPECT_GT(std::filesystem::file_size(path), 1000u);
  {
    // Each loop keeps its name's colour whichever loops ran: deadline blue, the oracle purple, and no
    // grey, which is the whole-frame loop's (they had taken the colours in the order the loops ran)
    std::stringstream svg;
    svg << std::ifstream(path).rdbuf();
    EXPECT_NE(svg.str().find("stroke=\"#2672d8\""), std::string::npos);
    EXPECT_NE(svg.str().find("stroke=\"#8c33a5\""), std::string::npos);
    EXPECT_EQ(svg.str().find("stroke=\"#999999\""), std::string::npos);
  }
  std::filesystem::remove(path);
  const LatencyReport plain = run(std::nullopt);
  EXPECT_FALSE(plain.recordings.front().drawn);
  for (const LatencyFrame& f : plain.recordings.front().loops[0].timeline) EXPECT_TRUE(std::isnan(f.drawn_error));
  EXPECT_THROW(write_latency_timeline(plain, 5, path), Error);
}

// A deadline loop whose fixed part does not fit the budget shows frames at a lowered size, taken
// from the view at the references' size: each is judged on the pixels it shows, against the
// references at the pixels of their size whose surfaces they show, and the report counts them.
TEST(LatencyTimeline, FramesAtALoweredSizeAreJudgedOnThePixelsTheyShow) {
  std::string csv = "t,x,y\n";  // 500 Hz: 800 px right at 0.4 s (a 65 ms saccade)
  auto bell = [](double tau) { return tau <= 0 ? 0.0 : tau >= 1 ? 1.0 : tau - std::sin(2 * M_PI * tau) / (2 * M_PI); };
  for (int i = 0; i < 900; ++i) {
    const double t = i / 500.0;
    csv += fmt::format("{},{},{}\n", t, 400 + 800 * bell((t - 0.4) / 0.065) + 0.3 * (i % 3), 520);
  }
  const Scene scene = make_builtin_scene("box");
  const std::vector<Recording> recordings = {parse_recording(csv, "saccade.csv")};
  const auto run = [&](double fixed_ms, std::function<void(RealtimeLoop&, int)> before_frame = {}) {
    LatencyParams p = model_clock_params(168, 105, 64, fixed_ms, 1.8);
    p.rays_ahead = false;  // (the landed fovea fresh: no rays cast there ahead of the gaze)
    p.min_amplitude_deg = 5;
    p.loops = {"deadline"};
    p.before_frame = std::move(before_frame);
    return bench_latency(scene, "builtin:box", scene.cameras.front(), ComputeDevice::cpu, 1, recordings, p, [](const std::string&) {});
  };
  // Each frame judged; the landing's fovea, refined only to the periphery's rays before the landing,
  // far from the references there, and within their noise once the eye has landed
  const auto expect_judged = [](const LatencyLoop& loop) {
    ASSERT_EQ(loop.saccades.size(), 1u);
    const LatencySaccade& sac = loop.saccades[0];
    double before = NAN, last = NAN;  // the landing fovea's error: the last frame shown before the landing, the last frame
    for (const LatencyFrame& f : loop.timeline) {
      ASSERT_TRUE(std::isfinite(f.fovea_error)) << f.shown_s;
      if (f.shown_s < sac.landing_s) before = f.fovea_error;
      last = f.fovea_error;
    }
    EXPECT_GT(before, 1.5);
    EXPECT_LT(last, 1.2);
    ASSERT_TRUE(sac.converged_ms);
    EXPECT_GT(*sac.converged_ms, 0);
    EXPECT_EQ(loop.frames_not_judged, 0);
    EXPECT_EQ(sac.frames_not_judged, 0);
  };
  const LatencyReport slow = run(30);  // (the budget is 16.7 ms: the loop lowers its size, from the view at full size)
  const LatencyLoop& loop = slow.recordings.front().loops.front();
  int lowered = 0;
  for (const LatencyFrame& f : loop.timeline) lowered += f.scale < 1 ? 1 : 0;
  EXPECT_GT(lowered, static_cast<int>(loop.timeline.size()) / 2);
  EXPECT_EQ(loop.frames_lowered, lowered);
  expect_judged(loop);
  EXPECT_EQ(loop.timeline.back().scale, loop.timeline[loop.timeline.size() / 2].scale);
  EXPECT_LT(loop.timeline.back().scale, 1.0);
  const nlohmann::json& j = slow.json["recordings"][0]["deadline"];
  EXPECT_EQ(j.at("frames_lowered"), lowered);
  EXPECT_EQ(j.at("frames_not_judged"), 0);
  EXPECT_EQ(j.at("saccades")[0].at("frames_not_judged"), 0);
  EXPECT_NE(
      slow.markdown.find(fmt::format("did not fit the budget: deadline: {} of {} frames. Each is judged", lowered, loop.timeline.size())),
      std::string::npos)
      << slow.markdown;
  // A size grown back, traced at its own (the budget raised at frame 10: room for sqrt(0.5 · 25 / 30)
  // of the size, at once on the model clock): judged against references traced at that size
  const LatencyReport grown = run(30, [](RealtimeLoop& rt, int frame) {
    if (frame == 10) rt.set_budget_ms(25);
  });
  const LatencyLoop& regrown = grown.recordings.front().loops.front();
  const double grown_scale = std::sqrt(0.5 * 25 / 30);
  int at_grown = 0;
  for (const LatencyFrame& f : regrown.timeline) at_grown += std::abs(f.scale - grown_scale) < 1e-9 ? 1 : 0;
  EXPECT_GT(at_grown, static_cast<int>(regrown.timeline.size()) / 2);
  EXPECT_EQ(regrown.frames_lowered, static_cast<int>(regrown.timeline.size()));
  expect_judged(regrown);
  // A loop that keeps its size: none, and no such line
  const LatencyReport fits = run(3);
  EXPECT_EQ(fits.recordings.front().loops.front().frames_lowered, 0);
  EXPECT_EQ(fits.markdown.find("Frames at a lowered size"), std::string::npos);
}

// A drawn saccade whose fovea every deadline loop had ready at its landing shows no wait: the note
// names the saccade the first deadline loop waited longest for (one never converged counts as
// longest); no note where the drawn one shows a wait, or where nothing was drawn.
TEST(LatencyTimeline, APictureWithoutAWaitNamesTheSaccadeThatWaitedLongest) {
  const auto saccades = [](std::vector<std::optional<double>> waits) {
    std::vector<LatencySaccade> out(waits.size());
    for (size_t k = 0; k < waits.size(); ++k) out[k].converged_ms = waits[k];
    return out;
  };
  LatencyReport report;
  report.recordings.resize(1);
  LatencyRecording& r = report.recordings.front();
  r.recording = "rec.asc";
  r.loops.resize(3);
  r.loops[0].name = "whole-frame";  // (always waits: not what the picture is about)
  r.loops[0].saccades = saccades({300.0, 250.0, 280.0, 310.0});
  r.loops[1].name = "deadline";
  r.loops[1].saccades = saccades({0.0, 17.0, 50.0, 0.0});
  r.loops[2].name = "deadline+prediction";
  r.loops[2].saccades = saccades({0.0, 0.0, 33.0, 0.0});
  EXPECT_EQ(latency_timeline_note(report, 0, "--timeline-saccade "), "");  // nothing drawn
  r.drawn = 0;
  EXPECT_EQ(latency_timeline_note(report, *r.drawn, "--timeline-saccade "),
            "saccade 0's fovea was ready at its landing in every deadline loop, so its picture shows no wait; the deadline loop "
            "waited longest for saccade 2 (50 ms): --timeline-saccade 2");
  r.drawn = 1;  // the deadline loop waits for it: the picture shows that
  EXPECT_EQ(latency_timeline_note(report, *r.drawn, "--timeline-saccade "), "");
  r.drawn = 3;  // a saccade past the last was asked for: the last is drawn, and that is said
  EXPECT_EQ(latency_timeline_note(report, 50, "--timeline-saccade "),
            "saccade 50 was asked for, and rec.asc's segment judged 4 (0–3): the last is drawn; saccade 3's fovea was ready at its "
            "landing in every deadline loop, so its picture shows no wait; the deadline loop waited longest for saccade 2 (50 ms): "
            "--timeline-saccade 2");
  r.loops[1].saccades[3].converged_ms = 10.0;
  EXPECT_EQ(latency_timeline_note(report, 50, "--timeline-saccade "),
            "saccade 50 was asked for, and rec.asc's segment judged 4 (0–3): the last is drawn");
  r.loops[1].saccades[3].converged_ms = 0.0;
  r.drawn = 3;
  r.loops[1].saccades[1].converged_ms.reset();  // never converged within the segment: the longest
  EXPECT_NE(
      latency_timeline_note(report, *r.drawn, "timeline_saccade=").find("saccade 1 (not converged within the segment): timeline_saccade=1"),
      std::string::npos);
  for (LatencyLoop& loop : r.loops)
    for (LatencySaccade& s : loop.saccades) s.converged_ms = 0.0;
  EXPECT_EQ(latency_timeline_note(report, *r.drawn, "--timeline-saccade "),
            "saccade 3's fovea was ready at its landing in every deadline loop, so its picture shows no wait (nor did any other "
            "landing in rec.asc's segment wait)");
}

// A segment asked past the recording's last sample ends there, and says so: its frames would have
// shown the gaze held where the recording left it, judged as if the eye had stayed. A segment with
// no saccade gives dashes where the medians of its saccades would be, not "nan".
TEST(LatencySegment, ASegmentPastTheRecordingsEndIsCutThereAndSaysSo) {
  std::string csv = "t,x,y\n";  // 0.5 s at 500 Hz, a fixation with the tracker's noise
  for (int i = 0; i < 250; ++i) csv += fmt::format("{},{},{}\n", i / 500.0, 640 + 0.3 * (i % 3), 512 - 0.2 * (i % 2));
  const Scene scene = make_builtin_scene("box");
  LatencyParams p = model_clock_params(84, 52, 16, 1, 3);
  p.loops = {"deadline"};
  const std::vector<Recording> recordings = {parse_recording(csv, "short.csv")};
  std::vector<std::string> said;
  const LatencyReport report = bench_latency(scene, "builtin:box", scene.cameras.front(), ComputeDevice::cpu, 1, recordings, p,
                                             [&](const std::string& line) { said.push_back(line); });
  const LatencyRecording& r = report.recordings.front();
  EXPECT_TRUE(r.cut);
  EXPECT_DOUBLE_EQ(r.begin_s, 0.0);
  EXPECT_NEAR(r.end_s, 0.498, 1e-9);
  // A frame a refresh over the 0.498 s, not over the 3 s asked for
  ASSERT_EQ(r.loops.size(), 1u);
  EXPECT_GE(r.loops[0].frames, 29);
  EXPECT_LE(r.loops[0].frames, 31);
  const nlohmann::json& j = report.json["recordings"][0];
  EXPECT_TRUE(j["segment_cut"].get<bool>());
  EXPECT_NEAR(j["segment_s"][1].get<double>(), 0.498, 1e-9);
  bool line = false;
  for (const std::string& l : said)
    line = line || (l.find("short.csv") != std::string::npos && l.find(", where the recording ends (3 s") != std::string::npos);
  EXPECT_TRUE(line);
  EXPECT_NE(report.markdown.find("0.0–0.5 s, where the recording ends (3 s asked for from 0 s);"), std::string::npos) << report.markdown;
  EXPECT_EQ(report.markdown.find("nan"), std::string::npos) << report.markdown;
  EXPECT_NE(report.markdown.find("median duration — ms"), std::string::npos) << report.markdown;
  // Within the recording: not cut, and the note is absent
  p.duration_s = 0.25;
  const LatencyReport within = bench_latency(scene, "builtin:box", scene.cameras.front(), ComputeDevice::cpu, 1, recordings, p, {});
  EXPECT_FALSE(within.recordings.front().cut);
  EXPECT_DOUBLE_EQ(within.recordings.front().end_s, 0.25);
  EXPECT_EQ(within.markdown.find("where the recording ends"), std::string::npos);
  EXPECT_LE(within.recordings.front().loops[0].frames, 16);
}

}  // namespace
}  // namespace foveal
