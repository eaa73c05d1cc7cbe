// foveal/impair/field.h — visual fields: perimetry results, standard grids, generated defects, and
// the continuous loss map the renderer reads.
//
// Coordinates are degrees of visual angle from the fixation as the patient sees the world: x to the
// right, y up (perimetry charts). In the right eye (OD) the physiological blind spot lies about 15°
// temporally (x > 0) and 1.5° below the horizontal meridian; in the left eye (OS) at x < 0.
// Loss is in dB of contrast sensitivity (≥ 0; 0 = an age-normal location).
#pragma once

#include "foveal/util/hd.h"

#include <glm/glm.hpp>

#include <algorithm>
#include <cmath>
#include <functional>
#include <optional>
#include <string>
#include <vector>

namespace foveal {

enum class Eye { od, os };
const char* to_string(Eye eye);
std::optional<Eye> parse_eye_side(std::string_view text);  // "OD", "OS" (any case)

// What a field file's value column holds.
enum class FieldValue { sensitivity_db, total_deviation_db, pattern_deviation_db };
const char* to_string(FieldValue kind);

struct FieldPoint {
  double x_deg = 0, y_deg = 0;
  double value_db = 0;  // as read (sensitivity or deviation)
  double loss_db = 0;   // ≥ 0
};

// One eye's test results.
struct PerimetryField {
  Eye eye = Eye::od;
  FieldValue kind = FieldValue::total_deviation_db;
  std::vector<FieldPoint> points;
};

// The age-normal sensitivity (dB) at an eccentricity, used to turn sensitivities into losses:
// Calixto, Santos & Cronemberger 2006 (Arq Bras Oftalmol 69(5), normal subjects aged 20 or more):
// mean sensitivity 28.7 − 0.050·age dB over the central 26°, falling by 0.30 dB per degree of
// eccentricity; foveal::kNormalMeanEccentricityDeg places the mean. Perimeters differ in their dB
// scale: where the perimeter reports total deviation, use it instead.
struct NormalModel {
  double intercept_db = 28.7;
  double age_db_per_year = -0.050;
  double eccentricity_db_per_deg = -0.30;
  double mean_eccentricity_deg = 13.0;  // the mean eccentricity of the central 26° field
  double sensitivity_db(double age_years, double eccentricity_deg) const {
    return intercept_db + age_db_per_year * age_years + eccentricity_db_per_deg * (eccentricity_deg - mean_eccentricity_deg);
  }
};

// The standard grids' locations in reading order (top row first, left to right) for one eye: 24-2
// (54 locations), 30-2 (76) and 10-2 (68). Throws Error for another name.
std::vector<glm::dvec2> standard_grid(const std::string& name, Eye eye);
// The grid's blind-spot test locations (15°, ±3° temporal for 24-2 and 30-2; none for 10-2).
bool is_blind_spot_location(const std::string& grid, Eye eye, glm::dvec2 location);

// Read a field file (CSV, BOM and CRLF accepted): with columns x_deg,y_deg and one value column
// (sensitivity_db, total_deviation_db or pattern_deviation_db), or — when `grid` names a standard
// grid — the value column alone in the grid's reading order; an optional `eye` column (OD/OS) holds
// both eyes in one file (without it the values are `default_eye`'s). Errors name file:line.
std::vector<PerimetryField> read_field_file(const std::string& path, const std::string& grid = {}, Eye default_eye = Eye::od,
                                            double age_years = 50, const NormalModel& normal = {});
std::vector<PerimetryField> parse_field_csv(const std::string& text, const std::string& name, const std::string& grid = {},
                                            Eye default_eye = Eye::od, double age_years = 50, const NormalModel& normal = {});

// The physiological blind spot: centre 15.5° temporal, 1.5° below the horizontal meridian, 5.5° wide
// and 7.5° high (Rohrschneider 2004, IOVS 45(9)); an absolute scotoma (kAbsoluteLossDb).
inline constexpr double kBlindSpotXDeg = 15.5, kBlindSpotYDeg = -1.5;
inline constexpr double kBlindSpotWidthDeg = 5.5, kBlindSpotHeightDeg = 7.5;
inline constexpr double kAbsoluteLossDb = 40.0;  // contrast × 10^-4: nothing is seen
glm::dvec2 blind_spot_centre(Eye eye);
// The blind spot's loss at a location (0 outside; a 0.5° soft edge).
double blind_spot_loss_db(Eye eye, glm::dvec2 location);

// A loss map's samples as both devices read them: n × n cells of kStepDeg over ±kExtentDeg, row 0 at
// the top. field_loss_db is FieldMap::loss_db's rule, written once for the CPU and the CUDA backend.
struct FieldMapView {
  const float* loss = nullptr;
  int n = 0;
  bool empty = true;
};
FOVEAL_HD inline double field_loss_db(const FieldMapView& m, double x, double y, double extent_deg, double step_deg) {
  if (m.empty || !std::isfinite(x) || !std::isfinite(y)) return 0.0;
  const int n = m.n, half = n / 2;
  // rows of the query's hemifield only: the upper half is rows [0, half), the lower [half, n)
  const bool upper = y >= 0;
  const int row_lo = upper ? 0 : half, row_hi = upper ? half - 1 : n - 1;
  const double fx = std::clamp((x + extent_deg) / step_deg - 0.5, 0.0, n - 1.0);
  const double fy = std::clamp((extent_deg - y) / step_deg - 0.5, double(row_lo), double(row_hi));
  const int x0 = std::min(static_cast<int>(fx), n - 2), y0 = std::min(static_cast<int>(fy), std::max(row_lo, row_hi - 1));
  const int y1 = std::min(y0 + 1, row_hi);
  const double tx = fx - x0, ty = y1 > y0 ? fy - y0 : 0.0;
  auto at = [&](int i, int j) { return double(m.loss[size_t(j) * n + i]); };
  return (1 - ty) * ((1 - tx) * at(x0, y0) + tx * at(x0 + 1, y0)) + ty * ((1 - tx) * at(x0, y1) + tx * at(x0 + 1, y1));
}

// A continuous loss map, sampled every `step` degrees over ±extent; a lookup never mixes the upper
// and lower hemifields (the rows' boundary is the horizontal meridian), and holds the edge value
// beyond the extent.
class FieldMap {
 public:
  static constexpr double kExtentDeg = 90.0, kStepDeg = 0.25;
  FieldMap();  // no loss anywhere
  // Sample loss(x, y) at the cell centres.
  static FieldMap from_function(const std::function<double(double, double)>& loss_db);
  double loss_db(double x_deg, double y_deg) const { return field_loss_db(view(), x_deg, y_deg, kExtentDeg, kStepDeg); }
  FieldMapView view() const { return {loss_.data(), n_, max_loss_ == 0}; }
  // Per cell: the smaller loss of the two (the better eye; Crabb & Viswanathan 1998).
  static FieldMap best_of(const FieldMap& a, const FieldMap& b);
  bool empty() const { return max_loss_ == 0; }
  double max_loss_db() const { return max_loss_; }
  int cells() const { return n_; }

 private:
  int n_;
  std::vector<float> loss_;  // n_ × n_, row 0 at the top (y = +extent)
  double max_loss_ = 0;
};

// Interpolates one eye's losses, separately above and below the horizontal meridian: inverse-
// distance weighting (Shepard 1968, power 2) of the test locations of the same hemifield, each
// weight tapered by a Gaussian of σ = 6° (the 24-2's spacing) so that the map is local and
// continuous; exact at the locations, the nearest ones' values beyond the grid. Locations inside
// the blind spot are left out (the blind spot is added by the map, not interpolated).
double interpolate_loss_db(const PerimetryField& field, double x_deg, double y_deg);

// Integrated visual field (Crabb & Viswanathan 1998): at each location tested in both eyes the
// better (smaller) loss; locations tested in one eye only keep its value.
PerimetryField integrated_field(const PerimetryField& od, const PerimetryField& os);

// Defects generated for users without data (depth in dB; for the eye given, mirrored for OS):
//   arcuate[:DB[:superior|inferior]]        Bjerrum arc 10–20° from fixation, from the blind spot to the nasal meridian
//   nasal-step[:DB[:superior|inferior]]     nasal field beyond 15°, one hemifield
//   paracentral[:DB[:superior|inferior]]    a 3°-radius spot 5° nasal and 5° up (or down)
//   constriction:R[:DB]                     everything beyond R° (advanced glaucoma, retinitis pigmentosa)
//   central:R[:DB]                          everything within R° (macular degeneration)
//   altitudinal[:DB[:superior|inferior]]    a whole hemifield
//   hemianopia:left|right[:DB]              homonymous: the same half in both eyes
//   quadrantanopia:upper-left|upper-right|lower-left|lower-right[:DB]
// Default depth: 25 dB. Throws Error naming the spec.
std::function<double(double, double)> generated_defect(const std::string& spec, Eye eye);

// An eye's or both eyes' fields as the renderer sees them.
struct VisualField {
  std::vector<PerimetryField> measured;  // from files
  struct Generated {
    std::string spec;        // e.g. "arcuate:20"
    std::optional<Eye> eye;  // nullopt: both eyes
  };
  std::vector<Generated> generated;
  std::string view = "auto";  // "OD", "OS", "both"; auto = both when two eyes are measured, else the one
  bool blind_spot = true;     // monocular views show the eye's blind spot
  bool empty() const { return measured.empty() && generated.empty(); }
  // The loss map of the view (monocular: the eye's field and blind spot; both: the better eye).
  FieldMap map() const;
  // "OD", "OS" or "both": `view`, with auto resolved.
  std::string resolved_view() const;
  // The test locations of the view: one eye's, or the integrated field of both.
  std::vector<FieldPoint> view_points() const;
};

}  // namespace foveal
