// Replay through the device-neutral renderer: each frame is the renderer's frame for the gaze the
// fixation filter gives at that frame (replay_gazes), with temporal reuse building on its history.
#include "foveal/experiments/replay.h"

#include "foveal/render/reuse.h"

#include <gtest/gtest.h>

#include <cstring>
#include <string>

using namespace foveal;

namespace {

// 1.2 s of gaze at 250 Hz: a fixation on the left, a saccade, a fixation on the right (screen px).
Recording two_fixations() {
  std::string csv = "t,x,y\n";
  for (int i = 0; i < 300; ++i) {
    const double t = i / 250.0;
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
