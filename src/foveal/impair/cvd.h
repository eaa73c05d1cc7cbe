// foveal/impair/cvd.h — colour-vision deficiency on linear RGB.
//
// Anomalous trichromacy (protan, deutan, tritan at severity 0–1): Machado, Oliveira & Fernandes,
// "A physiologically-based model for simulation of color vision deficiency", IEEE TVCG 15(6),
// 2009 — the paper's published matrices for severities 0, 0.1, …, 1 (linear RGB), interpolated
// linearly in between. Dichromacy (protanopia, deuteranopia, tritanopia): Brettel, Viénot &
// Mollon, "Computerized simulation of color appearance for dichromats", JOSA A 14(10), 1997 — in
// LMS space, the missing cone's signal is replaced so that each colour falls on one of two
// half-planes spanned by the neutral axis and a monochromatic anchor (475/575 nm for protan and
// deutan, 485/660 nm for tritan). Achromatopsia (rod monochromacy): the relative luminance Y.
#pragma once

#include "foveal/util/hd.h"
#include "foveal/util/image.h"

#include <glm/glm.hpp>

#include <string>

namespace foveal {

enum class CvdType { none, protan, deutan, tritan, protanopia, deuteranopia, tritanopia, achromatopsia };

struct CvdParams {
  CvdType type = CvdType::none;
  double severity = 1.0;  // anomalous trichromacy only, in [0, 1]
};

const char* to_string(CvdType type);
// "protan", "deutan", "tritan", "protanopia", "deuteranopia", "tritanopia", "achromatopsia"; throws Error.
CvdType parse_cvd_type(const std::string& name);

// Machado et al. 2009, table entry `step` (0–10: severity step/10) of `type` (protan, deutan or tritan).
glm::dmat3 machado_table(CvdType type, int step);
// The matrix for any severity in [0, 1]: the table's, or linear between its two neighbours.
glm::dmat3 machado_matrix(CvdType type, double severity);

// One linear-RGB colour as the deficient observer sees it (not clamped).
glm::dvec3 simulate_cvd(const CvdParams& params, glm::dvec3 linear_rgb);
// Linear RGB ↔ LMS (Smith & Pokorny cone fundamentals with the sRGB primaries).
glm::dvec3 rgb_to_lms(glm::dvec3 rgb);
glm::dvec3 lms_to_rgb(glm::dvec3 lms);

// One observer's transform of linear RGB, prepared once (cvd_transform) and applied to each pixel
// by either device (cvd_apply): a matrix (Machado's, or achromatopsia's luminance row) or
// Brettel's two half-planes in LMS.
struct CvdTransform {
  enum Kind { none, matrix, half_planes } kind = none;
  glm::dmat3 rgb_matrix{1.0};                       // matrix
  glm::dmat3 lms_from_rgb{1.0}, rgb_from_lms{1.0};  // half_planes
  int missing = 0, num = 0, den = 0;                // the missing cone; the ratio LMS[num]/LMS[den] that chooses the plane
  glm::dvec3 normal_below{0.0}, normal_above{0.0};  // the planes' normals (below / above the neutral ratio)
  double neutral_ratio = 0;
};
// Throws Error for a severity outside [0, 1] (anomalous trichromacy).
CvdTransform cvd_transform(const CvdParams& params);
FOVEAL_HD inline glm::dvec3 cvd_apply(const CvdTransform& t, glm::dvec3 rgb) {
  if (t.kind == CvdTransform::matrix) return t.rgb_matrix * rgb;
  if (t.kind != CvdTransform::half_planes) return rgb;
  glm::dvec3 lms = t.lms_from_rgb * rgb;
  const bool below = lms[t.den] > 0 ? lms[t.num] / lms[t.den] < t.neutral_ratio : false;
  const glm::dvec3 n = below ? t.normal_below : t.normal_above;
  // the point of the half-plane with the same two remaining cone signals: n · lms' = 0
  const int a = (t.missing + 1) % 3, b = (t.missing + 2) % 3;
  lms[t.missing] = -(n[a] * lms[a] + n[b] * lms[b]) / n[t.missing];
  return t.rgb_from_lms * lms;
}

// The whole image in place (3 channels, linear); values clamped to ≥ 0.
void apply_cvd(const CvdParams& params, Image& image);

}  // namespace foveal
