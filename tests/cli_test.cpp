// Tests of the `foveal` command line as a user runs it: outputs, the stats contract, bad input.
#include "cli_helpers.h"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <sys/wait.h>

#include <array>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>

using namespace foveal_test;
namespace fs = std::filesystem;

namespace {

// Each command line fails with one line, "foveal: error: …" holding `needle`, and no crash.
void expect_clear_errors(const std::vector<std::pair<std::string, std::string>>& cases) {
  for (const auto& [args, needle] : cases) {
    const CliRun r = foveal_test::foveal(args);
    EXPECT_NE(r.status, 0) << args;
    EXPECT_LT(r.status, 128) << args << " crashed";
    EXPECT_EQ(lines(r.err), 1u) << args << ": " << r.err;
    EXPECT_NE(r.err.find(needle), std::string::npos) << args << ": " << r.err;
    EXPECT_EQ(r.err.rfind("foveal: error: ", 0), 0u) << args << ": " << r.err;
  }
}

}  // namespace

TEST(Cli, RenderWritesImageMaskPlotAovsAndContractStats) {
  const CliRun r = foveal_test::foveal(
      "render --size 96x60 --max-rays 8 --gaze 10,10 -o img.png --mask mask.png --acuity-plot fig4.svg "
      "--aov ao=ao.pfm,depth=depth.exr,position=p.pfm,normal=n.exr --stats stats.json");
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_NE(r.out.find("AO rays"), std::string::npos);
  for (const char* f : {"img.png", "mask.png", "ao.pfm", "depth.exr", "p.pfm", "n.exr"}) EXPECT_GT(fs::file_size(scratch(f)), 100u) << f;
  std::stringstream svg;
  svg << std::ifstream(scratch("fig4.svg")).rdbuf();
  EXPECT_NE(svg.str().find("<polyline"), std::string::npos);
  const auto j = nlohmann::json::parse(std::ifstream(scratch("stats.json")));
  EXPECT_EQ(j["mode"], "foveated");
  EXPECT_EQ(j["width"], 96);
  EXPECT_EQ(j["height"], 60);
  EXPECT_EQ(j["gaze_px"][0], 10.0);
  EXPECT_EQ(j["seed"], 1);
  EXPECT_GE(j["threads"].get<int>(), 1);
  EXPECT_GE(j["scene"]["triangles"].get<int>(), 100000);
  EXPECT_GT(j["scene"]["build_ms"].get<double>(), 0);
  EXPECT_EQ(j["rays"]["primary"], 96 * 60);
  EXPECT_EQ(j["rays"]["total"].get<uint64_t>(), j["rays"]["primary"].get<uint64_t>() + j["rays"]["ao"].get<uint64_t>());
  EXPECT_EQ(j["ao_rays_per_pixel"]["max"], 8);
  EXPECT_LE(j["ao_rays_per_pixel"]["mean"].get<double>(), 8.0);
  for (const char* k : {"primary", "ao", "shade", "total"}) EXPECT_GE(j["time_ms"][k].get<double>(), 0) << k;
}

TEST(Cli, FullModeCastsMaxRaysEverywhere) {
  const CliRun r = foveal_test::foveal("render --scene builtin:plane --size 32x20 --mode full --max-rays 5 -o f.png --stats full.json -q");
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_EQ(r.out, "");
  const auto j = nlohmann::json::parse(std::ifstream(scratch("full.json")));
  EXPECT_EQ(j["ao_rays_per_pixel"]["min"], 5);
  EXPECT_EQ(j["mode"], "full");
}

TEST(Cli, BadInputGivesOneClearLineAndNonZeroExit) {
  const std::vector<std::pair<std::string, std::string>> cases = {
      {"render --size 0x10", "--size"},
      {"render --size abc", "--size"},
      {"render --display 0,30,60", "display width"},
      {"render --display 47.5,30", "--display"},
      {"render --mode half", "unknown mode"},
      {"render --max-rays -3", "--max-rays"},
      {"render --min-rays 10 --max-rays 5", "--min-rays"},
      {"render --gamma 0", "--gamma"},
      {"render --ao-distance -1", "--ao-distance"},
      {"render --gaze 1", "--gaze"},
      {"render --scene missing.obj", "missing.obj: no such file"},
      {"render --scene builtin:nothing", "unknown built-in"},
      {"render --camera nope", "no camera named 'nope'"},
      {"render --eye 0,0,1", "--eye and --look"},
      {"render --fov 200", "--fov"},
      // Every documented range, at both ends (and just beyond)
      {"render --fov 0", "--fov"},
      {"render --fov 180", "--fov"},
      {"render --fov -5", "--fov"},
      {"render --size 16385x10", "--size"},
      {"render --max-rays 65536", "--max-rays"},
      {"render --min-rays -1", "--min-rays"},
      {"render --gamma -1", "--gamma"},
      {"render --beta -0.1", "--beta"},
      {"render --ellipse 0", "--ellipse"},
      {"render --ambient-constant -0.5", "--ambient-constant"},
      {"render --ao-distance 0", "--ao-distance"},
      {"render --display 47.5,0,60", "display"},
      {"render --display 47.5,30,0", "viewing distance"},
      {"render --threads 4097", "threads"},
      {"render --threads -1", "threads"},
      {"render --bogus", "bogus"},
      {"render --aov colour=x.pfm --size 8x8 --max-rays 1", "unknown buffer"},
      {"render -o /nonexistent/dir/x.png --size 8x8 --max-rays 1", "/nonexistent/dir/x.png"},
      // A command that is none: named, with those there are; the help pointed to is the command's
      {"bench nothing", "'nothing' is no command of foveal bench (the commands: ao, vision, blur, quality, latency, events, stalls)"},
      {"bench", "a command is needed: ao, vision,"},
      {"nothing", "'nothing' is no command of foveal (the commands: render, bench,"},
      {"", "a command is needed: render, bench,"},
      {"render --bogus", "(see 'foveal render --help')"},
      {"replay -o x", "--gaze is required (see 'foveal replay --help')"},
      {"bench latency --bogus", "(see 'foveal bench latency --help')"},
  };
  expect_clear_errors(cases);
}

// Every option that names an output file is checked when the command line is read: a bench's
// --json in a missing folder used to fail only after its minutes of work.
TEST(Cli, OutputFilesAreCheckedBeforeTheWork) {
  const std::string missing = (fs::temp_directory_path() / "foveal-no-such-folder" / "out").string();
  const std::vector<std::pair<std::string, std::string>> cases = {
      {"bench latency --json " + missing + ".json", "--json"},
      {"bench latency --markdown " + missing + ".md", "--markdown"},
      {"bench latency --timeline timeline.gif", "--timeline"},
      {"bench ao --json " + missing + ".json", "--json"},
      {"bench quality --markdown " + missing + ".md", "--markdown"},
      {"bench events --json " + missing + ".json", "--json"},
      {"bench stalls --json " + missing + ".json", "--json"},
      {"bench vision --json " + missing + ".json", "--json"},
      {"bench vision --markdown " + missing + ".md", "--markdown"},
      {"bench quality --plot pareto.pdf", "--plot"},
      {"gaze recording.csv --samples " + missing + ".csv", "--samples"},
      {"render --stats " + missing + ".json", "--stats"},
      {"render -o render.tif", "--output"},
      {"render --acuity-plot plot.pdf", "--acuity-plot"},
      {"gaze recording.csv --events nhr --events-out " + missing + ".tsv", "--events-out"},
      {"replay --gaze recording.csv -o frames --stats " + missing + ".json", "--stats"},
      {"replay --gaze recording.csv -o frames --video " + missing + ".mp4", "--video"},
      {"simulate -o steps --video " + missing + ".mp4", "--video"},
      {"compare a.png --reference b.png --plot plot.pdf", "--plot"},
      {"perceive a.png -o b.png --amsler " + missing + ".png", "--amsler"},
      {"view --frames 1 --screenshot " + missing + ".png", "--screenshot"},
  };
  for (const auto& [args, needle] : cases) {
    const CliRun r = foveal_test::foveal(args);
    EXPECT_NE(r.status, 0) << args;
    EXPECT_EQ(lines(r.err), 1u) << args << ": " << r.err;
    EXPECT_EQ(r.err.rfind("foveal: error: " + needle + ": ", 0), 0u) << args << ": " << r.err;
    EXPECT_EQ(r.out, "") << args << ": the work started";
  }
}

// One rule for every number an option takes: finite, and an unsigned one not negative — also
// where the chosen mode leaves the option unused (perceive's fixation filter without --gaze ran
// with --ivt-threshold nan as if it had not been given; CLI11 read --seed -1 as 2^64 − 1).
TEST(Cli, EveryNumberIsFiniteAndNoUnsignedOneNegative) {
  const std::string rec = scratch("finite.csv");
  std::ofstream(rec) << "t,x,y\n0,100,100\n0.002,101,100\n0.004,102,100\n";
  const std::vector<std::pair<std::string, std::string>> cases = {
      {"render --gamma nan", "--gamma: must be a finite number, got nan"},
      {"render --beta inf", "--beta: must be a finite number, got inf"},
      {"render --seed -1", "--seed: must be 0 or more, got -1"},
      {"perceive a.png -o b.png --ivt-threshold nan", "--ivt-threshold: must be a finite number"},
      {"perceive " + rec + " -o b.png --ivt-threshold -1", "--ivt-threshold"},
      {"simulate -o s --velocity-window-ms -1", "--velocity-window-ms"},
      {"simulate -o s --ambient -1", "--ambient: must be 0 or more, got -1"},  // (not CLI11's range up to the largest double)
      {"gaze " + rec + " --ek-lambda -2", "--ek-lambda"},
      {"gaze " + rec + " --max-blink-ms nan", "--max-blink-ms: must be a finite number"},
      {"bench latency --min-amplitude -inf", "--min-amplitude: must be a finite number, got -inf"},
      {"bench latency --timeline-saccade -1", "--timeline-saccade: must be 0 or more, got -1"},
      {"bench quality --max-error -1", "--max-error"},
      {"bench latency --tolerance 0", "--tolerance: must be more than 0, got 0"},
      {"bench quality --tolerance -0.5", "--tolerance: must be more than 0, got -0.5"},
      {"view --frame-budget-ms -1", "--frame-budget-ms"},  // (without --realtime: before any window opens)
      {"view --starvation -1", "--starvation"},
      {"bench quality --max-flicker 0", "--max-flicker"},
  };
  expect_clear_errors(cases);
  // inf where a text option documents it: the AO rays' length
  const CliRun inf = foveal_test::foveal("render --size 16x10 --max-rays 2 --ao-distance inf -o inf.png -q");
  EXPECT_EQ(inf.status, 0) << inf.err;
}

TEST(Cli, MalformedAndEmptyMeshesAreErrorsNotCrashes) {
  std::ofstream(scratch("empty.obj"));
  std::ofstream(scratch("junk.obj")) << "v 1 2\nf 1 2 3 4 5\nthis is not obj\n";
  std::ofstream(scratch("junk.ply")) << "ply\nformat binary_little_endian 1.0\nelement vertex 100\nproperty float x\nend_header\n\x01";
  std::ofstream(scratch("bad.json")) << "{\"meshes\": [ {\"file\": 3} ]}";
  for (const char* f : {"empty.obj", "junk.obj", "junk.ply", "bad.json"}) {
    const CliRun r = foveal_test::foveal(std::string("render --size 8x8 --scene ") + f);
    EXPECT_NE(r.status, 0) << f;
    EXPECT_LT(r.status, 128) << f << " crashed";
    EXPECT_EQ(lines(r.err), 1u) << f << ": " << r.err;
    EXPECT_NE(r.err.find(f), std::string::npos) << f << ": " << r.err;
  }
}

TEST(Cli, SameSeedSameImageWhateverTheThreads) {
  ASSERT_EQ(foveal_test::foveal("render --size 48x32 --max-rays 6 --threads 1 --aov ao=t1.pfm -o t1.png -q").status, 0);
  ASSERT_EQ(foveal_test::foveal("render --size 48x32 --max-rays 6 --threads 2 --aov ao=t2.pfm -o t2.png -q").status, 0);
  auto bytes = [](const char* f) {
    std::stringstream s;
    s << std::ifstream(scratch(f), std::ios::binary).rdbuf();
    return s.str();
  };
  EXPECT_EQ(bytes("t1.pfm"), bytes("t2.pfm"));
  EXPECT_EQ(bytes("t1.png"), bytes("t2.png"));
}

// Peak memory per triangle of a render on a large indexed mesh (a 1,000,000-triangle binary PLY
// height field) stays at most 150 bytes above the same render of a tiny scene (it was ~370: the
// importer's vertex joining, copies held together, the index buffer copied into Embree).
TEST(Cli, PeakMemoryPerTriangleOfALargeMesh) {
#if defined(__SANITIZE_ADDRESS__)
  GTEST_SKIP() << "skipped under AddressSanitizer (its shadow memory is part of the resident set)";
#else
  const int n = 708;  // n×n vertices: 2·707² = 999,698 triangles
  {
    std::ofstream ply(scratch("grid.ply"), std::ios::binary);
    ply << "ply\nformat binary_little_endian 1.0\nelement vertex " << n * n
        << "\nproperty float x\nproperty float y\nproperty float z\nelement face " << 2 * (n - 1) * (n - 1)
        << "\nproperty list uchar int vertex_indices\nend_header\n";
    for (int j = 0; j < n; ++j)
      for (int i = 0; i < n; ++i) {
        const float v[3] = {2.0f * i / (n - 1) - 1, 0.1f * std::sin(0.05f * i) * std::cos(0.04f * j), 2.0f * j / (n - 1) - 1};
        ply.write(reinterpret_cast<const char*>(v), sizeof v);
      }
    for (int j = 0; j + 1 < n; ++j)
      for (int i = 0; i + 1 < n; ++i) {
        const int a = j * n + i;
        for (const std::array<int, 3>& t : {std::array<int, 3>{a, a + n, a + 1}, std::array<int, 3>{a + 1, a + n, a + n + 1}}) {
          const unsigned char three = 3;
          ply.write(reinterpret_cast<const char*>(&three), 1);
          ply.write(reinterpret_cast<const char*>(t.data()), 3 * sizeof(int));
        }
      }
  }
  auto peak = [](const std::string& scene, const char* stats) {
    const CliRun r =
        foveal_test::foveal("render --scene " + scene + " --size 420x262 --max-rays 4 --device cpu -q -o m.png --stats " + stats);
    EXPECT_EQ(r.status, 0) << r.err;
    return nlohmann::json::parse(std::ifstream(scratch(stats)))["peak_rss_mib"].get<double>();
  };
  const double base = peak("builtin:plane", "mem0.json"), big = peak("grid.ply", "mem1.json");
  const double per_triangle = (big - base) * 1024 * 1024 / 999698;
  std::printf("peak %.1f MiB, baseline %.1f MiB: %.1f bytes per triangle\n", big, base, per_triangle);
  EXPECT_LE(per_triangle, 150.0);
#endif
}

// The library names its parameters (util/error.h); the command line says them as its options, in
// the options' units, and never lets a library name through.
TEST(Cli, LibraryErrorsNameTheOptionsTheUserTyped) {
  const std::pair<std::string, std::string> cases[] = {
      {"render --size 40x30 --ellipse -1 -o e.png", "--ellipse: must be > 0, got -1"},
      {"render --size 40x30 --max-rays 20 --min-rays 30 -o e.png", "--min-rays: must be in [0, --max-rays = 20], got 30"},
      {"render --size 40x30 --gaze nan,1 -o e.png", "--gaze: "},
      {"simulate --scene builtin:plane --size 40x30 --steps 1 -o e --pupil 20", "--pupil: must be in (0, 10] mm, got 20"},
      {"simulate --scene builtin:plane --size 40x30 --steps 1 -o e --saccade-max 0", "--saccade-max: must be positive degrees, got 0"},
      {"gaze ../x.csv --gap-fill-ms -5", "--gap-fill-ms: must be zero or positive, got -5"},  // in ms, as typed
      {"gaze ../x.csv --pursuit-velocity 40", "--pursuit-velocity: must be below the saccade threshold --ivt-threshold (30 deg/s), got 40"},
  };
  for (const auto& [args, expected] : cases) {
    const CliRun r = foveal_test::foveal(args);
    EXPECT_EQ(r.status, 1) << args;
    EXPECT_EQ(lines(r.err), 1u) << args << "\n" << r.err;
    EXPECT_NE(r.err.find("foveal: error: " + expected), std::string::npos) << args << "\n" << r.err;
    for (const char* library : {"ellipse_ratio", "min_rays", "max_rays", "gaze_px", "pupil_diameter_mm", "saccade_max_deg", "gap_fill_s",
                                "pursuit_velocity_deg_s", "velocity_threshold_deg_s"})
      EXPECT_EQ(r.err.find(library), std::string::npos) << args << "\n" << r.err;
  }
}

namespace foveal_test {

// Issue 36, finding 6: a gaze far from the image is one clear line naming --gaze (it overflowed
// the foveation model into the full budget everywhere).
TEST(Cli, AGazeFarFromTheImageIsRefused) {
  expect_one_line_error("render --scene builtin:box --size 64x40 --gaze 1e155,1e155 -o far.png", "--gaze");
  EXPECT_FALSE(fs::exists(scratch("far.png")));
}

}  // namespace foveal_test
