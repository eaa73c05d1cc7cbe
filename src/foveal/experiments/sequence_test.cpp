// Tests of the sequence mode of `bench quality`.
#include "foveal/experiments/sequence.h"
#include "foveal/render/frame_renderer.h"
#include "foveal/util/error.h"

#include <gtest/gtest.h>

using namespace foveal;

TEST(QualitySequence, TemporalReuseCastsFewerRaysAtTheSameErrorOnAStillCamera) {
  const Scene box = make_builtin_scene("box");
  const std::unique_ptr<FrameRenderer> renderer = make_frame_renderer(box, ComputeDevice::cpu);
  QualitySequenceParams q;
  q.render.width = 80, q.render.height = 50, q.render.foveation.max_rays = 32;
  q.reference_rays = 32;
  q.cameras = orbit_path(box.cameras.front(), 0.0, 6);
  q.gazes = fixation_path(glm::dvec2(40, 25), q.render, 6, 3);
  ASSERT_EQ(q.gazes.size(), 6u);
  EXPECT_EQ(q.gazes[0], q.gazes[2]);
  EXPECT_NE(q.gazes[2], q.gazes[3]);  // the fixation moves after 3 frames
  const QualitySequenceResult r = run_quality_sequence(box, *renderer, q);
  ASSERT_EQ(r.configs.size(), 5u);
  const SequenceConfigResult& paper = r.configs[0];
  const SequenceConfigResult& temporal = r.configs[2];
  EXPECT_EQ(paper.name, "paper");
  EXPECT_EQ(temporal.name, "temporal");
  EXPECT_GT(temporal.ray_ratio, 2.0 * paper.ray_ratio);  // n/F = n/4 rays a frame after the first
  EXPECT_LT(temporal.weighted_ratio, 1.2 * paper.weighted_ratio);
  EXPECT_LT(temporal.flicker_ratio, paper.flicker_ratio + 0.5);
  EXPECT_EQ(r.configs[0].frame_weighted_ratio.size(), 6u);
  // An orbit moves the eye on a circle about the look point
  const auto path = orbit_path(box.cameras.front(), 90.0, 2);
  const Camera& c = box.cameras.front();
  EXPECT_NEAR(glm::length(path[1].eye - c.look), glm::length(c.eye - c.look), 1e-4);
  EXPECT_NEAR(glm::dot(path[1].eye - c.look, c.eye - c.look), (c.eye.y - c.look.y) * (c.eye.y - c.look.y), 1e-3);
  // Bad input
  q.cameras.resize(1);
  EXPECT_THROW(run_quality_sequence(box, *renderer, q), Error);
}

TEST(QualitySequence, ConfigurationListsAreReadInAnyOrderAndBadOnesNamed) {
  const auto c = parse_reuse_configs("--configs", "paper, denoise+adaptive ,temporal+denoise+adaptive,adaptive");
  ASSERT_EQ(c.size(), 4u);
  EXPECT_EQ(c[0].name, "paper");
  EXPECT_FALSE(c[0].reuse.any());
  EXPECT_EQ(c[1].name, "adaptive+denoise");
  EXPECT_TRUE(c[1].reuse.adaptive && c[1].reuse.denoise && !c[1].reuse.temporal);
  EXPECT_EQ(c[2].name, "temporal+adaptive+denoise");
  EXPECT_TRUE(c[2].reuse.adaptive && c[2].reuse.denoise && c[2].reuse.temporal);
  EXPECT_EQ(c[3].name, "adaptive");
  EXPECT_TRUE(c[3].reuse.adaptive && !c[3].reuse.denoise);
  // The defaults are what the names say
  for (const ReuseConfig& d : default_sequence_configs()) {
    const auto again = parse_reuse_configs("--configs", d.name);
    ASSERT_EQ(again.size(), 1u);
    EXPECT_EQ(again[0].name, d.name);
    EXPECT_EQ(again[0].reuse.adaptive, d.reuse.adaptive);
    EXPECT_EQ(again[0].reuse.denoise, d.reuse.denoise);
    EXPECT_EQ(again[0].reuse.temporal, d.reuse.temporal);
  }
  auto message = [](const std::string& list) {
    try {
      parse_reuse_configs("--configs", list);
    } catch (const Error& e) {
      return std::string(e.what());
    }
    return std::string("accepted");
  };
  EXPECT_NE(message("adaptive+blur").find("unknown configuration 'blur' in 'adaptive+blur'"), std::string::npos);
  EXPECT_NE(message("adaptive+adaptive").find("names adaptive twice"), std::string::npos);
  EXPECT_NE(message("paper+denoise").find("joins paper"), std::string::npos);
  EXPECT_NE(message("denoise,denoise").find("denoise is listed twice"), std::string::npos);
  EXPECT_NE(message("paper,,denoise").find("unknown configuration ''"), std::string::npos);
  EXPECT_NE(message("").find("--configs"), std::string::npos);
}
