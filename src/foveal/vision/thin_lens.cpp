// foveal/vision/thin_lens.cpp — distributed ray tracing through the eye's lens.
#include "foveal/vision/thin_lens.h"

#include "foveal/util/error.h"
#include "foveal/util/sampling.h"

#include <cmath>
#include <numbers>

namespace foveal {

double camera_pixels_per_degree(const Camera& camera, int height) {
  return 0.5 * height / std::tan(glm::radians(0.5 * camera.fov_deg)) * (std::numbers::pi / 180.0);
}

namespace {

void check(const ThinLensParams& p) {
  if (p.width < 1 || p.height < 1) fail("thin lens: empty image");
  if (p.samples < 1 || p.samples > 65536) fail("lens_samples: must be in [1, 65536], got {}", p.samples);
  if (!(p.pupil_diameter_mm > 0)) fail("pupil_diameter_mm: must be positive, got {}", p.pupil_diameter_mm);
}

}  // namespace

Image thin_lens_reference(const Tracer& tracer, const Scene& scene, const Camera& camera, const ThinLensParams& p) {
  check(p);
  const CameraRays pinhole(camera, p.width, p.height);
  const glm::vec3 forward = glm::normalize(camera.look - camera.eye);
  const glm::vec3 right = glm::normalize(glm::cross(forward, camera.up)), up = glm::cross(right, forward);
  const double radius = 0.5 * p.pupil_diameter_mm * 1e-3 / scene.meters_per_unit;  // scene units
  const double v = p.focus_vergence * scene.meters_per_unit;                       // per scene unit
  const float epsilon = surface_epsilon(scene.bounds());
  Image sum(p.width, p.height, 3, 0.0f);
  for (int s = 0; s < p.samples; ++s) {
    // Sobol point → uniform point on the disc (polar map)
    const double u1 = sobol_dim0(uint32_t(s)) * 0x1.0p-32, u2 = sobol_dim1(uint32_t(s)) * 0x1.0p-32;
    const double r = radius * std::sqrt(u1), a = 2 * std::numbers::pi * u2;
    const glm::vec3 lens = float(r * std::cos(a)) * right + float(r * std::sin(a)) * up;
    const GBuffer g = trace_gbuffer(tracer, scene, p.width, p.height, [&](int x, int y) {
      Ray ray = pinhole(x + 0.5, y + 0.5);
      // Through the lens point towards the pixel's point on the focal plane 1/v away:
      // direction ∝ d/(d·f) − v·lens (v ≤ 0: parallel or diverging)
      const glm::vec3 d = ray.dir / glm::dot(ray.dir, forward);
      ray.org = camera.eye + lens;
      ray.dir = glm::normalize(d - float(v) * lens);
      return ray;
    });
    const Image c = shade_constant_ambient(scene, camera, g, p.ambient, epsilon);
    for (size_t i = 0; i < sum.pixels.size(); ++i) sum.pixels[i] += c.pixels[i];
  }
  for (float& x : sum.pixels) x /= float(p.samples);
  return sum;
}

Image thin_lens_approximation(const Tracer& tracer, const Scene& scene, const Camera& camera, const ThinLensParams& p,
                              const BlurParams& blur) {
  check(p);
  const GBuffer g = trace_primary(tracer, scene, camera, p.width, p.height);
  const Image color = shade_constant_ambient(scene, camera, g, p.ambient, surface_epsilon(scene.bounds()));
  const double ppd = camera_pixels_per_degree(camera, p.height);
  const double a = p.pupil_diameter_mm * 1e-3;
  const glm::vec3 forward = glm::normalize(camera.look - camera.eye);
  std::vector<float> coc(size_t(p.width) * p.height);
  for (size_t i = 0; i < coc.size(); ++i) {
    // The thin lens focuses planes: the distance that counts is along the optical axis
    const double axial_m = g.hit(i) ? g.depth[i] * glm::dot(g.view[i], forward) * scene.meters_per_unit : INFINITY;
    const double object_vergence = axial_m > 0 && std::isfinite(axial_m) ? 1.0 / axial_m : 0.0;
    coc[i] = static_cast<float>(glm::degrees(a * std::abs(object_vergence - p.focus_vergence)) * ppd);
  }
  return variable_blur(color, coc, blur);
}

}  // namespace foveal
