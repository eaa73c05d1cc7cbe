// foveal/util/image.h — a plain float image: width × height × channels, rows top to bottom.
#pragma once

#include <cstddef>
#include <vector>

namespace foveal {

// Interleaved float pixels; row 0 is the top of the image.
struct Image {
  int width = 0;
  int height = 0;
  int channels = 0;
  std::vector<float> pixels;  // size width*height*channels

  Image() = default;
  Image(int w, int h, int c, float fill = 0.0f)
      : width(w), height(h), channels(c), pixels(static_cast<size_t>(w) * h * c, fill) {}

  // Pixel (x, y), channel c.
  float& at(int x, int y, int c = 0) {
    return pixels[(static_cast<size_t>(y) * width + x) * channels + c];
  }
  float at(int x, int y, int c = 0) const {
    return pixels[(static_cast<size_t>(y) * width + x) * channels + c];
  }
  bool empty() const { return pixels.empty(); }
};

}  // namespace foveal
