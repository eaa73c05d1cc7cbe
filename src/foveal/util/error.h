// foveal/util/error.h — the one exception type the library throws for bad input.
#pragma once

#include <span>
#include <stdexcept>
#include <string>
#include <string_view>

namespace foveal {

// A user-facing error: one line that names the file and line, or the parameter, and the reason.
//
// An error about one parameter begins with the parameter's own name — the field of the params
// struct that holds it, in its unit ("max_rays: must be in [0, 65535], got -1",
// "pupil_diameter_mm: must be in (0, 10] mm") — never a front end's word for it, so that each front
// end says it in its caller's words: the command line names its flag (--max-rays), Python its
// keyword argument (max_rays), with in_words() below.
struct Error : std::runtime_error {
  using std::runtime_error::runtime_error;
};

// One parameter's name in the library and in a front end.
struct ParameterName {
  std::string_view library;    // "pupil_diameter_mm"
  std::string_view front_end;  // "--pupil" (the command line), "pupil_mm" (Python)
};
// The message with the parameter it begins with, and any other snake_case parameter it mentions,
// renamed into the front end's words; the rest unchanged.
std::string in_words(std::string_view message, std::span<const ParameterName> names);

}  // namespace foveal

// fmt 9 does not compile under nvcc: CUDA sources throw Error with a ready string
#if !defined(__CUDACC__)
#include <fmt/format.h>

namespace foveal {

// Throw an Error with an fmt-formatted message.
template <class... Args>
[[noreturn]] void fail(fmt::format_string<Args...> format, Args&&... args) {
  throw Error(fmt::format(format, std::forward<Args>(args)...));
}

}  // namespace foveal
#endif
