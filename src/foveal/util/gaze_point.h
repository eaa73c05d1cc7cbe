// foveal/util/gaze_point.h — one rule for every gaze or fixation point a caller gives in render
// pixels: finite, and near the image (within ten image widths and heights of it). A point beyond
// that is no place the eye can look on this display, and squares of coordinates near 1e155
// overflow the models' arithmetic into silently wrong answers (issue 36, findings 6 and 7).
#pragma once

#include "foveal/util/error.h"

#include <cmath>

namespace foveal {

inline constexpr double kGazeReachImages = 10;  // how many image sizes beyond its edges a point may lie

// Whether (x, y) lies within kGazeReachImages image sizes of a width × height image (false for a
// coordinate that is not finite).
inline bool gaze_point_near(double x, double y, int width, int height) {
  const double w = width, h = height, k = kGazeReachImages;
  return x >= -k * w && x <= (k + 1) * w && y >= -k * h && y <= (k + 1) * h;
}

// Throws Error naming `name` unless (x, y) is finite and within kGazeReachImages image sizes of a
// width × height image.
inline void check_gaze_point(const char* name, double x, double y, int width, int height) {
  if (!(std::isfinite(x) && std::isfinite(y))) fail("{}: must be finite render pixels, got ({}, {})", name, x, y);
  if (!gaze_point_near(x, y, width, height))
    fail("{}: ({}, {}) is not near the {}x{} image (render pixels; at most {:g} image widths and heights beyond its edges)", name, x, y,
         width, height, kGazeReachImages);
}

}  // namespace foveal
