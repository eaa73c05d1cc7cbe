// foveal/io/plot.h — a small line plot (polylines and labels) written as SVG or PNG (OpenCV):
// the acuity plot, the error-against-eccentricity plot. Written by hand because no packaged C++
// library writes both from one description without a plotting runtime.
#pragma once

#include <glm/glm.hpp>

#include <string>
#include <vector>

namespace foveal {

// Drawing primitives shared by the SVG and PNG back ends.
struct Stroke {
  std::vector<glm::vec2> points;  // plot pixels, origin top-left
  glm::vec3 colour;               // RGB in [0, 1]
  float width = 2;
  bool dashed = false;
};
struct Label {
  glm::vec2 at;
  std::string text;
  float size = 14;
  bool centred = false;
};
struct Plot {
  int width = 720, height = 440;
  std::vector<Stroke> strokes;
  std::vector<Label> labels;
};

// The heat colour map for a fraction t in [0, 1] (dark blue → cyan → yellow → red), sRGB bytes:
// error maps, the viewer's AO budget.
glm::u8vec3 heat_colour(float t);

// Write by extension: .svg or .png; throws Error naming the file.
void save_plot(const Plot& plot, const std::string& path);
// The extensions save_plot writes: .png and .svg.
const std::vector<std::string>& plot_extensions();

}  // namespace foveal
