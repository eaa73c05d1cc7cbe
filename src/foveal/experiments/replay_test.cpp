// Replay through the device-neutral renderer: each frame is the renderer's frame for the gaze the
// fixation filter gives at that frame (replay_gazes), with temporal reuse building on its history.
#include "foveal/experiments/replay.h"

#include "foveal/render/reuse.h"

#include <gtest/gtest.h>

#include <cstring>
#include <memory>
#include <string>

using namespace foveal;

namespace {

// 1.2 s of gaze at `hz` (250): a fixation on the left, a saccade, a fixation on the right (screen px).
Recording two_fixations(int hz = 250) {
  std::string csv = "t,x,y\n";
  for (int i = 0; i < hz * 6 / 5; ++i) {
    const double t = static_cast<double>(i) / hz;
    const double x = t < 0.6 ? 500 : 1200, y = 520;
    csv += std::to_string(t) + "," + std::to_string(x + (i % 3)) + "," + std::to_string(y + (i % 2)) + "\n";
  }
  return parse_recording(csv, "two-fixations.csv");
}

}  // namespace

TEST(Replay, FramesAreTheRenderersFramesForTheFilteredGaze) {
  const Scene box = make_builtin_scene("box");
  const Tracer tracer(box);
  const Recording recording = two_fixations();
  RenderParams p;
  p.width = 84, p.height = 52, p.foveation.max_rays = 32;
  p.reuse.temporal = true;
  ReplaySettings s;
  s.fps = 10;
  const Display display;
  const std::vector<ReplayFrame> gazes = replay_gazes(recording, display, p, s);
  ASSERT_EQ(static_cast<int>(gazes.size()), replay_frame_count(recording, s));
  // The gaze follows the recording: left half, then right half
  EXPECT_LT(gazes[4].render_gaze.x, 0.5 * p.width);
  EXPECT_GT(gazes.back().render_gaze.x, 0.5 * p.width);

  const std::unique_ptr<FrameRenderer> renderer = make_frame_renderer(box, ComputeDevice::cpu);
  const Camera camera = box.cameras.front();
  AoHistory history;  // the same frames by hand: render_frame with a history of the test's own
  int frames = 0;
  const ReplaySummary summary =
      replay_recording(recording, display, *renderer, camera, p, s, [&](const ReplayFrame& f, const Frame& frame) {
        ASSERT_LT(f.index, static_cast<int>(gazes.size()));
        EXPECT_EQ(f.render_gaze, gazes[f.index].render_gaze);
        EXPECT_FALSE(f.reused);  // temporal: every frame adds rays
        RenderParams q = p;
        q.gaze_px = f.render_gaze;
        const Frame expected = render_frame(tracer, box, camera, q, {}, &history);
        EXPECT_EQ(std::memcmp(frame.color.pixels.data(), expected.color.pixels.data(), expected.color.pixels.size() * sizeof(float)), 0)
            << "frame " << f.index;
        EXPECT_EQ(f.ao_rays, expected.stats.ao_rays);
        ++frames;
      });
  EXPECT_EQ(frames, static_cast<int>(gazes.size()));
  EXPECT_EQ(summary.frames, frames);
  EXPECT_EQ(renderer->history_frames(), static_cast<uint32_t>(frames));
}

// replay --realtime: a frame per refresh from the real-time loop, the fovea at the raw gaze (no
// fixation filter's delay), every frame at the render size with the loop's rays.
TEST(Replay, RealtimeFramesFollowTheRawGazeThroughTheLoop) {
  const Scene box = make_builtin_scene("box");
  const Recording recording = two_fixations();
  RenderParams p;
  p.width = 168, p.height = 105, p.foveation.max_rays = 64;
  ReplaySettings s;
  s.fps = 60;
  s.realtime = true;
  const Display display;
  const std::unique_ptr<FrameRenderer> renderer = make_frame_renderer(box, ComputeDevice::cpu);
  std::vector<ReplayFrame> frames;
  const ReplaySummary summary = replay_recording_realtime(recording, display, *renderer, box, box.cameras.front(), p, s,
                                                          [&](const ReplayFrame& f, const Frame& frame) {
                                                            EXPECT_EQ(frame.color.width, 168);
                                                            frames.push_back(f);
                                                          });
  ASSERT_EQ(summary.frames, replay_frame_count(recording, s));
  ASSERT_EQ(static_cast<int>(frames.size()), summary.frames);
  EXPECT_GT(summary.ao_rays, 0u);
  // Before the saccade the fovea is on the left fixation, a frame after it on the right one
  // (500 and 1200 of 1680 screen px → 50 and 120 render px)
  for (const ReplayFrame& f : frames) {
    if (f.t_s < 0.55) EXPECT_NEAR(f.render_gaze.x, 50, 1.5) << f.t_s;
    if (f.t_s > 0.62) EXPECT_NEAR(f.render_gaze.x, 120, 1.5) << f.t_s;
  }
}

// replay --realtime's summary says how small the loop rendered and why (its note at the smallest
// size), and what the samples left its predictor: nothing at 250 Hz, too late to gain much at 60.
TEST(Replay, RealtimeSummarySaysTheSmallestSizeAndWhy) {
  const Scene box = make_builtin_scene("box");
  RenderParams p;
  p.width = 168, p.height = 105, p.foveation.max_rays = 16;
  ReplaySettings s;
  s.fps = 60;
  s.realtime = true;
  s.duration_s = 0.5;
  const Display display;
  const std::unique_ptr<FrameRenderer> renderer = make_frame_renderer(box, ComputeDevice::cpu);
  std::vector<ReplayFrame> frames;
  const auto run = [&](const Recording& recording) {
    double smallest = 1;
    frames.clear();
    const ReplaySummary summary =
        replay_recording_realtime(recording, display, *renderer, box, box.cameras.front(), p, s, [&](const ReplayFrame& f, const Frame&) {
          smallest = std::min(smallest, f.scale);
          frames.push_back(f);
        });
    EXPECT_EQ(summary.min_scale, smallest);
    return summary;
  };
  // a refresh's budget: the base shading of 168x105 fits, the size is kept, and nothing is said
  const ReplaySummary kept = run(two_fixations());
  EXPECT_EQ(kept.min_scale, 1);
  EXPECT_EQ(kept.scale_note, "");
  EXPECT_EQ(kept.gaze_note, "");
  EXPECT_EQ(kept.held_note, "");
  // a budget no base shading fits: the loop renders smaller, and the summary keeps its reason
  s.budget_ms = 0.02;
  const ReplaySummary lowered = run(two_fixations());
  EXPECT_LT(lowered.min_scale, 1);
  EXPECT_NE(lowered.scale_note.find("of the 0.02 ms frame budget at 168x105: rendering at"), std::string::npos) << lowered.scale_note;
  EXPECT_GT(lowered.late, 0);
  // … and each frame's fovea is where the gaze was, at the size asked for, the frame that chose the
  // smaller size included (its own size, not the next frame's: 50 px read as 50 / 0.6)
  for (const ReplayFrame& f : frames)
    if (f.t_s < 0.55) EXPECT_NEAR(f.render_gaze.x, 50, 1.5) << f.t_s << " at scale " << f.scale;
  // … unless the size may not go lower (min_scale 1: a stimulus that keeps its resolution): its
  // frames come late, and the summary says why. (The lowered run's may say so too where even a
  // quarter of the size does not fit the 0.02 ms, as under the sanitizers)
  s.min_scale = 1;
  const ReplaySummary held = run(two_fixations());
  EXPECT_EQ(held.min_scale, 1);
  EXPECT_EQ(held.scale_note, "");
  EXPECT_GT(held.late, 0);
  EXPECT_NE(held.held_note.find("may not go below 100 % of 168x105 (min_scale): frames come late"), std::string::npos) << held.held_note;
  for (const ReplayFrame& f : frames) EXPECT_EQ(f.scale, 1.0);
  s.min_scale = kDefaultMinScale;
  // 60-Hz samples: the predictor's note reaches the summary
  s.budget_ms.reset();
  const ReplaySummary slow = run(two_fixations(60));
  EXPECT_NE(slow.gaze_note.find("(60 Hz)"), std::string::npos) << slow.gaze_note;
}
