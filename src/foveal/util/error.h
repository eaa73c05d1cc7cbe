// foveal/util/error.h — the one exception type the library throws for bad input.
#pragma once

#include <stdexcept>
#include <string>

namespace foveal {

// A user-facing error: one line that names the file, line or option and the reason.
struct Error : std::runtime_error {
  using std::runtime_error::runtime_error;
};

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
