// foveal/util/units.h — angle units, defined once for every module (and the GPU's per-pixel code).
#pragma once

#include <numbers>

namespace foveal {

// Degrees per radian, 180/π: degrees = radians · kDeg.
inline constexpr double kDeg = 180.0 / std::numbers::pi;

}  // namespace foveal
