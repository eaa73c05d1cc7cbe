// foveal/ui/overlays.h — what the viewer draws over a rendered image: the gaze and fixation,
// the elliptical ROI contours q(E) = 1, 0.5, 0.25, the AO budget as a heat map, the scan path,
// and the sharpness field's sharp region. Drawn into an 8-bit sRGB RGBA buffer, the texture the
// window shows and the screenshot it writes.
#pragma once

#include "foveal/perception/foveation.h"
#include "foveal/util/image.h"

#include <glm/glm.hpp>

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

namespace foveal {

// Paste `src` into `dst` with its top-left corner at (x0, y0).
void paste(Rgba8& dst, const Rgba8& src, int x0, int y0);

// Which overlays are drawn.
struct Overlays {
  bool gaze = true;       // red cross at the raw gaze, white ring at the fixation the render follows
  bool contours = false;  // ROI contours where q(E) = 1 (yellow), 0.5 (orange), 0.25 (red)
  bool budget = false;    // AO rays n(E)/n_max as a heat map over the image (half transparent)
  bool scanpath = false;  // the recent fixations joined in order
  bool sharp = false;     // vision mode: pixels the sharpness field remembers sharp, tinted green
};
// "gaze,contours,budget,scanpath,sharp" in any order, or "all", or "none".
Overlays parse_overlays(const std::string& text);
std::string to_string(const Overlays& overlays);

// q(E) on a coarse grid (every `step` pixels, with the far edges included), bilinearly
// interpolated: the overlays follow the gaze every displayed frame at a fraction of the
// renderer's per-pixel cost.
class QualityGrid {
 public:
  QualityGrid(const FoveationModel& model, int width, int height, int step = 4);
  // q at a render position (pixel centres at +0.5), interpolated.
  float quality(double x_px, double y_px) const;
  // q at every pixel centre (row-major), the same values as quality(x + 0.5, y + 0.5).
  void fill(std::vector<float>& q) const;

 private:
  int width_, height_, step_, nx_, ny_;
  std::vector<float> q_;
};

// What the overlays need of the current frame. Positions are render pixels of the image the
// overlays are drawn on (origin top-left).
struct OverlayInputs {
  std::optional<glm::dvec2> gaze;              // the latest raw gaze sample
  std::optional<glm::dvec2> fixation;          // the fixation the render follows
  std::vector<glm::dvec2> scanpath;            // recent fixations, oldest first
  const FoveationModel* model = nullptr;       // contours and budget (nullptr: not drawn)
  const std::vector<float>* coc_px = nullptr;  // per-pixel remembered CoC (sharp region; nullptr: not drawn)
  float sharp_px = 1.0f;                       // a pixel is sharp when its CoC is below this
};

// Draw the overlays into the region of `image` at (x0, y0) of the render's size `width`×`height`.
void draw_overlays(Rgba8& image, int x0, int y0, int width, int height, const Overlays& which, const OverlayInputs& in);

}  // namespace foveal
