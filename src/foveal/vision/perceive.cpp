// foveal/vision/perceive.cpp — a person's eye applied to a stimulus image.
#include "foveal/vision/perceive.h"

#include "foveal/io/image_io.h"
#include "foveal/perception/eye.h"
#include "foveal/util/error.h"
#include "foveal/util/gaze_point.h"

#include <glm/geometric.hpp>
#include <glm/trigonometric.hpp>

#include <algorithm>
#include <cmath>

namespace foveal {

Perceiver::Perceiver(PerceiveParams params) : params_(std::move(params)) {
  validate(params_.eye.eye);
  if (params_.depth) check_depth_map(*params_.depth, "depth");
  if (params_.blur.taps < 1 || params_.blur.taps > 1024) fail("blur_taps: must be in [1, 1024], got {}", params_.blur.taps);
  passes_ = std::make_unique<ImpairmentPasses>(params_.eye.impair.any() ? params_.eye.impair : Impairments{});
}

Display Perceiver::display_for(int width, int height) const {
  Display d = params_.display;
  if (d.res_x <= 0 || d.res_y <= 0) {  // the stimulus fills the display's width, with square pixels
    d.res_x = width;
    d.res_y = height;
    d.height_cm = d.width_cm * height / width;
  }
  return d;
}

Image Perceiver::see(const Image& in, glm::dvec2 gaze) const {
  if (in.channels == 4) {  // the eye sees the colour; the alpha passes through (transparent stays transparent)
    Image rgb(in.width, in.height, 3);
    const size_t n = size_t(in.width) * in.height;
    for (size_t i = 0; i < n; ++i)
      for (int c = 0; c < 3; ++c) rgb.pixels[i * 3 + c] = in.pixels[i * 4 + c];
    const Image seen = see_rgb(rgb, gaze);
    Image out = in;
    for (size_t i = 0; i < n; ++i)
      for (int c = 0; c < 3; ++c) out.pixels[i * 4 + c] = seen.pixels[i * 3 + c];
    return out;
  }
  if (in.channels != 3) fail("image: {} channels; the eye sees RGB or RGBA (grey: stimulus_to_linear makes it RGB)", in.channels);
  return see_rgb(in, gaze);
}

Image Perceiver::see_rgb(const Image& in, glm::dvec2 gaze) const {
  const std::optional<Image>& depth = params_.depth;
  if (depth && (depth->width != in.width || depth->height != in.height))
    fail("depth: {}x{}, the input is {}x{}", depth->width, depth->height, in.width, in.height);
  check_gaze_point("gaze_px", gaze.x, gaze.y, in.width, in.height);
  const Display d = display_for(in.width, in.height);
  const Retinotopy r = display_retinotopy(d, in.width, in.height, gaze);
  const EyeParams& eye = params_.eye.eye;
  Image out = in;
  if (params_.optics) {
    // The eye accommodates to the fixated point; a pixel's CoC is A·|1/D − v| plus the peripheral
    // penalty × its eccentricity (as simulate; without depth the stimulus is a plane at the viewing distance)
    const double plane_m = d.distance_cm / 100.0;
    auto depth_at = [&](double x, double y) {  // clamped in floating point: a far gaze is no int overflow
      if (!depth) return plane_m;
      const int xi = static_cast<int>(std::clamp(x, 0.0, in.width - 1.0)), yi = static_cast<int>(std::clamp(y, 0.0, in.height - 1.0));
      return static_cast<double>(depth->at(xi, yi, 0));
    };
    const double v = accommodate(eye, depth_at(gaze.x, gaze.y));
    const double penalty = peripheral_penalty_per_deg(eye);
    std::vector<float> coc(size_t(in.width) * in.height);
    CocShape shape;
    const bool astigmatic = eye.cylinder_d > 0;
    if (astigmatic) shape.scale.resize(coc.size());
    shape.axis_deg = static_cast<float>(eye.cylinder_axis_deg);
    for (int y = 0; y < in.height; ++y)
      for (int x = 0; x < in.width; ++x) {
        const size_t i = size_t(y) * in.width + x;
        const double ecc = glm::length(glm::dvec2(r.field_deg[i]));
        const glm::dvec2 axes = glm::degrees(coc_axes_rad(eye, depth_at(x, y), v)) + penalty * ecc;
        const double major = std::max(axes.x, axes.y);
        coc[i] = static_cast<float>(major * r.ppd);
        if (astigmatic) shape.scale[i] = major > 0 ? glm::vec2(axes / major) : glm::vec2(1.0f);
      }
    out = variable_blur(in, coc, params_.blur, astigmatic ? &shape : nullptr);
  }
  passes_->apply(out, r);
  return out;
}

void check_depth_map(const Image& d, const std::string& name) {
  size_t bad = 0;
  glm::ivec2 first(-1);
  for (int y = 0; y < d.height; ++y)
    for (int x = 0; x < d.width; ++x) {
      const float v = d.at(x, y, 0);
      if (!(v > 0) && bad++ == 0) first = {x, y};  // NaN, zero, negative (+inf passes: far)
    }
  if (bad)
    fail("{}: {} depths are NaN, zero or negative (the first at pixel {},{}: {}); depths are metres from the eye, > 0, or inf for far away",
         name, bad, first.x, first.y, d.at(first.x, first.y, 0));
}

Image stimulus_to_linear(Image im, bool srgb, const std::string& name) {
  if (im.channels == 1) {  // grey: three equal channels
    Image rgb(im.width, im.height, 3);
    for (size_t i = 0; i < im.pixels.size(); ++i) rgb.pixels[i * 3] = rgb.pixels[i * 3 + 1] = rgb.pixels[i * 3 + 2] = im.pixels[i];
    im = std::move(rgb);
  }
  if (im.channels != 3 && im.channels != 4) fail("{}: {} channels; perceive reads grey, RGB or RGBA images", name, im.channels);
  if (srgb)
    for (size_t i = 0; i < im.pixels.size(); ++i)
      if (im.channels == 3 || i % 4 != 3) im.pixels[i] = srgb_to_linear(im.pixels[i]);  // alpha is no colour
  return im;
}

Image lamps_card() {
  Image im(960, 540, 3, 0.02f);
  const glm::vec2 lamps[] = {{160, 140}, {480, 110}, {800, 140}, {300, 420}, {660, 420}};
  for (int y = 0; y < im.height; ++y)
    for (int x = 0; x < im.width; ++x) {
      float v = 0.02f;
      for (const glm::vec2 c : lamps)
        if (glm::length(glm::vec2(x, y) - c) < 9) v = 40.0f;
      if (y > 250 && y < 300 && x > 280 && x < 680 && (x / 20) % 2 == 0) v = 0.8f;  // bars of a chart
      for (int k = 0; k < 3; ++k) im.at(x, y, k) = v;
    }
  return im;
}

}  // namespace foveal
