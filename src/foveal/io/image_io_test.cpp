// Tests of image and AOV files: PFM, EXR and PNG round trips, bad files, the contract's NaN/1 rule.
#include "foveal/io/image_io.h"
#include "foveal/render/outputs.h"
#include "foveal/util/error.h"

#include <gtest/gtest.h>
#include <opencv2/imgcodecs.hpp>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <string>
#include <tuple>
#include <vector>

using namespace foveal;
namespace fs = std::filesystem;

namespace {
Image ramp(int w, int h, int c) {
  Image im(w, h, c);
  for (size_t i = 0; i < im.pixels.size(); ++i) im.pixels[i] = static_cast<float>(i) * 0.01f - 0.3f;
  return im;
}
std::string temp(const std::string& name) {
  return (fs::temp_directory_path() / ("foveal_io_" + std::to_string(::getpid()) + "_" + name)).string();
}
}  // namespace

TEST(ImageIO, FloatFormatsRoundTripExactly) {
  for (const char* ext : {".pfm", ".exr"})
    for (int channels : {1, 3}) {
      const Image im = ramp(7, 5, channels);
      const std::string path = temp(std::string("rt") + std::to_string(channels) + ext);
      save_image(im, path);
      const Image back = load_image(path);
      fs::remove(path);
      ASSERT_EQ(back.width, 7);
      ASSERT_EQ(back.height, 5);
      ASSERT_EQ(back.channels, channels);
      EXPECT_EQ(back.pixels, im.pixels) << ext;  // top row stays on top
    }
}

// The extensions a command checks an image output against up front are those save_image writes,
// and no other (render -o x.tif is refused when the command line is read)
TEST(ImageIO, EveryListedExtensionIsWrittenAndNoOther) {
  for (const std::string& ext : image_extensions()) {
    const std::string path = temp("listed" + ext);
    save_image(ramp(6, 4, 3), path);
    EXPECT_GT(fs::file_size(path), 0u) << ext;
    const Image back = load_image(path);
    EXPECT_EQ(back.width, 6) << ext;
    fs::remove(path);
  }
  for (const char* ext : {".tif", ".gif", ".webp", ""}) EXPECT_THROW(save_image(ramp(6, 4, 3), temp(std::string("unlisted") + ext)), Error);
}

TEST(ImageIO, PngIsEightBitSrgb) {
  Image im(4, 2, 3, 0.0f);
  im.at(0, 0, 0) = 1.0f;
  im.at(1, 0, 1) = 0.5f;  // linear 0.5 → sRGB 0.735
  const std::string path = temp("x.png");
  save_image(im, path);
  const Image back = load_image(path);
  fs::remove(path);
  EXPECT_FLOAT_EQ(back.at(0, 0, 0), 1.0f);
  EXPECT_NEAR(back.at(1, 0, 1), linear_to_srgb(0.5f), 1.0 / 255);
  EXPECT_FLOAT_EQ(back.at(1, 0, 0), 0.0f);
}

TEST(ImageIO, MalformedFilesGiveErrors) {
  EXPECT_THROW(parse_pfm("", "a.pfm"), Error);
  EXPECT_THROW(parse_pfm("P6\n1 1\n255\n", "a.pfm"), Error);
  EXPECT_THROW(parse_pfm("PF\n-3 2\n-1.0\n", "a.pfm"), Error);
  EXPECT_THROW(parse_pfm("Pf\n2 2\n-1.0\n\x01\x02", "a.pfm"), Error);       // truncated
  EXPECT_THROW(parse_pfm("Pf\n1 1\n0\n\x01\x02\x03\x04", "a.pfm"), Error);  // zero scale
  EXPECT_THROW(parse_pfm("Pf\n1 1\n98888888888", "a.pfm"), Error);          // ends in the header (found by fuzzing)
  EXPECT_THROW(load_image(temp("missing.exr")), Error);
  const std::string bad = temp("bad.exr");
  std::ofstream(bad) << "not an exr";
  EXPECT_THROW(load_image(bad), Error);
  fs::remove(bad);
  EXPECT_THROW(save_image(Image(2, 2, 3), temp("x.tiffy")), Error);
}

// OpenCV picks its decoder by the content: a DICOM-like file under a .jpg name (found by fuzzing)
// reached GDCM, which aborts the process on it; content of no format foveal reads is refused first
TEST(ImageIO, ContentOfAnotherFormatIsRefusedBeforeDecoding) {
  const std::string path = temp("dicom-like.jpg");
  {
    std::ofstream out(path, std::ios::binary);
    const unsigned char bytes[] = {0xFF, 0x02, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0xD8, 0xFF, 0x2E, 0x00, 0x10, 'J', 'F', 'I', 'F'};
    out.write(reinterpret_cast<const char*>(bytes), sizeof bytes);
  }
  try {
    load_image(path);
    ADD_FAILURE() << "accepted";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("not a PNG, JPEG, BMP, TIFF, PPM, EXR or PFM image"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find(path), std::string::npos) << e.what();
  }
  fs::remove(path);
  // OpenCV's decoders check whole signatures: "P6" not followed by whitespace is no PPM to it, and
  // a "DICM" at byte 128 then reached the DICOM decoder (found by fuzzing); so is a PNG's first
  // four bytes without the other four
  for (const std::string& start : {std::string("P6\x01\xff", 4), std::string("\x89PNG\0\0\0\0", 8)}) {
    const std::string named = temp("dicom-after.jpg");
    std::ofstream(named, std::ios::binary) << start << std::string(124, '\x32') << "DICM" << std::string(16, '\0');
    try {
      load_image(named);
      ADD_FAILURE() << "accepted";
    } catch (const Error& e) {
      EXPECT_NE(std::string(e.what()).find("not a PNG, JPEG, BMP, TIFF, PPM, EXR or PFM image"), std::string::npos) << e.what();
    }
    fs::remove(named);
  }
  // A real PNG under a .jpg name still reads (decoded by its content, as before)
  const std::string png = temp("png.png"), named = temp("png-named.jpg");
  save_image(Image(3, 2, 3), png);
  fs::copy_file(png, named, fs::copy_options::overwrite_existing);
  EXPECT_EQ(load_image(named).width, 3);
  fs::remove(png);
  fs::remove(named);
  const std::string ppm = temp("round.ppm");  // what save_image writes, read back
  save_image(Image(4, 3, 3), ppm);
  EXPECT_EQ(load_image(ppm).height, 3);
  fs::remove(ppm);
}

namespace {
// A classic TIFF holding one image file directory; each entry is {tag, type (3 SHORT, 4 LONG),
// values}: values that do not fit in the entry's four bytes go after the directory.
std::string tiff(bool little, const std::vector<std::tuple<uint16_t, uint16_t, std::vector<uint32_t>>>& entries) {
  std::string out = little ? std::string("II*\0", 4) : std::string("MM\0*", 4), extra;
  auto put = [&](std::string& to, uint32_t v, int n) {
    for (int i = 0; i < n; ++i) to += static_cast<char>((v >> (8 * (little ? i : n - 1 - i))) & 0xff);
  };
  put(out, 8, 4);
  put(out, static_cast<uint32_t>(entries.size()), 2);
  const uint32_t after = 8 + 2 + 12 * static_cast<uint32_t>(entries.size()) + 4;
  for (const auto& [tag, type, values] : entries) {
    const int size = type == 3 ? 2 : 4;
    put(out, tag, 2), put(out, type, 2), put(out, static_cast<uint32_t>(values.size()), 4);
    std::string value;
    for (uint32_t v : values) put(value, v, size);
    if (value.size() <= 4) {
      out += value + std::string(4 - value.size(), '\0');
    } else {
      put(out, after + static_cast<uint32_t>(extra.size()), 4);
      extra += value;
    }
  }
  put(out, 0, 4);  // no next directory
  return out + extra + std::string(64, '\0');
}

std::string refusal(const std::string& name, const std::string& bytes) {
  const std::string path = temp(name);
  std::ofstream(path, std::ios::binary) << bytes;
  std::string what = "accepted";
  try {
    load_image(path);
  } catch (const Error& e) {
    what = e.what();
  }
  fs::remove(path);
  return what;
}
}  // namespace

// OpenCV allocates the frame a header states before it finds the file truncated: a PPM under a
// .jpg name claiming 30000×30000 (found by fuzzing) took 2.7 GB. PPM and TIFF headers are read
// first, as PNG, JPEG and BMP ones were, and a 64-bit RGBA TIFF within the pixel cap is refused
// for the 2 GB its samples decode to.
TEST(ImageIO, OversizedPpmAndTiffAreRefusedFromTheirHeader) {
  EXPECT_NE(
      refusal("huge-ppm.jpg", "P6\n# a comment 1 2 3\n30000 30000\n255\n\x01\x02").find("30000x30000 pixels, more than the 67 million"),
      std::string::npos);
  EXPECT_NE(refusal("huge-pgm.pgm", "P5 20000\t9000 65535 ").find("20000x9000 pixels"), std::string::npos);
  for (bool little : {true, false}) {
    const std::string wide = refusal("wide.tif", tiff(little, {{256, 4, {9000}}, {257, 3, {9000}}, {277, 3, {1}}}));
    EXPECT_NE(wide.find("wide.tif: 9000x9000 pixels, more than the 67 million"), std::string::npos) << little << ": " << wide;
    const std::string deep =
        refusal("deep.tif", tiff(little, {{256, 3, {8000}}, {257, 3, {8000}}, {258, 3, {64, 64, 64, 64}}, {277, 3, {4}}}));
    EXPECT_NE(deep.find("deep.tif: 8000x8000 pixels of 32 bytes each decode to more than 1024 MiB"), std::string::npos)
        << little << ": " << deep;
    // Within both caps the file goes on to the decoder, which finds it has no pixel data
    const std::string small = refusal("small.tif", tiff(little, {{256, 3, {800}}, {257, 3, {600}}, {258, 3, {8}}, {277, 3, {1}}}));
    EXPECT_NE(small.find("small.tif: cannot read image"), std::string::npos) << little << ": " << small;
  }
  // Real files of both formats still read: OpenCV's own TIFF (8 and 16 bits) and PPM, and a PGM
  // with a comment
  for (const char* ext : {".tif", ".ppm"})
    for (int depth : {CV_8U, CV_16U}) {
      const std::string path = temp(std::string("real") + ext);
      cv::Mat written(7, 9, CV_MAKETYPE(depth, 3), cv::Scalar::all(depth == CV_8U ? 51 : 13107));
      ASSERT_TRUE(cv::imwrite(path, written));
      const Image back = load_image(path);
      fs::remove(path);
      ASSERT_EQ(back.width, 9) << ext;
      EXPECT_EQ(back.height, 7) << ext;
      EXPECT_FLOAT_EQ(back.at(8, 6, 2), 0.2f) << ext << depth;
    }
  const std::string pgm = temp("comment.pgm");
  std::ofstream(pgm, std::ios::binary) << "P5\n# made by hand\n3 2\n255\n" << std::string("\x00\x80\xff\x00\x80\xff", 6);
  const Image grey = load_image(pgm);
  fs::remove(pgm);
  ASSERT_EQ(grey.width, 3);
  EXPECT_FLOAT_EQ(grey.at(2, 0, 0), 1.0f);
}

TEST(ImageIO, BigEndianPfmIsSwapped) {
  // One grey pixel 1.0f stored big-endian (scale > 0)
  const std::string bytes = std::string("Pf\n1 1\n1.0\n") + std::string("\x3f\x80\x00\x00", 4);
  EXPECT_EQ(parse_pfm(bytes, "be.pfm").pixels.at(0), 1.0f);
}

TEST(Outputs, AovsHoldNanOrOneWhereNothingWasHit) {
  Frame f;
  f.gbuffer.width = 2;
  f.gbuffer.height = 1;
  f.gbuffer.prim = {Hit::kNoHit, 5};
  f.gbuffer.position = {glm::vec3(0), glm::vec3(1, 2, 3)};
  f.gbuffer.normal = {glm::vec3(0), glm::vec3(0, 1, 0)};
  f.gbuffer.albedo = {glm::vec3(0), glm::vec3(0.5f)};
  f.gbuffer.depth = {INFINITY, 4.5f};
  f.visibility = {1.0f, 0.25f};
  f.maps.width = 2;
  f.maps.height = 1;
  f.maps.rays = {0, 10};
  f.maps.quality = {0.1f, 1.0f};
  f.maps.blend = {0, 1};
  f.maps.eccentricity = {9, 0};
  EXPECT_EQ(aov_image(f, "ao").pixels, (std::vector<float>{1.0f, 0.25f}));
  EXPECT_TRUE(std::isnan(aov_image(f, "depth").pixels[0]));
  EXPECT_EQ(aov_image(f, "depth").pixels[1], 4.5f);
  EXPECT_TRUE(std::isnan(aov_image(f, "position").pixels[0]));
  EXPECT_EQ(aov_image(f, "position").pixels[5], 3.0f);
  EXPECT_EQ(aov_image(f, "budget").pixels[1], 10.0f);
  EXPECT_THROW(aov_image(f, "colour"), Error);
  EXPECT_THROW(write_aovs(f, "ao"), Error);
  EXPECT_THROW(write_aovs(f, "ao=x.png"), Error);
}

TEST(ImageIO, DisplayBytesAreTheSavedPngBytes) {
  // Every float around every step of the sRGB byte, and a sweep, against lround(255·linear_to_srgb(v))
  std::vector<float> values = {-1.0f, 0.0f, -0.0f, 1e-30f, 1.0f, 2.0f, NAN, INFINITY};
  for (int i = 0; i <= 200000; ++i) values.push_back(-0.01f + 1.02f * i / 200000.0f);
  for (int k = 0; k <= 255; ++k) {
    // the linear value whose sRGB encoding is exactly (k − 0.5)/255, and its neighbours
    const float s = (k - 0.5f) / 255.0f;
    float v = s <= 0.04045f ? s / 12.92f : std::pow((s + 0.055f) / 1.055f, 2.4f);
    for (int d = 0; d < 8; ++d) v = std::nextafter(v, -1.0f);
    for (int d = 0; d < 16; ++d, v = std::nextafter(v, 2.0f)) values.push_back(v);
  }
  Image img(static_cast<int>(values.size()), 1, 1);
  img.pixels = values;
  const Rgba8 bytes = to_rgba8(img);
  for (size_t i = 0; i < values.size(); ++i) {
    const long expected = std::lround(linear_to_srgb(values[i]) * 255.0f);
    ASSERT_EQ(bytes.at(static_cast<int>(i), 0)[0], expected) << "v = " << values[i];
    ASSERT_EQ(srgb_byte(values[i]), expected) << "v = " << values[i];
  }
}

TEST(ImageIO, DisplayFloatsFollowTheSrgbCurve) {
  // IEC 61966-2-1's curve, in double precision: the oracle
  auto srgb = [](double v) { return v <= 0.0031308 ? 12.92 * v : 1.055 * std::pow(v, 1 / 2.4) - 0.055; };
  std::vector<float> values;
  for (int i = 0; i <= 300000; ++i) values.push_back(static_cast<float>(i) / 300000.0f);
  for (float v = 0.0031308f, d = 0; d < 64; ++d) values.push_back(v = std::nextafter(v, 2.0f));  // the knee
  for (float v = 1e-6f; v < 1; v *= 1.37f) values.push_back(v);
  const int width = static_cast<int>(values.size());
  std::vector<float> out(values.size());
  linear_to_srgb(values.data(), out.data(), width, 1, 1, 0.0f, 1.0f, false);
  double worst = 0;
  for (size_t i = 0; i < values.size(); ++i) worst = std::max(worst, std::abs(out[i] - srgb(values[i])));
  EXPECT_LT(worst, 1e-6);
  // Clipped to [0, 1] first, then mapped to [low, high] (PsychoPy's −1 … 1)
  const std::vector<float> edge = {-3.0f, 0.0f, 0.5f, 1.0f, 7.0f};
  std::vector<float> mapped(edge.size());
  linear_to_srgb(edge.data(), mapped.data(), 5, 1, 1, -1.0f, 1.0f, false);
  EXPECT_FLOAT_EQ(mapped[0], -1.0f);
  EXPECT_FLOAT_EQ(mapped[1], -1.0f);
  EXPECT_NEAR(mapped[2], -1.0 + 2 * srgb(0.5), 1e-6);
  EXPECT_FLOAT_EQ(mapped[3], 1.0f);
  EXPECT_FLOAT_EQ(mapped[4], 1.0f);
}

TEST(ImageIO, DisplayFloatsGoBottomUpWithAlphaUnencodedAndRefuseWhatIsNotFinite) {
  // 2 × 3 pixels of RGBA: rows reversed (OpenGL's order), alpha clipped and mapped but not encoded
  std::vector<float> in(2 * 3 * 4);
  for (size_t i = 0; i < in.size(); ++i) in[i] = static_cast<float>(i) / static_cast<float>(in.size());
  std::vector<float> out(in.size());
  linear_to_srgb(in.data(), out.data(), 2, 3, 4, 0.0f, 1.0f, true);
  for (int y = 0; y < 3; ++y)
    for (int x = 0; x < 2; ++x)
      for (int c = 0; c < 4; ++c) {
        const float v = in[static_cast<size_t>(((2 - y) * 2 + x) * 4 + c)];
        EXPECT_NEAR(out[static_cast<size_t>((y * 2 + x) * 4 + c)], c == 3 ? v : linear_to_srgb(v), 1e-6) << x << "," << y << "," << c;
      }
  // In place, top-down: the same values
  std::vector<float> same = in;
  linear_to_srgb(same.data(), same.data(), 2, 3, 4, 0.0f, 1.0f, false);
  for (size_t i = 0; i < in.size(); ++i) EXPECT_FLOAT_EQ(same[i], out[static_cast<size_t>(((2 - i / 8) * 8) + i % 8)]);
  // Reversed into itself it would overwrite rows not yet read: refused
  EXPECT_THROW(linear_to_srgb(same.data(), same.data(), 2, 3, 4, 0.0f, 1.0f, true), Error);
  // A value not finite: an error naming its pixel and channel, and nothing written
  std::vector<float> bad(2 * 3 * 3, 0.25f);
  bad[static_cast<size_t>((2 * 2 + 1) * 3 + 2)] = NAN;  // pixel (1, 2), channel 2
  std::vector<float> untouched(bad.size(), -5.0f);
  try {
    linear_to_srgb(bad.data(), untouched.data(), 2, 3, 3, 0.0f, 1.0f, false);
    FAIL() << "no error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("pixel (1, 2) channel 2 is nan"), std::string::npos) << e.what();
  }
  for (const float v : untouched) EXPECT_EQ(v, -5.0f);
}
