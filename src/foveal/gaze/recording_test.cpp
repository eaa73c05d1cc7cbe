// Recording readers: every real recording against its data README, hand-made files of each
// format, and malformed input that must fail with file, line and reason (or read as invalid).
#include "foveal/gaze/recording.h"
#include "foveal/util/text.h"
#include "foveal/util/error.h"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>

namespace fs = std::filesystem;
using namespace foveal;

namespace {

const std::string kGaze = std::string(FOVEAL_DATA_DIR) + "/gaze";

// The error message of parse_recording, or "" if it succeeded.
std::string error_of(const std::string& text, const std::string& name, ReadOptions o = {}) {
  try {
    parse_recording(text, name, o);
  } catch (const Error& e) {
    return e.what();
  }
  return "";
}

const char* kAsc =
    "** CONVERTED FROM test.edf\n"
    "MSG\t1000 DISPLAY_COORDS 0 0 799 599\n"
    "START\t1000 \tLEFT\tSAMPLES\tEVENTS\n"
    "SAMPLES\tGAZE\tLEFT\tRATE\t 500.00\tTRACKING\tCR\tFILTER\t2\n"
    "1000\t  100.0\t  200.0\t 1000.0\t...\n"
    "1002\t  101.0\t  201.0\t 1000.0\t...\n"
    "1004\t   .\t   .\t    0.0\t...\n"
    "1006\t  103.0\t  203.0\t 1000.0\t...\n"
    " \t \n"  // blanks only (found by fuzzing)
    "EFIX L   1000\t1006\t8\t  101.3\t  201.3\t   1000\n"
    "END\t1007 \tSAMPLES\tEVENTS\tRES\t  36.39\t  36.07\n"
    "   3820.2  273.52  324.43\n";  // a calibration line outside a block: not a sample

}  // namespace

TEST(Recording, EyeLinkAscHandMade) {
  const Recording r = parse_recording(kAsc, "test.asc");
  EXPECT_EQ(r.format, GazeFormat::asc);
  ASSERT_EQ(r.samples.size(), 4u);
  EXPECT_EQ(r.screen_px, glm::ivec2(800, 600));
  EXPECT_TRUE(r.screen_from_file);
  EXPECT_DOUBLE_EQ(r.samples[1].t_s, 1.002);
  EXPECT_EQ(r.samples[1].px, glm::dvec2(101, 201));
  // "." is a missing sample: invalid with a NaN point, never (0, 0)
  EXPECT_FALSE(r.samples[2].valid);
  EXPECT_TRUE(std::isnan(r.samples[2].px.x));
  EXPECT_EQ(r.valid_count(), 3u);
  EXPECT_DOUBLE_EQ(r.nominal_rate_hz, 500);
  EXPECT_NEAR(r.rate_hz(), 500, 1e-6);
  ASSERT_EQ(r.fixations.size(), 1u);
  EXPECT_DOUBLE_EQ(r.fixations[0].end_s, 1.006);
}

TEST(Recording, EyeLinkBinocularAverageAndSingleEye) {
  const std::string asc =
      "MSG\t1 GAZE_COORDS 0.00 0.00 1023.00 767.00\n"
      "START\t10 \tLEFT\tRIGHT\tSAMPLES\tEVENTS\n"
      "SAMPLES\tGAZE\tLEFT\tRIGHT\tRATE\t1000.00\n"
      "10\t 100.0\t 200.0\t 1000.0\t 110.0\t 210.0\t 1000.0\t.....\n"
      "11\t   .\t   .\t    0.0\t 120.0\t 220.0\t 1000.0\t.....\n"
      "END\t12\n";
  ReadOptions o;
  Recording r = parse_recording(asc, "bino.asc", o);
  EXPECT_EQ(r.screen_px, glm::ivec2(1024, 768));
  EXPECT_EQ(r.samples[0].px, glm::dvec2(105, 205));  // average of both eyes
  EXPECT_EQ(r.samples[1].px, glm::dvec2(120, 220));  // the valid eye only
  o.eye = EyeSelection::left;
  r = parse_recording(asc, "bino.asc", o);
  EXPECT_EQ(r.samples[0].px, glm::dvec2(100, 200));
  EXPECT_FALSE(r.samples[1].valid);
}

TEST(Recording, PupilTobiiAndCsvHandMade) {
  ReadOptions o;
  o.screen_px = {1000, 500};
  // Pupil: normalised, origin bottom-left; low confidence → invalid
  const Recording p = parse_recording(
      "gaze_timestamp,world_index,confidence,norm_pos_x,norm_pos_y\n"
      "10.0,1,0.9,0.25,0.75\n"
      "10.004,1,0.2,0.5,0.5\n",
      "gaze_positions.csv", o);
  EXPECT_EQ(p.format, GazeFormat::pupil);
  EXPECT_EQ(p.samples[0].px, glm::dvec2(250, 125));
  EXPECT_TRUE(p.samples[0].valid);
  EXPECT_FALSE(p.samples[1].valid);
  // Tobii SDK: µs, normalised, validity > 1 means missing
  const Recording t = parse_recording(
      "Time\tLGazePos2dx\tLGazePos2dy\tLValidity\tRGazePos2dx\tRGazePos2dy\tRValidity\n"
      "1000000\t0.4\t0.5\t0\t0.6\t0.5\t0\n"
      "1003333\t-1.0\t-1.0\t4\t0.6\t0.4\t0\n"
      "1006666\t-1.0\t-1.0\t4\t-1.0\t-1.0\t4\n",
      "tobii.tsv", o);
  EXPECT_EQ(t.format, GazeFormat::tobii);
  EXPECT_NEAR(t.samples[0].px.x, 500, 1e-9);
  EXPECT_NEAR(t.samples[1].px.x, 600, 1e-9);
  EXPECT_NEAR(t.samples[1].px.y, 200, 1e-9);
  EXPECT_FALSE(t.samples[2].valid);
  EXPECT_NEAR(t.samples[1].t_s - t.samples[0].t_s, 0.003333, 1e-9);
  // Tobii Pro Lab: pixels, ms without a unit, its own fixations, other sensors' rows skipped
  const Recording pl = parse_recording(
      "Recording timestamp [μs]\tSensor\tRecording resolution width\tRecording resolution height\tGaze point X\tGaze point Y\t"
      "Validity left\tValidity right\tEye movement type\tEye movement type index\tFixation point X\tFixation point Y\n"
      "0\tEye Tracker\t1920\t1080\t960\t540\tValid\tValid\tFixation\t1\t961\t541\n"
      "8333\tEye Tracker\t1920\t1080\t962,5\t542\tValid\tValid\tFixation\t1\t961\t541\n"
      "10000\tMouse\t\t\t\t\t\t\t\t\t\t\n"
      "16666\tEye Tracker\t1920\t1080\t\t\tInvalid\tInvalid\tEyesNotFound\t1\t\t\n"
      "25000\tEye Tracker\t1920\t1080\t100\t100\tValid\tValid\tSaccade\t1\t\t\n",
      "prolab.tsv", o);
  EXPECT_EQ(pl.samples.size(), 4u);
  EXPECT_EQ(pl.screen_px, glm::ivec2(1920, 1080));
  EXPECT_DOUBLE_EQ(pl.samples[1].px.x, 962.5);  // decimal comma
  EXPECT_NEAR(pl.samples[1].t_s, 0.008333, 1e-12);
  EXPECT_FALSE(pl.samples[2].valid);
  ASSERT_EQ(pl.fixations.size(), 1u);
  EXPECT_NEAR(pl.fixations[0].end_s, 0.008333, 1e-12);
  // Plain CSV with a header, ms, normalised bottom-left
  o.csv_time_scale = 1e-3;
  o.csv_normalised = true;
  o.csv_origin_bottom_left = true;
  const Recording c = parse_recording("time,x,y,confidence\n0,0.5,0.25,1\n4,,,0\n8,nan,0.5,1\n", "plain.csv", o);
  EXPECT_EQ(c.format, GazeFormat::csv);
  EXPECT_EQ(c.samples[0].px, glm::dvec2(500, 375));
  EXPECT_FALSE(c.samples[1].valid);
  EXPECT_FALSE(c.samples[2].valid);
  EXPECT_DOUBLE_EQ(c.samples[2].t_s, 0.008);
}

TEST(Recording, MalformedInputNamesFileLineAndReason) {
  struct Case {
    const char* text;
    const char* name;
    const char* expected;  // must appear in the message
  };
  const Case cases[] = {
      {"", "empty.csv", "empty.csv: empty recording"},
      {"t,x,y\n0,1,2\n1,abc,3\n", "text.csv", "text.csv:3: x 'abc' is not a number"},
      {"t,x,y\n0,1,2\n1,2\n", "short.csv", "short.csv:3: 2 fields, expected 3"},
      {"t,x,y,azimuth\n0,1,2,3\n", "cols.csv", "cols.csv:1: unknown column 'azimuth'"},
      {"t,x,y,pupil\n0,1,2,-3\n", "pupil.csv", "pupil.csv:2: pupil size -3 is negative"},
      {"t,x,y\n0,1,2\n-1,2,3\n", "back.csv", "back.csv:3: time -1 is before the previous sample's 0"},
      {"START\t1\tLEFT\tSAMPLES\nSAMPLES\tGAZE\tLEFT\n1\t10.0\n", "trunc.asc", "trunc.asc:3: sample has 2 fields"},
      {"START\t1\tLEFT\tSAMPLES\nSAMPLES\tGAZE\tLEFT\n1\t10.0\tfoo\t100\n", "word.asc", "word.asc:3: gaze y 'foo' is not a number"},
      {"START\t1\tLEFT\tSAMPLES\n5\t1\t1\t1\n3\t1\t1\t1\n", "order.asc", "order.asc:3: time 3 ms is before"},
      {"MSG\t1 nothing\n", "nosamples.asc", "nosamples.asc: no samples inside START"},
      {"gaze_timestamp,confidence,norm_pos_x,norm_pos_y\n1,0.9,0.5\n", "p.csv", "p.csv:2: 3 fields, but the header has 4"},
      {"gaze_timestamp,confidence,norm_pos_x\n1,0.9,0.5\n", "p2.csv", "p2.csv:1: missing column 'norm_pos_y'"},
      {"gaze_timestamp,confidence,norm_pos_x,norm_pos_y\n1,high,0.5,0.5\n", "p3.csv",
       "p3.csv:2: column 'confidence': 'high' is not a number"},
      {"Time\tLGazePos2dx\tLGazePos2dy\tLValidity\tRGazePos2dx\tRGazePos2dy\tRValidity\n1\t0.5\t0.5\t0\t0.5\n", "t.tsv",
       "t.tsv:2: 5 fields, but the header has 7"},
      {"id,start_timestamp,duration,dispersion\n", "fixations.csv", "this is Pupil's fixations.csv"},
  };
  for (const Case& c : cases) {
    const std::string message = error_of(c.text, c.name);
    EXPECT_NE(message.find(c.expected), std::string::npos) << "for " << c.name << " got: '" << message << "'";
  }
}

// The real recordings of ../shared/data/gaze, checked against the counts in its README.
TEST(Recording, RealEyeLinkMonocular) {
  const std::string path = kGaze + "/eyelink/monoRemote500.asc";
  if (!fs::exists(path)) GTEST_SKIP() << "skipped: " << path << " absent";
  const Recording r = read_recording(path);
  EXPECT_EQ(r.format, GazeFormat::asc);
  EXPECT_EQ(r.samples.size(), 41582u);
  EXPECT_EQ(r.samples.size() - r.valid_count(), 51u);  // "51 with missing gaze"
  EXPECT_EQ(r.block_starts.size(), 4u);
  EXPECT_EQ(r.fixations.size(), 300u);
  EXPECT_EQ(r.blinks.size(), 3u);
  EXPECT_EQ(r.screen_px, glm::ivec2(1024, 768));
  EXPECT_NEAR(r.rate_hz(), 500, 0.5);
  EXPECT_DOUBLE_EQ(r.samples.front().t_s, 12134.094);
  EXPECT_DOUBLE_EQ(r.samples.back().t_s, 12223.216);
  EXPECT_EQ(r.eyes, "left");
  EXPECT_FLOAT_EQ(r.samples.front().pupil, 278.0f);  // the sample line's third column
  for (const GazeSample& s : r.samples)
    if (!s.valid) EXPECT_TRUE(std::isnan(s.pupil) || s.pupil > 0);  // EyeLink's 0 (no pupil) is NaN, never a size
}

TEST(Recording, CsvPupilColumn) {
  const Recording r = parse_recording("t,x,y,pupil\n0,1,2,3.5\n0.001,1,2,0\n0.002,1,2,\n", "p.csv");
  ASSERT_EQ(r.samples.size(), 3u);
  EXPECT_FLOAT_EQ(r.samples[0].pupil, 3.5f);
  EXPECT_TRUE(std::isnan(r.samples[1].pupil));  // 0: no pupil seen
  EXPECT_TRUE(std::isnan(r.samples[2].pupil));
}

TEST(Recording, RealEyeLinkBinocular) {
  const std::string path = kGaze + "/eyelink/bino1000.asc";
  if (!fs::exists(path)) GTEST_SKIP() << "skipped: " << path << " absent";
  ReadOptions o;
  o.eye = EyeSelection::left;
  const Recording r = read_recording(path, o);
  EXPECT_EQ(r.samples.size(), 3467u);
  EXPECT_EQ(r.valid_count(), 3467u);   // "no missing"
  EXPECT_EQ(r.fixations.size(), 12u);  // 24 EFIX, for the two eyes
  EXPECT_EQ(r.screen_px, glm::ivec2(1024, 768));
  EXPECT_NEAR(r.rate_hz(), 1000, 1);
  EXPECT_EQ(r.block_starts.size(), 4u);
}

TEST(Recording, RealPupilExports) {
  const std::string path = kGaze + "/pupil_labs/gaze_positions.csv";
  if (!fs::exists(path)) GTEST_SKIP() << "skipped: " << path << " absent";
  const Recording r = read_recording(path);
  EXPECT_EQ(r.format, GazeFormat::pupil);
  EXPECT_EQ(r.samples.size(), 9302u);
  EXPECT_NEAR(r.duration_s(), 39.20, 0.01);
  EXPECT_NEAR(r.rate_hz(), 237, 1);
  // "69 % of rows have confidence ≥ 0.8": the fraction at or above 0.8
  size_t high = 0;
  for (const GazeSample& s : r.samples) high += s.confidence >= 0.8f;
  EXPECT_NEAR(static_cast<double>(high) / r.samples.size(), 0.69, 0.01);
  EXPECT_FALSE(r.has_tracker_fixations);  // no fixations.csv beside it

  const std::string t10 = kGaze + "/pupil_labs/tutorial10/gaze_positions.csv";
  const Recording t = read_recording(t10);
  EXPECT_EQ(t.samples.size(), 2054u);
  EXPECT_NEAR(t.duration_s(), 6.93, 0.01);
  EXPECT_NEAR(t.rate_hz(), 296, 1);
  EXPECT_TRUE(t.has_tracker_fixations);
  EXPECT_EQ(t.fixations.size(), 36u);
  EXPECT_EQ(t.blinks.size(), 3u);
  for (const GazeEvent& f : t.fixations) {  // durations "~170–200" ms, read as milliseconds
    EXPECT_GT(f.end_s - f.start_s, 0.05);
    EXPECT_LT(f.end_s - f.start_s, 0.3);
  }
  for (const GazeEvent& b : t.blinks) EXPECT_NEAR(b.end_s - b.start_s, 0.4, 0.3);  // "~0.4 s"
}

TEST(Recording, RealTobii) {
  const std::string path = kGaze + "/tobii/tx300_participant1_trial2.tsv";
  if (!fs::exists(path)) GTEST_SKIP() << "skipped: " << path << " absent";
  ReadOptions o;
  o.screen_px = {1920, 1080};
  const Recording r = read_recording(path, o);
  EXPECT_EQ(r.format, GazeFormat::tobii);
  EXPECT_EQ(r.samples.size(), 1206u);
  EXPECT_NEAR(r.duration_s(), 4.016, 0.005);
  EXPECT_NEAR(r.rate_hz(), 300, 1);
  EXPECT_LT(r.valid_count(), r.samples.size());  // some samples are lost
  for (const GazeSample& s : r.samples) {
    if (!s.valid) {
      EXPECT_TRUE(std::isnan(s.px.x));  // never the −1 filler scaled into the screen
      continue;
    }
    EXPECT_GE(s.px.x, -0.1 * 1920);
    EXPECT_LE(s.px.x, 1920);
  }
}

// Every text reader takes a UTF-8 byte-order mark (as spreadsheet programs on Windows save) and CRLF
// line ends, alone and together, and reads the same samples and events as from the plain text.
TEST(Recording, ByteOrderMarkAndCrlfInEveryReader) {
  ReadOptions o;
  o.screen_px = {1000, 500};
  auto variants = [](const std::string& text) {
    std::string crlf;
    for (char c : text) crlf += c == '\n' ? std::string("\r\n") : std::string(1, c);
    const std::string bom = "\xEF\xBB\xBF";
    return std::vector<std::string>{bom + text, crlf, bom + crlf};
  };
  auto same = [](const Recording& a, const Recording& b, const std::string& what) {
    ASSERT_EQ(a.samples.size(), b.samples.size()) << what;
    for (size_t i = 0; i < a.samples.size(); ++i) {
      EXPECT_EQ(a.samples[i].t_s, b.samples[i].t_s) << what;
      EXPECT_EQ(a.samples[i].valid, b.samples[i].valid) << what;
      if (a.samples[i].valid) EXPECT_EQ(a.samples[i].px, b.samples[i].px) << what;
    }
    EXPECT_EQ(a.fixations.size(), b.fixations.size()) << what;
    EXPECT_EQ(a.format, b.format) << what;
  };
  const std::vector<std::pair<std::string, std::string>> files = {
      {"gaze_positions.csv", "gaze_timestamp,world_index,confidence,norm_pos_x,norm_pos_y\n10.0,1,0.9,0.25,0.75\n10.004,1,0.95,0.5,0.5\n"},
      {"tobii.tsv",
       "Time\tLGazePos2dx\tLGazePos2dy\tLValidity\tRGazePos2dx\tRGazePos2dy\tRValidity\n"
       "1000000\t0.4\t0.5\t0\t0.6\t0.5\t0\n1003333\t0.4\t0.5\t0\t0.6\t0.4\t0\n"},
      {"plain.csv", "t,x,y\n0.0,10,20\n0.1,11,21\n"},
      {"rec.asc", kAsc},
  };
  for (const auto& [name, text] : files) {
    const Recording plain = parse_recording(text, name, o);
    for (const std::string& v : variants(text)) {
      EXPECT_EQ(detect_gaze_format(v, name), plain.format) << name;
      same(parse_recording(v, name, o), plain, name);
    }
  }
  // Pupil's side files
  const std::string fixations =
      "id,start_timestamp,duration,start_frame_index,end_frame_index,norm_pos_x,norm_pos_y\n1,10.0,200,1,5,0.5,0.5\n";
  const std::string blinks = "id,start_timestamp,duration,end_timestamp\n1,11.0,0.3,11.3\n";
  for (const std::string& v : variants(fixations)) EXPECT_EQ(parse_pupil_fixations(v, "fixations.csv", {1000, 500}).size(), 1u);
  for (const std::string& v : variants(blinks)) EXPECT_EQ(parse_pupil_blinks(v, "blinks.csv").size(), 1u);
  // A real export saved with a BOM
  const std::string path = kGaze + "/pupil_labs/gaze_positions.csv";
  if (fs::exists(path)) {
    const std::string text = text::read_file(path);
    same(parse_recording("\xEF\xBB\xBF" + text, path, {}), parse_recording(text, path, {}), "real Pupil export");
  }
}

// Absurd points in a recording (x = 1e300, or far off the stated screen) are invalid, carry no
// point and are counted in the notes; points a little off the screen stay valid.
TEST(Recording, AbsurdPointsAreInvalidAndCounted) {
  const Recording c = parse_recording("t,x,y\n0.0,100,200\n0.01,1e300,200\n0.02,100,-1e9\n0.03,-50,20\n", "plain.csv", {});
  ASSERT_EQ(c.samples.size(), 4u);
  EXPECT_TRUE(c.samples[0].valid);
  EXPECT_FALSE(c.samples[1].valid);
  EXPECT_TRUE(std::isnan(c.samples[1].px.x));
  EXPECT_FALSE(c.samples[2].valid);
  EXPECT_TRUE(c.samples[3].valid);  // just off the screen's edge
  ASSERT_FALSE(c.notes.empty());
  EXPECT_NE(c.notes.back().find("2 samples"), std::string::npos) << c.notes.back();
  // A large monitor's pixels without --screen are not glitches
  const Recording big = parse_recording("t,x,y\n0.0,3800,2100\n", "uhd.csv", {});
  EXPECT_TRUE(big.samples[0].valid);
  // Normalised coordinates: more than one screen beyond the edges is invalid
  ReadOptions norm;
  norm.screen_px = {1000, 500};
  const Recording p = parse_recording(
      "gaze_timestamp,world_index,confidence,norm_pos_x,norm_pos_y\n10.0,1,0.9,0.25,0.75\n10.004,1,0.95,1e30,-5\n10.008,1,0.95,2.5,0.5\n",
      "gaze_positions.csv", norm);
  EXPECT_TRUE(p.samples[0].valid);
  EXPECT_FALSE(p.samples[1].valid);
  EXPECT_FALSE(p.samples[2].valid);
}

// An EyeLink file cut in the middle of a block (no END) is read, with a warning that names the
// block and says the file may be truncated; a complete file has no warning.
TEST(Recording, TruncatedEyeLinkBlockIsReadWithAWarning) {
  EXPECT_TRUE(parse_recording(kAsc, "whole.asc", {}).warnings.empty());
  const std::string text = kAsc;
  const std::string cut = text.substr(0, text.find("1006\t"));  // cut after the third sample
  const Recording r = parse_recording(cut, "cut.asc", {});
  EXPECT_EQ(r.samples.size(), 3u);
  ASSERT_EQ(r.warnings.size(), 1u);
  EXPECT_NE(r.warnings[0].find("cut.asc: recording block 1 (from line 3) has no END"), std::string::npos) << r.warnings[0];
  EXPECT_NE(r.warnings[0].find("truncated"), std::string::npos);
}
