// foveal/impair/cvd.cpp — Machado et al. 2009, Brettel et al. 1997, achromatopsia.
#include "foveal/impair/cvd.h"

#include "foveal/util/error.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <cmath>

namespace foveal {

namespace {

using Row9 = std::array<double, 9>;  // a 3×3 matrix, row-major

// Machado, Oliveira & Fernandes 2009, the published simulation matrices for linear RGB, severity
// 0.0, 0.1, …, 1.0 (rows of the matrix one after another).
constexpr std::array<Row9, 11> kProtan = {{
    {1.000000, 0.000000, -0.000000, 0.000000, 1.000000, 0.000000, -0.000000, -0.000000, 1.000000},
    {0.856167, 0.182038, -0.038205, 0.029342, 0.955115, 0.015544, -0.002880, -0.001563, 1.004443},
    {0.734766, 0.334872, -0.069637, 0.051840, 0.919198, 0.028963, -0.004928, -0.004209, 1.009137},
    {0.630323, 0.465641, -0.095964, 0.069181, 0.890046, 0.040773, -0.006308, -0.007724, 1.014032},
    {0.539009, 0.579343, -0.118352, 0.082546, 0.866121, 0.051332, -0.007136, -0.011959, 1.019095},
    {0.458064, 0.679578, -0.137642, 0.092785, 0.846313, 0.060902, -0.007494, -0.016807, 1.024301},
    {0.385450, 0.769005, -0.154455, 0.100526, 0.829802, 0.069673, -0.007442, -0.022190, 1.029632},
    {0.319627, 0.849633, -0.169261, 0.106241, 0.815969, 0.077790, -0.007025, -0.028051, 1.035076},
    {0.259411, 0.923008, -0.182420, 0.110296, 0.804340, 0.085364, -0.006276, -0.034346, 1.040622},
    {0.203876, 0.990338, -0.194214, 0.112975, 0.794542, 0.092483, -0.005222, -0.041043, 1.046265},
    {0.152286, 1.052583, -0.204868, 0.114503, 0.786281, 0.099216, -0.003882, -0.048116, 1.051998},
}};
constexpr std::array<Row9, 11> kDeutan = {{
    {1.000000, 0.000000, -0.000000, 0.000000, 1.000000, 0.000000, -0.000000, -0.000000, 1.000000},
    {0.866435, 0.177704, -0.044139, 0.049567, 0.939063, 0.011370, -0.003453, 0.007233, 0.996220},
    {0.760729, 0.319078, -0.079807, 0.090568, 0.889315, 0.020117, -0.006027, 0.013325, 0.992702},
    {0.675425, 0.433850, -0.109275, 0.125303, 0.847755, 0.026942, -0.007950, 0.018572, 0.989378},
    {0.605511, 0.528560, -0.134071, 0.155318, 0.812366, 0.032316, -0.009376, 0.023176, 0.986200},
    {0.547494, 0.607765, -0.155259, 0.181692, 0.781742, 0.036566, -0.010410, 0.027275, 0.983136},
    {0.498864, 0.674741, -0.173604, 0.205199, 0.754872, 0.039929, -0.011131, 0.030969, 0.980162},
    {0.457771, 0.731899, -0.189670, 0.226409, 0.731012, 0.042579, -0.011595, 0.034333, 0.977261},
    {0.422823, 0.781057, -0.203881, 0.245752, 0.709602, 0.044646, -0.011843, 0.037423, 0.974421},
    {0.392952, 0.823610, -0.216562, 0.263559, 0.690210, 0.046232, -0.011910, 0.040281, 0.971630},
    {0.367322, 0.860646, -0.227968, 0.280085, 0.672501, 0.047413, -0.011820, 0.042940, 0.968881},
}};
constexpr std::array<Row9, 11> kTritan = {{
    {1.000000, 0.000000, -0.000000, 0.000000, 1.000000, 0.000000, -0.000000, -0.000000, 1.000000},
    {0.926670, 0.092514, -0.019184, 0.021191, 0.964503, 0.014306, 0.008437, 0.054813, 0.936750},
    {0.895720, 0.133330, -0.029050, 0.029997, 0.945400, 0.024603, 0.013027, 0.104707, 0.882266},
    {0.905871, 0.127791, -0.033662, 0.026856, 0.941251, 0.031893, 0.013410, 0.148296, 0.838294},
    {0.948035, 0.089490, -0.037526, 0.014364, 0.946792, 0.038844, 0.010853, 0.193991, 0.795156},
    {1.017277, 0.027029, -0.044306, -0.006113, 0.958479, 0.047634, 0.006379, 0.248708, 0.744913},
    {1.104996, -0.046633, -0.058363, -0.032137, 0.971635, 0.060503, 0.001336, 0.317922, 0.680742},
    {1.193214, -0.109812, -0.083402, -0.058496, 0.979410, 0.079086, -0.002346, 0.403492, 0.598854},
    {1.257728, -0.139648, -0.118081, -0.078003, 0.975409, 0.102594, -0.003316, 0.501214, 0.502102},
    {1.278864, -0.125333, -0.153531, -0.084748, 0.957674, 0.127074, -0.000989, 0.601151, 0.399838},
    {1.255528, -0.076749, -0.178779, -0.078411, 0.930809, 0.147602, 0.004733, 0.691367, 0.303900},
}};

glm::dmat3 from_rows(const Row9& m) {
  // glm is column-major: element [column][row]
  return glm::transpose(glm::dmat3(m[0], m[1], m[2], m[3], m[4], m[5], m[6], m[7], m[8]));
}

// Smith & Pokorny cone fundamentals for the sRGB primaries (linear RGB → LMS)
const glm::dmat3 kLmsFromRgb =
    from_rows({0.17885956, 0.43997117, 0.03596577, 0.03380394, 0.27515242, 0.03620635, 0.00031087, 0.00191661, 0.01528089});
const glm::dmat3 kRgbFromLms = glm::inverse(kLmsFromRgb);
// IEC 61966-2-1: linear sRGB → CIE XYZ (D65)
const glm::dmat3 kXyzFromRgb =
    from_rows({0.4124564, 0.3575761, 0.1804375, 0.2126729, 0.7151522, 0.0721750, 0.0193339, 0.1191920, 0.9503041});

// LMS of a monochromatic light from its CIE 1931 chromaticity (Y = 1)
glm::dvec3 spectral_lms(double x, double y) {
  const glm::dvec3 xyz(x / y, 1.0, (1.0 - x - y) / y);
  return kLmsFromRgb * (glm::inverse(kXyzFromRgb) * xyz);
}

// Brettel et al. 1997: the two half-planes of one dichromacy, each the plane through the origin,
// the neutral stimulus E and an anchor, as its normal (CvdTransform's half_planes).
CvdTransform make_dichromat(int missing, glm::dvec3 anchor_below, glm::dvec3 anchor_above) {
  const glm::dvec3 e = rgb_to_lms(glm::dvec3(1.0));  // the display's white
  CvdTransform d;
  d.kind = CvdTransform::half_planes;
  d.lms_from_rgb = kLmsFromRgb;
  d.rgb_from_lms = kRgbFromLms;
  d.missing = missing;
  d.normal_below = glm::cross(e, anchor_below);
  d.normal_above = glm::cross(e, anchor_above);
  // protan (L missing) and deutan (M missing) choose by S/M resp. S/L; tritan by M/L
  if (missing == 0) d.num = 2, d.den = 1;
  if (missing == 1) d.num = 2, d.den = 0;
  if (missing == 2) d.num = 1, d.den = 0;
  d.neutral_ratio = e[d.num] / e[d.den];
  return d;
}

const CvdTransform& dichromat(CvdType type) {
  // CIE 1931 chromaticities of the anchors: 475 nm (0.1096, 0.0868), 575 nm (0.4788, 0.5202),
  // 485 nm (0.0687, 0.2007), 660 nm (0.7300, 0.2700)
  static const CvdTransform protan = make_dichromat(0, spectral_lms(0.4788, 0.5202), spectral_lms(0.1096, 0.0868));
  static const CvdTransform deutan = make_dichromat(1, spectral_lms(0.4788, 0.5202), spectral_lms(0.1096, 0.0868));
  static const CvdTransform tritan = make_dichromat(2, spectral_lms(0.7300, 0.2700), spectral_lms(0.0687, 0.2007));
  return type == CvdType::protanopia ? protan : type == CvdType::deuteranopia ? deutan : tritan;
}

}  // namespace

const char* to_string(CvdType type) {
  switch (type) {
    case CvdType::none:
      return "none";
    case CvdType::protan:
      return "protan";
    case CvdType::deutan:
      return "deutan";
    case CvdType::tritan:
      return "tritan";
    case CvdType::protanopia:
      return "protanopia";
    case CvdType::deuteranopia:
      return "deuteranopia";
    case CvdType::tritanopia:
      return "tritanopia";
    case CvdType::achromatopsia:
      return "achromatopsia";
  }
  return "?";
}

CvdType parse_cvd_type(const std::string& name) {
  for (CvdType t : {CvdType::protan, CvdType::deutan, CvdType::tritan, CvdType::protanopia, CvdType::deuteranopia, CvdType::tritanopia,
                    CvdType::achromatopsia})
    if (name == to_string(t)) return t;
  fail("unknown colour-vision deficiency '{}' (expected protan, deutan, tritan, protanopia, deuteranopia, tritanopia, achromatopsia)",
       name);
}

glm::dmat3 machado_table(CvdType type, int step) {
  if (step < 0 || step > 10) fail("Machado table: severity step {} outside 0–10", step);
  switch (type) {
    case CvdType::protan:
      return from_rows(kProtan[step]);
    case CvdType::deutan:
      return from_rows(kDeutan[step]);
    case CvdType::tritan:
      return from_rows(kTritan[step]);
    default:
      fail("Machado et al. 2009 tabulate protan, deutan and tritan only, not {}", to_string(type));
  }
}

glm::dmat3 machado_matrix(CvdType type, double severity) {
  if (!(severity >= 0 && severity <= 1)) fail("colour-vision deficiency severity must be in [0, 1], got {}", severity);
  const double s = severity * 10.0;
  const int lo = std::min(9, static_cast<int>(std::floor(s)));
  const double t = s - lo;
  if (t < 1e-9) return machado_table(type, lo);
  if (t > 1 - 1e-9) return machado_table(type, lo + 1);
  return machado_table(type, lo) * (1.0 - t) + machado_table(type, lo + 1) * t;
}

glm::dvec3 rgb_to_lms(glm::dvec3 rgb) { return kLmsFromRgb * rgb; }
glm::dvec3 lms_to_rgb(glm::dvec3 lms) { return kRgbFromLms * lms; }

CvdTransform cvd_transform(const CvdParams& p) {
  CvdTransform t;
  switch (p.type) {
    case CvdType::none:
      break;
    case CvdType::protan:
    case CvdType::deutan:
    case CvdType::tritan:
      t.kind = CvdTransform::matrix;
      t.rgb_matrix = machado_matrix(p.type, p.severity);
      break;
    case CvdType::achromatopsia:  // every channel the relative luminance Y
      t.kind = CvdTransform::matrix;
      t.rgb_matrix = glm::dmat3(glm::dvec3(0.2126729), glm::dvec3(0.7151522), glm::dvec3(0.0721750));
      break;
    case CvdType::protanopia:
    case CvdType::deuteranopia:
    case CvdType::tritanopia:
      t = dichromat(p.type);
      break;
  }
  return t;
}

glm::dvec3 simulate_cvd(const CvdParams& p, glm::dvec3 rgb) { return cvd_apply(cvd_transform(p), rgb); }

void apply_cvd(const CvdParams& p, Image& image) {
  if (p.type == CvdType::none) return;
  if (image.channels != 3) fail("colour-vision deficiency needs a 3-channel image, got {} channels", image.channels);
  const size_t n = size_t(image.width) * image.height;
  const CvdTransform t = cvd_transform(p);
  tbb::parallel_for(tbb::blocked_range<size_t>(0, n, 8192), [&](const tbb::blocked_range<size_t>& r) {
    for (size_t i = r.begin(); i < r.end(); ++i) {
      float* px = &image.pixels[i * 3];
      const glm::dvec3 out = cvd_apply(t, glm::dvec3(px[0], px[1], px[2]));
      for (int c = 0; c < 3; ++c) px[c] = static_cast<float>(std::max(0.0, out[c]));
    }
  });
}

}  // namespace foveal
