// One rule for an eye (resolve_eye): an explicit option overrides the profile, which overrides the
// default — in simulate, view, perceive and bench vision alike. Before, simulate kept a profile's
// pupil unless --pupil differed from 3.5 (an explicit --pupil 3.5 was ignored), view always
// overwrote it, and bench vision had no --pupil at all.
#include "cli_helpers.h"

#include "foveal/impair/profile.h"
#include "foveal/io/image_io.h"
#include "foveal/util/error.h"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <fstream>
#include <string>

using namespace foveal_test;

namespace {

// A patient whose profile states a 5.5 mm pupil, and nothing else about the optics
std::string patient_profile() {
  fs::create_directories(scratch(""));
  std::ofstream(scratch("pupil-patient.json")) << R"({"age": 40, "eyes": {"OD": {"pupil_mm": 5.5, "refraction": -1}}})";
  return "pupil-patient.json";
}

nlohmann::json read_json(const std::string& name) { return nlohmann::json::parse(std::ifstream(scratch(name))); }

bool have_xvfb() { return std::system("command -v xvfb-run > /dev/null 2>&1") == 0; }

}  // namespace

// The rule itself: the spec gives the eye, a given override replaces it whatever its value.
TEST(EyeRule, AnExplicitValueBeatsTheProfileWhichBeatsTheDefault) {
  const std::string profile = scratch(patient_profile()).string();
  EXPECT_DOUBLE_EQ(foveal::resolve_eye("healthy").eye.pupil_diameter_mm, 3.5);                     // the default
  EXPECT_DOUBLE_EQ(foveal::resolve_eye(profile).eye.pupil_diameter_mm, 5.5);                       // the profile's
  EXPECT_DOUBLE_EQ(foveal::resolve_eye(profile, {3.5, std::nullopt}).eye.pupil_diameter_mm, 3.5);  // explicit, the default's value
  EXPECT_DOUBLE_EQ(foveal::resolve_eye("myopia:-2", {7.0, 20.0}).eye.pupil_diameter_mm, 7.0);
  EXPECT_DOUBLE_EQ(foveal::resolve_eye("myopia:-2", {7.0, 20.0}).eye.image_distance_mm, 20.0);
  EXPECT_DOUBLE_EQ(foveal::resolve_eye(profile, {3.5, std::nullopt}).eye.refraction_d, -1.0);  // the rest stays the profile's
  EXPECT_THROW(foveal::resolve_eye(profile, {12.0, std::nullopt}), foveal::Error);             // validated after the override
  EXPECT_EQ(foveal::optics_json(foveal::resolve_eye(profile).eye)["pupil_mm"], 5.5);
}

TEST(EyeRule, SimulateKeepsAProfilesPupilAndAnExplicitPupilOverridesIt) {
  const std::string profile = patient_profile();
  const std::string common = "simulate --scene builtin:plane --size 64x40 --steps 1 --save-steps 1 -q --eye " + profile;
  ASSERT_EQ(foveal_test::foveal(common + " -o s1 --stats s1.json").status, 0);
  EXPECT_EQ(read_json("s1.json")["optics"]["pupil_mm"], 5.5);
  EXPECT_EQ(read_json("s1.json")["optics"]["refraction_d"], -1.0);
  const CliRun r = foveal_test::foveal(common + " -o s2 --stats s2.json --pupil 3.5");
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_EQ(read_json("s2.json")["optics"]["pupil_mm"], 3.5);  // 3.5, the default's value, is still an explicit choice
  ASSERT_EQ(foveal_test::foveal("simulate --scene builtin:plane --size 64x40 --steps 1 -q -o s3 --stats s3.json").status, 0);
  EXPECT_EQ(read_json("s3.json")["optics"]["pupil_mm"], 3.5);  // no profile, no option: the default
}

TEST(EyeRule, PerceiveKeepsAProfilesPupilAndAnExplicitPupilOverridesIt) {
  const std::string profile = patient_profile();
  foveal::Image im(64, 40, 3);
  for (size_t i = 0; i < im.pixels.size(); ++i) im.pixels[i] = (i % 7) / 7.0f;
  foveal::save_image(im, scratch("stimulus.png").string());
  const CliRun kept = foveal_test::foveal("perceive stimulus.png -o seen1.png --eye " + profile);
  ASSERT_EQ(kept.status, 0) << kept.err;
  EXPECT_NE(kept.out.find("pupil 5.5 mm"), std::string::npos) << kept.out;
  const CliRun overridden = foveal_test::foveal("perceive stimulus.png -o seen2.png --pupil 3.5 --eye " + profile);
  ASSERT_EQ(overridden.status, 0) << overridden.err;
  EXPECT_NE(overridden.out.find("pupil 3.5 mm"), std::string::npos) << overridden.out;
}

TEST(EyeRule, BenchVisionKeepsAProfilesPupilAndAnExplicitPupilOverridesIt) {
  const std::string profile = patient_profile();
  const std::string common = "bench vision --scene builtin:plane --size 48x32 --steps 2 --impairments none --device cpu --eye " + profile;
  ASSERT_EQ(foveal_test::foveal(common + " --json bv1.json").status, 0);
  EXPECT_EQ(read_json("bv1.json")["optics"]["pupil_mm"], 5.5);
  ASSERT_EQ(foveal_test::foveal(common + " --pupil 3.5 --json bv2.json").status, 0);
  EXPECT_EQ(read_json("bv2.json")["optics"]["pupil_mm"], 3.5);
}

TEST(EyeRule, ViewKeepsAProfilesPupilAndAnExplicitPupilOverridesIt) {
  if (!have_xvfb()) GTEST_SKIP() << "skipped: xvfb-run absent (Debian package xvfb)";
  const std::string profile = patient_profile();
  const std::string view =
      "ASAN_OPTIONS=detect_leaks=0 xvfb-run -a -n " + std::to_string(100 + ::getpid() % 800 + 1) + " -s '-screen 0 1280x1024x24'";
  const std::string common = "view --scene builtin:plane --size 64x40 --mode vision --frames 1 --eye " + profile;
  const CliRun kept = run_foveal(view, common + " --screenshot v1.png < /dev/null");
  ASSERT_EQ(kept.status, 0) << kept.err;
  EXPECT_EQ(read_json("v1.json")["settings"]["eye"]["pupil_mm"], 5.5);  // before: overwritten by --pupil's default
  const CliRun overridden = run_foveal(view, common + " --pupil 3.5 --screenshot v2.png < /dev/null");
  ASSERT_EQ(overridden.status, 0) << overridden.err;
  EXPECT_EQ(read_json("v2.json")["settings"]["eye"]["pupil_mm"], 3.5);
}
