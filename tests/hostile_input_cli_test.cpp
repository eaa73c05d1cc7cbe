// Hostile input, round two (issue 36): one regression test per finding that the command line
// shows — nothing written over an input, no partial output, no silent wrong answer, every error one
// line naming what was wrong. Findings 3, 6 (render, Python), 7, 8, 10, 12 and 16 have theirs next
// to the code they fixed (perceive_cli_test, render_cli_test, detect_test, events_test).
#include "cli_helpers.h"

#include "foveal/gaze/recording.h"
#include "foveal/io/image_io.h"
#include "foveal/util/error.h"
#include "foveal/util/files.h"
#include "foveal/util/text.h"

#include <fmt/core.h>
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <sstream>

using namespace foveal_test;
namespace fs = std::filesystem;

namespace {

foveal::Image card(int w, int h, int channels = 3) {
  foveal::Image im(w, h, channels);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x)
      for (int c = 0; c < channels; ++c) im.at(x, y, c) = c == 3 ? (x < w / 2 ? 0.0f : 1.0f) : 0.2f + 0.6f * ((x / 4 + y / 4 + c) % 2);
  return im;
}

std::string bytes_of(const fs::path& p) {
  std::stringstream s;
  s << std::ifstream(p, std::ios::binary).rdbuf();
  return s.str();
}

void write(const fs::path& p, const std::string& text) { std::ofstream(p, std::ios::binary) << text; }

// No staging folder of a failed run left beside the output
bool staging_left(const std::string& name) {
  for (const auto& e : fs::directory_iterator(scratch("")))
    if (e.path().filename().string().rfind("." + name + ".partial-", 0) == 0) return true;
  return false;
}

}  // namespace

// 1. An output that is the input is refused before anything is written; the input is unchanged.
TEST(HostileInput, OutputOverAnInputIsRefused) {
  foveal::save_image(card(32, 20), scratch("h1.png").string());
  const std::string before = bytes_of(scratch("h1.png"));
  expect_one_line_error("perceive h1.png -o h1.png --eye cataract:0.5",
                        "--output h1.png: is input h1.png, an input of this run; foveal never writes over its inputs");
  // The pictures of the eye are outputs too: not over the input, not over another output, and not
  // written by a run that fails (an Amsler grid named like a missing input was written, then read)
  expect_one_line_error("perceive h1.png -o h1-out.png --eye amd:0.5 --amsler h1.png", "--amsler h1.png: is input h1.png");
  expect_one_line_error("perceive h1.png -o h1-out.png --eye amd:0.5 --field-map h1-out.png",
                        "--output h1-out.png and --field-map h1-out.png: two outputs into one file");
  expect_one_line_error("perceive h1-none.png -o h1-out.png --eye amd:0.5 --amsler h1-none.png", "h1-none.png: no such image");
  EXPECT_FALSE(fs::exists(scratch("h1-none.png")));
  EXPECT_FALSE(fs::exists(scratch("h1-out.png")));
  expect_one_line_error("perceive h1.png -o ./sub/../h1.png --eye cataract:0.5", "foveal never writes over its inputs");
  EXPECT_EQ(bytes_of(scratch("h1.png")), before);
  fs::create_directories(scratch("h1-frames"));
  foveal::save_image(card(32, 20), scratch("h1-frames/a.png").string());
  expect_one_line_error("perceive h1-frames -o h1-frames --eye cataract:0.5", "foveal never writes over its inputs");
  // An output over another argument that names a file is refused when the command line is read:
  // gaze's outputs over its own recording, a bench's --json over its --recording (which it had
  // refused only once its work was done) …
  write(scratch("h1.csv"), "t,x,y\n0,1,1\n0.01,2,2\n0.02,3,3\n");
  const std::string rec = bytes_of(scratch("h1.csv"));
  expect_one_line_error("gaze h1.csv --screen 100x100 --no-scanpath --json h1.csv",
                        "--json h1.csv: is RECORDING h1.csv, an input of this run; foveal never writes over its inputs");
  EXPECT_EQ(bytes_of(scratch("h1.csv")), rec);
  const std::string bench = "bench latency --scene builtin:sphere-plane --size 64x40 --duration 3 --recording h1.csv --json ./h1.csv";
  expect_one_line_error(bench, "--json ./h1.csv: is --recording h1.csv, an input of this run");
  EXPECT_EQ(foveal_test::foveal(bench).out.find("references"), std::string::npos);  // refused before any tracing
  EXPECT_EQ(bytes_of(scratch("h1.csv")), rec);
  // … and two outputs into one file, where the second would have replaced the first
  expect_one_line_error("gaze h1.csv --screen 100x100 --no-scanpath --json h1-out.txt --samples-out ./h1-out.txt",
                        "--json h1-out.txt and --samples-out ./h1-out.txt: two outputs into one file");
  EXPECT_FALSE(fs::exists(scratch("h1-out.txt")));
  // Every writer, through the input guard, where the input is no argument: a mesh a scene names,
  // its material library and its texture (--stats had replaced the mesh)
  foveal::save_image(card(8, 8), scratch("h1-tex.png").string());
  write(scratch("h1-tri.mtl"), "newmtl m\nKd 1 1 1\nmap_Kd h1-tex.png\n");
  write(scratch("h1-tri.obj"), "mtllib h1-tri.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nvt 1 0\nvt 0 1\nusemtl m\nf 1/1 2/2 3/3\n");
  write(scratch("h1-scene.json"), R"({"meshes": [{"file": "h1-tri.obj"}]})");
  for (const char* input : {"h1-tri.obj", "h1-tri.mtl", "h1-tex.png"}) {
    const std::string before_run = bytes_of(scratch(input));
    expect_one_line_error(fmt::format("render --scene h1-scene.json --size 16x10 --max-rays 2 -o h1-out.png --stats {} -q", input),
                          fmt::format("{}: is an input of this run", input));
    EXPECT_EQ(bytes_of(scratch(input)), before_run) << input;
  }
}

// An output file beside a folder of outputs may lie in that folder (created by the run), but is
// none of the files the command writes there: `--stats OUT/frames.csv` replaced replay's
// per-frame table (and `--stats OUT/x.json` was refused while OUT did not exist yet).
TEST(HostileInput, AnOutputInAFolderOfOutputsIsNoneOfItsFiles) {
  fs::remove_all(scratch("h1b-replay"));
  fs::remove_all(scratch("h1b-sim"));
  const std::string rec = write_three_fixations("h1b.csv");
  const std::string replay =
      "replay --gaze " + rec + " --scene builtin:box --size 32x20 --max-rays 4 --fps 20 --screen 480x300 --duration 0.3 -o h1b-replay";
  const CliRun first = foveal_test::foveal(replay + " --stats h1b-replay/stats.json -q");
  ASSERT_EQ(first.status, 0) << first.err;
  ASSERT_TRUE(fs::exists(scratch("h1b-replay/stats.json")));
  const std::string table = bytes_of(scratch("h1b-replay/frames.csv"));
  ASSERT_NE(table.find("frame,t_s"), std::string::npos);
  expect_one_line_error(replay + " --stats h1b-replay/frames.csv",
                        "--stats h1b-replay/frames.csv: is a file this command writes into h1b-replay (frames.csv)");
  expect_one_line_error(replay + " --video h1b-replay/frame_00001.png",
                        "--video h1b-replay/frame_00001.png: is a file this command writes");
  EXPECT_EQ(bytes_of(scratch("h1b-replay/frames.csv")), table);
  expect_one_line_error("simulate --scene builtin:box --size 32x20 -o h1b-sim --stats h1b-sim/perceived.png",
                        "--stats h1b-sim/perceived.png: is a file this command writes into h1b-sim (perceived.png)");
  EXPECT_FALSE(fs::exists(scratch("h1b-sim")));
  expect_one_line_error(replay + " --stats h1b-missing/stats.json",
                        "--stats: h1b-missing/stats.json: the folder h1b-missing does not exist");
}

// 2. A folder with one corrupt image: no output folder at all (nothing half-written); replay that
// fails on its first frame leaves no folder either (it left one with a header-only frames.csv).
TEST(HostileInput, AFailedRunLeavesNoPartialOutput) {
  fs::create_directories(scratch("h2-frames"));
  foveal::save_image(card(32, 20), scratch("h2-frames/a.png").string());
  foveal::save_image(card(32, 20), scratch("h2-frames/b.png").string());
  write(scratch("h2-frames/c.png"), "not a png at all");
  const CliRun r = foveal_test::foveal("perceive h2-frames -o h2-out --eye cataract:0.5 --no-optics -q");
  EXPECT_EQ(r.status, 1);
  EXPECT_NE(r.err.find("c.png"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(scratch("h2-out")));
  EXPECT_FALSE(staging_left("h2-out"));
  // replay failing on its first frame (the stimulus rectangle puts the gaze far off the render)
  write(scratch("h2.csv"), "t,x,y\n0,10,10\n0.05,12,10\n0.1,14,10\n0.15,16,10\n");
  const CliRun replay = foveal_test::foveal(
      "replay --gaze h2.csv --scene builtin:box --size 32x20 --max-rays 4 --fps 20 --screen 64x40 -o h2-replay "
      "--stimulus 1000,1000,10,10 -q");
  EXPECT_EQ(replay.status, 1);
  EXPECT_NE(replay.err.find("is not near"), std::string::npos) << replay.err;
  EXPECT_FALSE(fs::exists(scratch("h2-replay")));
  EXPECT_FALSE(staging_left("h2-replay"));
}

// 4. RGBA in perceive keeps its alpha (transparent stays transparent); an image of 5 channels is
// refused by the 8-bit writer instead of losing two; RGBA to JPEG says JPEG keeps no alpha.
TEST(HostileInput, AlphaIsKeptAndOddChannelCountsRefused) {
  foveal::save_image(card(32, 20, 4), scratch("h4.png").string());
  const CliRun r = foveal_test::foveal("perceive h4.png -o h4-seen.png --eye cataract:0.6 --no-optics -q");
  ASSERT_EQ(r.status, 0) << r.err;
  const foveal::Image in = foveal::load_image(scratch("h4.png").string(), true);
  const foveal::Image out = foveal::load_image(scratch("h4-seen.png").string(), true);
  ASSERT_EQ(out.channels, 4);
  for (int y = 0; y < 20; ++y)
    for (int x = 0; x < 32; ++x) EXPECT_EQ(out.at(x, y, 3), in.at(x, y, 3)) << x << "," << y;
  EXPECT_THROW(foveal::save_image(card(4, 4, 5), scratch("h4-five.png").string()), foveal::Error);
  EXPECT_FALSE(fs::exists(scratch("h4-five.png")));
  expect_one_line_error("perceive h4.png -o h4-seen.jpg --no-optics", "keeps no alpha channel");
}

// 5. A folder written as a video (or one image) is refused: no folder named x.mp4.
TEST(HostileInput, AFolderIsNotWrittenAsAVideo) {
  fs::create_directories(scratch("h5-frames"));
  foveal::save_image(card(32, 20), scratch("h5-frames/a.png").string());
  expect_one_line_error("perceive h5-frames -o h5.mp4 --no-optics", "-o h5.mp4: a folder of images is written as a folder of images");
  EXPECT_FALSE(fs::exists(scratch("h5.mp4")));
  expect_one_line_error("perceive h5-frames -o h5.png --no-optics", "give a folder name");
}

// 6 (perceive). A gaze of 1e155 is no point near the image: refused, not an overflow into an
// eccentricity of 0 (and no int cast for the depth lookup).
TEST(HostileInput, AFarGazeIsRefusedInPerceive) {
  foveal::save_image(card(32, 20), scratch("h6.png").string());
  expect_one_line_error("perceive h6.png -o h6-seen.png --gaze 1e155,1e155 --eye field:arcuate:20", "--gaze: (1e+155, 1e+155) is not near");
}

// 9. --start must be a finite time within the recording.
TEST(HostileInput, PerceiveStartIsChecked) {
  fs::create_directories(scratch("h9-frames"));
  foveal::save_image(card(32, 20), scratch("h9-frames/a.png").string());
  write(scratch("h9.csv"), "t,x,y\n0,10,10\n0.1,10,10\n0.2,10,10\n0.3,10,10\n");
  for (const char* start : {"nan", "inf"})  // (every option's number: apps/main.cpp)
    expect_one_line_error(std::string("perceive h9-frames -o h9-out --gaze h9.csv --screen 64x40 --no-optics --start ") + start,
                          std::string("--start: must be a finite number, got ") + start);
  expect_one_line_error("perceive h9-frames -o h9-out --gaze h9.csv --screen 64x40 --no-optics --start -1",
                        "--start: must be a finite number of seconds >= 0");
  expect_one_line_error("perceive h9-frames -o h9-out --gaze h9.csv --screen 64x40 --no-optics --start 1e9",
                        "the recording h9.csv lasts 0.300 s");
}

// 10. An hour-long gap in a recording is lost data: no event spans it (every detector and filter),
// and the summary's rate is the recording's, not samples per second of the whole span.
TEST(HostileInput, AnHourLongGapIsLostDataNotAFixation) {
  std::string csv = "t,x,y\n";
  for (int i = 0; i < 200; ++i) csv += std::to_string(i * 0.002) + ",500,400\n";
  for (int i = 0; i < 200; ++i) csv += std::to_string(3600 + i * 0.002) + ",500,400\n";
  write(scratch("h10.csv"), csv);
  for (const char* method : {"auto", "nhp", "ivt", "idt", "ek"}) {
    const CliRun r =
        foveal_test::foveal(std::string("gaze h10.csv --screen 1000x800 --no-scanpath --events ") + method + " --events-out h10.tsv");
    ASSERT_EQ(r.status, 0) << r.err;
    EXPECT_NE(r.out.find("500.0 Hz"), std::string::npos) << r.out;
    std::ifstream tsv(scratch("h10.tsv"));
    std::string line;
    std::getline(tsv, line);
    int rows = 0;
    while (std::getline(tsv, line)) {
      ++rows;
      const double duration = std::stod(line.substr(line.find('\t') + 1));
      EXPECT_LT(duration, 1.0) << method << ": " << line;
    }
    EXPECT_GE(rows, 2) << method;
  }
}

// 11. Samples that repeat a time are dropped with a warning: the rate is the recording's, and the
// summary and the detector agree.
TEST(HostileInput, RepeatedSampleTimesAreDroppedAndSaid) {
  std::string csv = "t,x,y\n";
  for (int i = 0; i < 1000; ++i) {
    csv += std::to_string(i * 0.002) + ",500,400\n";
    if (i % 100 == 0) csv += std::to_string(i * 0.002) + ",500,400\n";  // a duplicate every 100
  }
  const foveal::Recording r = foveal::parse_recording(csv, "dup.csv");
  EXPECT_EQ(r.samples.size(), 1000u);
  ASSERT_EQ(r.warnings.size(), 1u);
  EXPECT_NE(r.warnings[0].find("10 samples repeat the time"), std::string::npos);
  EXPECT_NEAR(r.rate_hz(), 500, 1);
}

// 13. NaN, zero or negative depths are refused with their count and the first pixel.
TEST(HostileInput, BadDepthsAreRefused) {
  foveal::save_image(card(8, 4), scratch("h13.png").string());
  foveal::Image depth(8, 4, 1, 1.5f);
  depth.at(3, 1, 0) = NAN;
  depth.at(5, 2, 0) = -1;
  depth.at(6, 2, 0) = 0;
  foveal::save_image(depth, scratch("h13-depth.pfm").string());
  expect_one_line_error("perceive h13.png -o h13-seen.png --depth h13-depth.pfm",
                        "h13-depth.pfm: 3 depths are NaN, zero or negative (the first at pixel 3,1");
  depth.at(3, 1, 0) = INFINITY;  // far away is allowed
  depth.at(5, 2, 0) = depth.at(6, 2, 0) = 2;
  foveal::save_image(depth, scratch("h13-depth.pfm").string());
  const CliRun ok = foveal_test::foveal("perceive h13.png -o h13-seen.png --depth h13-depth.pfm -q");
  EXPECT_EQ(ok.status, 0) << ok.err;
}

// 14. A profile's key given twice, conflicting presets and a dangling '+' are refused.
TEST(HostileInput, ConflictingEyeSettingsAreRefused) {
  foveal::save_image(card(8, 4), scratch("h14.png").string());
  write(scratch("h14.json"), R"({"name": "x", "age": 40, "age": 70})");
  expect_one_line_error("perceive h14.png -o h14-seen.png --eye h14.json", "h14.json: the key \"age\" is given twice in one object");
  expect_one_line_error("perceive h14.png -o h14-seen.png --eye cataract:0.3+cataract:0.9",
                        "'cataract:0.3' and 'cataract:0.9' both set cataract");
  expect_one_line_error("perceive h14.png -o h14-seen.png --eye cvd:deutan:0.2+cvd:protan:1", "both set colour vision");
  expect_one_line_error("perceive h14.png -o h14-seen.png --eye cataract:0.3+", "a '+' needs a preset on each side");
}

// 15. compare of images holding NaN says so instead of "identical" (PSNR inf).
TEST(HostileInput, CompareRefusesNonFinitePixels) {
  foveal::Image nan_image(8, 4, 3, NAN);
  foveal::save_image(nan_image, scratch("h15a.pfm").string());
  foveal::save_image(nan_image, scratch("h15b.pfm").string());
  expect_one_line_error("compare h15a.pfm h15b.pfm", "h15a.pfm: 96 NaN or infinite values");
}

// 17. "nan,nan" is a bad point, not a recording's name.
TEST(HostileInput, ANanGazeIsABadPoint) {
  foveal::save_image(card(8, 4), scratch("h17.png").string());
  const CliRun r = foveal_test::foveal("perceive h17.png -o h17-seen.png --gaze nan,nan");
  EXPECT_EQ(r.status, 1);
  EXPECT_NE(r.err.find("--gaze"), std::string::npos) << r.err;
  EXPECT_EQ(r.err.find("needs a video"), std::string::npos) << r.err;
}

// 17 (images). A PNG header claiming 100000×100000 is refused from the header, naming the file and
// the cap (it was a raw OpenCV assertion); a truncated PNG is one line naming the file (libpng's
// own line came first).
TEST(HostileInput, HugeAndTruncatedImagesAreOneLineNamingTheFile) {
  std::string png("\x89PNG\r\n\x1a\n\0\0\0\x0dIHDR", 16);
  for (uint32_t v : {100000u, 100000u})
    for (int k = 3; k >= 0; --k) png += static_cast<char>((v >> (8 * k)) & 0xff);
  png += std::string("\x08\x02\0\0\0", 5) + std::string(40, '\0');
  write(scratch("h17-huge.png"), png);
  expect_one_line_error("perceive h17-huge.png -o h17-out.png",
                        "h17-huge.png: 100000x100000 pixels, more than the 67 million foveal reads");
  foveal::save_image(card(64, 40), scratch("h17-whole.png").string());
  const std::string whole = bytes_of(scratch("h17-whole.png"));
  write(scratch("h17-cut.png"), whole.substr(0, whole.size() / 2));
  expect_one_line_error("perceive h17-cut.png -o h17-out.png", "h17-cut.png: cannot read image");
}

// 17 (names). A file name or a file's bytes quoted in an error that are not UTF-8 (a Latin-1 name,
// an EXR's corrupt channel name) are shown as \xNN, the message stays one line
TEST(HostileInput, BytesThatAreNotUtf8AreEscapedInErrors) {
  expect_one_line_error("perceive 'caf\xe9\n.png' -o h17-names.png", "caf\\xe9\\x0a.png: no such image");
}

// 18. Reading is bounded: an endless input is refused with its name once past the limit.
TEST(HostileInput, AnEndlessInputIsRefusedAtTheLimit) {
  try {
    foveal::text::read_file("/dev/zero", size_t(1) << 20);
    FAIL() << "read /dev/zero";
  } catch (const foveal::Error& e) {
    EXPECT_NE(std::string(e.what()).find("/dev/zero: more than 1 MiB"), std::string::npos) << e.what();
  }
}

// 19. An infinite display size says it must be finite.
TEST(HostileInput, AnInfiniteDisplayIsNamedSo) {
  write(scratch("h19.csv"), "t,x,y\n0,1,1\n0.01,2,2\n");
  expect_one_line_error("gaze h19.csv --display 47.5,30,inf --no-scanpath", "viewing distance must be a finite number > 0 cm, got inf");
}

// 20. A folder where a file belongs says it is a folder.
TEST(HostileInput, AFolderWhereAFileBelongsIsNamedSo) {
  foveal::save_image(card(8, 4), scratch("h20.png").string());
  fs::create_directories(scratch("h20-dir"));
  write(scratch("h20.json"), R"({"name": "x", "eyes": {"OD": {"field": {"file": "."}}}})");
  const CliRun r = foveal_test::foveal("perceive h20.png -o h20-seen.png --eye h20.json");
  EXPECT_EQ(r.status, 1);
  EXPECT_NE(r.err.find("is a folder, not a file"), std::string::npos) << r.err;
  expect_one_line_error("gaze h20-dir --no-scanpath", "h20-dir: is a folder");
}
