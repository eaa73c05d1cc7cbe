// Errors in the caller's words: the library names its parameters, a front end renames them.
#include "foveal/util/error.h"

#include <gtest/gtest.h>

using namespace foveal;

TEST(ErrorWords, TheLeadingParameterAndOtherParametersAreRenamedNothingElse) {
  static constexpr ParameterName kCli[] = {
      {"max_rays", "--max-rays"}, {"min_rays", "--min-rays"}, {"size", "--size"}, {"device", "--device"}, {"device cuda", "--device cuda"}};
  EXPECT_EQ(in_words("max_rays: must be in [0, 65535], got -1", kCli), "--max-rays: must be in [0, 65535], got -1");
  // a snake_case parameter mentioned later is renamed too; a plain word ("size") only where it leads
  EXPECT_EQ(in_words("min_rays: must be in [0, max_rays = 400], got 500", kCli), "--min-rays: must be in [0, --max-rays = 400], got 500");
  EXPECT_EQ(in_words("size: 0x0 is too small for the size asked", kCli), "--size: 0x0 is too small for the size asked");
  // the longest name that leads wins; a name inside another word is left alone
  EXPECT_EQ(in_words("device cuda: unavailable: no driver", kCli), "--device cuda: unavailable: no driver");
  EXPECT_EQ(in_words("device: unknown device 'x'", kCli), "--device: unknown device 'x'");
  EXPECT_EQ(in_words("a.json: max_rays_total is not max_rays", kCli), "a.json: max_rays_total is not --max-rays");
  // a message that names a file, or a parameter the front end does not know, is unchanged
  EXPECT_EQ(in_words("scene.json:3: unknown key", kCli), "scene.json:3: unknown key");
  EXPECT_EQ(in_words("gamma: must be > 0, got 0", kCli), "gamma: must be > 0, got 0");
}
