// tests/test_scenes.h — what the unit tests share: the built-in scenes, built once per test
// process, and a bit-for-bit comparison of images. One copy for every test file (the test binary is
// compiled in batches, so two files' private copies would collide).
#pragma once

#include "foveal/scene/scene.h"

#include <cstring>
#include <vector>

namespace foveal_test {

inline const foveal::Scene& sphere_plane() {
  static const foveal::Scene scene = foveal::make_builtin_scene("sphere-plane");
  return scene;
}
inline const foveal::Scene& box() {
  static const foveal::Scene scene = foveal::make_builtin_scene("box");
  return scene;
}

// Two float images equal to the last bit (NaNs included)
inline bool same_bits(const std::vector<float>& a, const std::vector<float>& b) {
  return a.size() == b.size() && std::memcmp(a.data(), b.data(), a.size() * sizeof(float)) == 0;
}

}  // namespace foveal_test
