// foveal/util/parse.h — parsing option values ("840x525", "1.5,2", "inf"); errors name the option.
#pragma once

#include <glm/glm.hpp>

#include <string>
#include <vector>

namespace foveal {

// Comma-separated finite numbers; exactly `count` of them unless count is 0.
std::vector<double> parse_numbers(const std::string& option, const std::string& text, size_t count = 0);
// "WxH" in pixels, each in [1, 16384].
glm::ivec2 parse_size(const std::string& option, const std::string& text);
// "X,Y".
glm::dvec2 parse_vec2(const std::string& option, const std::string& text);
// "X,Y,Z".
glm::vec3 parse_vec3(const std::string& option, const std::string& text);
// Checks of a parameter already parsed: a finite number > 0 / ≥ 0, else Error naming the option.
void require_positive(double value, const char* option);
void require_non_negative(double value, const char* option);
// A positive length or "inf".
float parse_length_or_inf(const std::string& option, const std::string& text);

}  // namespace foveal
