// foveal/util/parse.cpp — option value parsing.
#include "foveal/util/parse.h"

#include "foveal/util/error.h"
#include "foveal/util/text.h"

#include <cmath>
#include <limits>
#include <sstream>

namespace foveal {

std::vector<double> parse_numbers(const std::string& option, const std::string& text, size_t count) {
  std::vector<double> values;
  std::stringstream stream(text);
  std::string item;
  while (std::getline(stream, item, ',')) {
    const auto v = foveal::text::to_number(item);  // (the whole field, finite; spaces around it allowed: "418, 292")
    if (!v) fail("{}: '{}' is not a finite number", option, item);
    values.push_back(*v);
  }
  if (count != 0 && values.size() != count) fail("{}: expected {} comma-separated numbers, got '{}'", option, count, text);
  return values;
}

glm::ivec2 parse_size(const std::string& option, const std::string& text) {
  // One number each side of one x: "840x525". Anything else ("10x", "x10", "1,2x3", "10x10x10") is
  // named as the wrong form, not as a list of numbers the user never meant to give.
  const auto x = text.find_first_of("xX");
  const auto side = [&](const std::string& part) {
    const auto v = foveal::text::to_number(part);
    if (!v) fail("{}: expected WIDTHxHEIGHT in pixels (as 840x525), got '{}'", option, text);
    return *v;
  };
  if (x == std::string::npos) fail("{}: expected WIDTHxHEIGHT in pixels (as 840x525), got '{}'", option, text);
  const double w = side(text.substr(0, x)), h = side(text.substr(x + 1));
  if (w != std::floor(w) || h != std::floor(h) || w < 1 || h < 1 || w > 16384 || h > 16384)
    fail("{}: size must be whole pixels between 1x1 and 16384x16384, got '{}'", option, text);
  return {static_cast<int>(w), static_cast<int>(h)};
}

glm::dvec2 parse_vec2(const std::string& option, const std::string& text) {
  const auto v = parse_numbers(option, text, 2);
  return {v[0], v[1]};
}

glm::vec3 parse_vec3(const std::string& option, const std::string& text) {
  const auto v = parse_numbers(option, text, 3);
  return {static_cast<float>(v[0]), static_cast<float>(v[1]), static_cast<float>(v[2])};
}

void require_positive(double v, const char* option) {
  if (!(v > 0) || !std::isfinite(v)) fail("{}: must be a positive number, got {}", option, v);
}

void require_non_negative(double v, const char* option) {
  if (!(v >= 0) || !std::isfinite(v)) fail("{}: must be zero or positive, got {}", option, v);
}

float parse_length_or_inf(const std::string& option, const std::string& text) {
  if (text == "inf" || text == "infinity") return std::numeric_limits<float>::infinity();
  const double v = parse_numbers(option, text, 1)[0];
  if (!(v > 0)) fail("{}: must be > 0 or 'inf', got '{}'", option, text);
  return static_cast<float>(v);
}

}  // namespace foveal
