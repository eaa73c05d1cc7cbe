// Tests of the option parsers every command shares: a good value comes back exactly, and a bad one
// is an Error that names the option and the text given, in the form the user was meant to write.
#include "foveal/util/parse.h"

#include "foveal/util/error.h"

#include <gtest/gtest.h>

#include <cmath>
#include <string>

using namespace foveal;

namespace {
// The message of the Error that `f` throws, or "" where it throws none.
template <class F>
std::string error_of(F&& f) {
  try {
    f();
  } catch (const Error& e) {
    return e.what();
  }
  return "";
}
}  // namespace

TEST(Parse, SizesAreWholePixelsEachSideOfOneX) {
  EXPECT_EQ(parse_size("--size", "840x525"), glm::ivec2(840, 525));
  EXPECT_EQ(parse_size("--size", "1X1"), glm::ivec2(1, 1));
  EXPECT_EQ(parse_size("--size", "16384x16384"), glm::ivec2(16384, 16384));
  // a malformed size names the form, the option and the text, whatever part of it is wrong
  for (const char* bad : {"10x", "x10", "840", "", "1,2x3", "10x10x10", "ax5", "5xb", "5x5 px", "nanx5", "5xinf"}) {
    const auto message = error_of([&] { parse_size("--size", bad); });
    EXPECT_NE(message.find("--size: expected WIDTHxHEIGHT in pixels (as 840x525), got '" + std::string(bad) + "'"), std::string::npos)
        << bad << ": " << message;
  }
  // a well-formed size out of range says the range
  for (const char* bad : {"0x10", "10x0", "16385x2", "2.5x3", "-4x3"}) {
    const auto message = error_of([&] { parse_size("--size", bad); });
    EXPECT_NE(message.find("between 1x1 and 16384x16384, got '" + std::string(bad) + "'"), std::string::npos) << bad << ": " << message;
  }
}

TEST(Parse, NumbersAreFiniteAndCounted) {
  EXPECT_EQ(parse_numbers("--at", "1.5,-2,3e2"), (std::vector<double>{1.5, -2, 300}));
  EXPECT_EQ(parse_vec2("--gaze", "418,292"), glm::dvec2(418, 292));
  EXPECT_EQ(parse_vec2("--gaze", "418, 292"), glm::dvec2(418, 292));  // a space after the comma
  EXPECT_EQ(parse_size("--size", "840x 525"), glm::ivec2(840, 525));
  EXPECT_EQ(parse_vec3("--eye", "0,1.5,-2"), glm::vec3(0, 1.5f, -2));
  EXPECT_NE(error_of([] { parse_vec2("--gaze", "418"); }).find("--gaze: expected 2 comma-separated numbers, got '418'"), std::string::npos);
  EXPECT_NE(error_of([] { parse_vec2("--gaze", "1,2,3"); }).find("expected 2"), std::string::npos);
  for (const char* bad : {"1,,2", "1,x", "nan,1", "1,inf", "1.5.2,1"})
    EXPECT_NE(error_of([&] { parse_vec2("--gaze", bad); }).find("is not a finite number"), std::string::npos) << bad;
  EXPECT_EQ(parse_length_or_inf("--focus", "inf"), INFINITY);
  EXPECT_EQ(parse_length_or_inf("--focus", "0.5"), 0.5f);
  EXPECT_NE(error_of([] { parse_length_or_inf("--focus", "0"); }).find("--focus: must be > 0 or 'inf', got '0'"), std::string::npos);
  EXPECT_NE(error_of([] { require_positive(0, "--rate"); }).find("--rate: must be a positive number"), std::string::npos);
  EXPECT_NE(error_of([] { require_non_negative(-1, "--start"); }).find("--start: must be zero or positive"), std::string::npos);
  EXPECT_EQ(error_of([] { require_non_negative(0, "--start"); }), "");
}
