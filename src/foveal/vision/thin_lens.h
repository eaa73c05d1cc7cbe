// foveal/vision/thin_lens.h — the physically based reference for the blur: distributed ray
// tracing through a thin lens the size of the pupil, focused like the eye (many lens samples per
// pixel), and the approximation it is compared with (one pinhole image blurred per pixel).
#pragma once

#include "foveal/render/render.h"
#include "foveal/vision/blur.h"

namespace foveal {

struct ThinLensParams {
  int width = 512, height = 384;
  int samples = 256;          // lens samples per pixel (Sobol points on the pupil disc)
  double focus_vergence = 0;  // dioptres (1/m): what the eye accommodates to; ≤ 0 allowed
  double pupil_diameter_mm = 3.5;
  float ambient = 0.3f;  // constant Phong ambient factor, as in the simulation
};

// The camera's pixels per degree at the image centre (vertical field of view over the height).
double camera_pixels_per_degree(const Camera& camera, int height);

// The reference image: every pixel averages `samples` rays from points of the pupil disc through
// the pixel's point on the focal plane.
Image thin_lens_reference(const Tracer& tracer, const Scene& scene, const Camera& camera, const ThinLensParams& params);

// The approximation: the pinhole image blurred with each pixel's CoC A·|1/D − v| in camera pixels.
Image thin_lens_approximation(const Tracer& tracer, const Scene& scene, const Camera& camera, const ThinLensParams& params,
                              const BlurParams& blur = {});

}  // namespace foveal
