// foveal/impair/impairments.h — what an impaired eye does to the image after its optics: the ocular
// media (forward scatter and lens yellowing), the retina (visual-field loss, metamorphopsia) and
// colour vision — in that order, on linear RGB, with the field centred on the fixation.
#pragma once

#include "foveal/impair/cvd.h"
#include "foveal/impair/field.h"
#include "foveal/util/hd.h"
#include "foveal/util/image.h"

#include <glm/glm.hpp>

#include <memory>
#include <string>
#include <vector>

namespace foveal {

// Forward light scatter: the CIE 2002 general disability glare equation (CIE 146:2002; Vos & van
// den Berg 1999), the equivalent veiling luminance per glare illuminance, sr⁻¹, θ in degrees
// (valid 0.1°–100°), age A in years, pigmentation p (0 very dark eyes, 0.5 brown, 1 blue-green):
//   L/E = 10/θ³ + (5/θ² + 0.1·p/θ)·(1 + (A/62.5)⁴) + 0.0025·p
// A cataract multiplies the age-dependent (lens) term by `straylight` (1 = age-normal).
double cie_glare_psf(double theta_deg, double age_years, double pigmentation, double straylight = 1.0);
// Its integral over the solid angle between θ1 and θ2 (small-angle: dΩ = 2π θ dθ): the fraction of
// the light scattered there.
double cie_glare_fraction(double theta1_deg, double theta2_deg, double age_years, double pigmentation, double straylight = 1.0);
inline constexpr double kGlareMinDeg = 0.1;

struct MediaParams {
  double cataract = 0;        // severity 0–1: the lens's straylight × 10^severity (up to 1 log unit above age-normal)
  double age_years = 25;      // the CIE equation's age and the lens's yellowing
  double pigmentation = 0.5;  // the CIE equation's p
  bool glare = false;         // forward scatter (on with a cataract, or asked for)
  bool yellowing = false;     // lens transmittance (on with a cataract, or asked for)
  bool any() const { return glare || yellowing; }
};
// The straylight multiplier of a cataract severity.
double cataract_straylight_factor(double severity);
// Lens transmittance for linear R, G, B relative to a 25-year-old lens: the age dependence of
// Pokorny, Smith & Lutze 1987 (the age-dependent density D1 × [1 + 0.02(A − 32)] to 60 years,
// × [1.56 + 0.0667(A − 60)] beyond), D1 at the sRGB primaries' dominant wavelengths (about 610,
// 545 and 465 nm) taken as 0.02, 0.05 and 0.25; a brunescent cataract of severity s adds the density
// of 20·s more years.
glm::dvec3 lens_transmittance(const MediaParams& media);

// The scatter kernel on a pixel grid of `ppd` pixels per degree, (2·rx+1) × (2·ry+1): each pixel the
// CIE equation times its solid angle, the centre the integral from 0.1° to the pixel's own radius.
// The cataract's straylight factor multiplies the equation's lens term; the sum is the scattered fraction η.
std::vector<float> glare_kernel(double ppd, int rx, int ry, const MediaParams& media);
// The glare's coarse grid: the image divided by the smallest whole factor that leaves at most 160
// columns (the last cell may be partial).
struct GlareGrid {
  int factor = 1, columns = 0, rows = 0;
};
GlareGrid glare_grid(int width, int height);
// Its kernel over every pair of the grid's cells ((2·columns − 1) × (2·rows − 1), glare_kernel at the
// grid's own pixels per degree), scaled down where η would pass 0.95 (the straylight saturates); η
// is returned through `eta`.
std::vector<float> glare_grid_kernel(const GlareGrid& grid, double grid_ppd, const MediaParams& media, double* eta);
// out = (1 − η)·I + K ⊛ I (light scattered beyond the image is lost). Computed on a grid of at most
// 160 columns, the scattered part upsampled (the kernel's spectrum cached for the next frame).
void apply_glare(Image& image, double ppd, const MediaParams& media);
struct GlareSpectrum;  // the kernel's spectrum, kept while the grid and the media stay the same
void apply_glare(Image& image, double ppd, const MediaParams& media, std::shared_ptr<GlareSpectrum>* cache);

// How a field loss is shown. `contrast` (default): each band of a Laplacian pyramid (Burt &
// Adelson 1983) is scaled by the local sensitivity 10^(−L/10), Peli's local band-limited contrast
// (Peli 1990) reduced by L dB at unchanged local mean luminance. `blur`: every 6 dB removes the
// finest remaining octave. `grey`: the image fades into its mean colour. `fill`: the surround fills
// in (push-pull interpolation from where sensitivity remains).
enum class FieldMode { contrast, blur, grey, fill };
FieldMode parse_field_mode(const std::string& name);
const char* to_string(FieldMode mode);
// The Laplacian pyramid's levels below the image (halving while the smaller side is ≥ 16, at most 8).
int field_pyramid_levels(int width, int height);
// `loss_db` per pixel (width × height).
void apply_field_loss(Image& image, const std::vector<float>& loss_db, FieldMode mode);

// Metamorphopsia's distortion as both devices evaluate it: Gaussian bumps in the disc, each
// pushing in its own direction, windowed to zero beyond the radius + 1°.
struct MetamorphopsiaBumps {
  static constexpr int kCount = 12;
  double cx[kCount], cy[kCount];  // centres, degrees
  double ux[kCount], uy[kCount];  // unit directions
  double sigma = 1, radius = 0, half_amplitude = 0;
};
FOVEAL_HD inline glm::dvec2 metamorphopsia_displacement(const MetamorphopsiaBumps& b, double x, double y) {
  if (b.half_amplitude == 0) return {0, 0};
  const double r = sqrt(x * x + y * y);
  if (r > b.radius + 1) return {0, 0};
  glm::dvec2 d(0);
  for (int k = 0; k < MetamorphopsiaBumps::kCount; ++k) {
    const double e = exp(-((x - b.cx[k]) * (x - b.cx[k]) + (y - b.cy[k]) * (y - b.cy[k])) / (2 * b.sigma * b.sigma));
    d += e * glm::dvec2(b.ux[k], b.uy[k]);
  }
  const double window = 1.0 - std::clamp((r - b.radius + 1) / 2.0, 0.0, 1.0);
  return d * (b.half_amplitude * window);
}

// Metamorphopsia: a smooth retinotopic distortion within `radius_deg` of the fovea, displacements
// up to about `amplitude_deg`, the same for a seed.
struct Metamorphopsia {
  double amplitude_deg = 0;
  double radius_deg = 6;
  uint64_t seed = 1;
  bool any() const { return amplitude_deg > 0; }
  // The displacement (degrees, field coordinates: x right, y up) at a field location (draws the
  // bumps each call: a pass over many locations takes bumps() once).
  glm::dvec2 displacement(double x_deg, double y_deg) const { return metamorphopsia_displacement(bumps(), x_deg, y_deg); }
  MetamorphopsiaBumps bumps() const;  // the seed's bumps
};

struct Impairments {
  MediaParams media;
  VisualField field;
  FieldMode field_mode = FieldMode::contrast;
  Metamorphopsia metamorphopsia;
  CvdParams cvd;
  bool any() const { return media.any() || !field.empty() || metamorphopsia.any() || cvd.type != CvdType::none; }
  std::string describe() const;  // one line, for logs and stats
};

// Where each pixel lies in the visual field of the current fixation: degrees, x right, y up.
struct Retinotopy {
  int width = 0, height = 0;
  std::vector<glm::vec2> field_deg;  // width × height
  double ppd = 1;                    // pixels per degree at the fixation
};

// A retinotopy computed exactly on every `step`-th pixel ((width + step − 1)/step + 1 columns, as
// many rows likewise) and bilinear between: where each pixel lies, as both devices expand it.
struct RetinotopyGrid {
  static constexpr int kStep = 4;
  int width = 0, height = 0;
  int columns = 0, rows = 0;
  std::vector<glm::vec2> field_deg;  // columns × rows, empty where the retina is unimpaired
  double ppd = 1;
};
FOVEAL_HD inline glm::vec2 retinotopy_between(const glm::vec2* grid, int columns, int x, int y) {
  constexpr int step = RetinotopyGrid::kStep;
  const int i = x / step, j = y / step;
  const float tx = float(x - i * step) / step, ty = float(y - j * step) / step;
  const glm::vec2 a = grid[size_t(j) * columns + i], b = grid[size_t(j) * columns + i + 1];
  const glm::vec2 c = grid[size_t(j + 1) * columns + i], d = grid[size_t(j + 1) * columns + i + 1];
  return (1 - ty) * ((1 - tx) * a + tx * b) + ty * ((1 - tx) * c + tx * d);
}
// Every pixel's place (Retinotopy) from the grid.
Retinotopy expand(const RetinotopyGrid& grid);

// The render fills a display seen from its centre (perception/foveation.h): the exact angle from the
// gaze, split as the foveation model splits it, y turned upwards; ppd at the display centre.
struct Display;
Retinotopy display_retinotopy(const Display& display, int width, int height, glm::dvec2 gaze_px);

struct ImpairTimes {
  double media_ms = 0, field_ms = 0, colour_ms = 0, total_ms = 0;
};

// The impairments of one eye, prepared once (the field's loss map) and applied to each frame.
class ImpairmentPasses {
 public:
  explicit ImpairmentPasses(const Impairments& impairments);
  const Impairments& impairments() const { return impairments_; }
  const FieldMap& field_map() const { return map_; }
  // Unique to each constructed set of passes (a copy keeps it: the same impairments): what a device
  // that keeps a copy of the field's map knows it by.
  uint64_t id() const { return id_; }
  bool needs_retinotopy() const { return !map_.empty() || impairments_.metamorphopsia.any(); }
  // Media, then retina (metamorphopsia, field loss), then colour, in place on linear RGB. The
  // retinotopy's field_deg may be empty when the retina is unimpaired (needs_retinotopy()).
  ImpairTimes apply(Image& image, const Retinotopy& retinotopy) const;
  // The per-pixel loss (dB) of the field at this fixation.
  std::vector<float> loss_db(const Retinotopy& retinotopy) const;

 private:
  Impairments impairments_;
  FieldMap map_;
  uint64_t id_;
  mutable std::shared_ptr<GlareSpectrum> glare_cache_;  // apply() is not for concurrent use
};

// An Amsler grid (20 × 20 squares of 1°, a central dot; white on black) as the eye sees it while
// fixating its centre: `ppd` pixels per degree.
Image amsler_grid(const ImpairmentPasses& passes, double ppd);

}  // namespace foveal
