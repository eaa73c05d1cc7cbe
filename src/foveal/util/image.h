// foveal/util/image.h — a plain float image: width × height × channels, rows top to bottom.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

namespace foveal {

// Interleaved float pixels; row 0 is the top of the image.
struct Image {
  int width = 0;
  int height = 0;
  int channels = 0;
  std::vector<float> pixels;  // size width*height*channels

  Image() = default;
  Image(int w, int h, int c, float fill = 0.0f) : width(w), height(h), channels(c), pixels(static_cast<size_t>(w) * h * c, fill) {}

  // Pixel (x, y), channel c.
  float& at(int x, int y, int c = 0) { return pixels[(static_cast<size_t>(y) * width + x) * channels + c]; }
  float at(int x, int y, int c = 0) const { return pixels[(static_cast<size_t>(y) * width + x) * channels + c]; }
  bool empty() const { return pixels.empty(); }
};

// 8-bit sRGB RGBA pixels, rows top to bottom (the layout of an OpenGL GL_RGBA / GL_UNSIGNED_BYTE texture).
struct Rgba8 {
  int width = 0, height = 0;
  std::vector<uint8_t> px;  // width·height·4
  Rgba8() = default;
  Rgba8(int w, int h) : width(w), height(h), px(static_cast<size_t>(w) * h * 4, 255) {}
  uint8_t* at(int x, int y) { return px.data() + (static_cast<size_t>(y) * width + x) * 4; }
  const uint8_t* at(int x, int y) const { return px.data() + (static_cast<size_t>(y) * width + x) * 4; }
  bool empty() const { return px.empty(); }
};

}  // namespace foveal
