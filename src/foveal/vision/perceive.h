// foveal/vision/perceive.h — a person's eye applied to a stimulus image (what `foveal perceive`
// and foveal.perceive do per frame): the optics (defocus at the viewing distance, or per pixel
// from a depth map, thin lens as simulate's), then the ocular media, the retina and colour vision.
#pragma once

#include "foveal/impair/impairments.h"
#include "foveal/impair/profile.h"
#include "foveal/perception/foveation.h"
#include "foveal/util/image.h"
#include "foveal/vision/blur.h"

#include <glm/vec2.hpp>

#include <memory>
#include <optional>
#include <string>

namespace foveal {

struct PerceiveParams {
  EyeSpec eye;                              // the eye (resolve_eye: presets or a profile)
  Display display{47.5, 30.0, 60.0, 0, 0};  // res_x = res_y = 0: the stimulus fills the width, square pixels
  std::optional<Image> depth;               // metres from the eye per pixel (finite > 0, or +inf), the stimulus's size
  bool optics = true;                       // the defocus blur (off: the media, field and colour only)
  BlurParams blur;
};

class Perceiver {
 public:
  explicit Perceiver(PerceiveParams params);
  // One linear-RGB (3 channels) or RGBA (4: the alpha passes through) frame seen while fixating
  // `gaze` (image pixels, origin top-left). Throws Error naming gaze_px or depth.
  Image see(const Image& linear, glm::dvec2 gaze) const;
  const PerceiveParams& params() const { return params_; }
  const ImpairmentPasses& passes() const { return *passes_; }
  // The display a w × h stimulus fills (the stimulus's own resolution where none is given).
  Display display_for(int width, int height) const;

 private:
  Image see_rgb(const Image& in, glm::dvec2 gaze) const;
  PerceiveParams params_;
  std::unique_ptr<ImpairmentPasses> passes_;
};

// A depth map's check: every depth finite and > 0, or +inf (far away); throws Error naming `name`,
// the count of bad depths and the first one's pixel.
void check_depth_map(const Image& depth, const std::string& name);

// 8- or 16-bit sRGB-encoded values (0–1) to linear, grey to three channels; 3 or 4 channels
// (RGBA: the alpha is no colour and stays as it is). `srgb` false: the values are linear already
// (EXR, PFM). Throws Error naming `name` for other channel counts.
Image stimulus_to_linear(Image image, bool srgb, const std::string& name);

// A glare test card, linear HDR: a dark room (0.02) with bright lamps (luminance 40) and a white
// bar chart, 960×540 — what forward scatter shows best (builtin:lamps).
Image lamps_card();

}  // namespace foveal
