// Tests of the impairments against the published models they implement.
#include "foveal/impair/cvd.h"
#include "foveal/impair/field.h"
#include "foveal/impair/impairments.h"
#include "foveal/impair/profile.h"
#include "foveal/perception/foveation.h"
#include "foveal/util/error.h"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <numbers>
#include <sstream>

namespace foveal {
namespace {

// Machado, Oliveira & Fernandes 2009, the paper's matrices (typed here from the publication as the
// oracle, apart from the implementation's table): for each type, severity 0.1 … 1.0, 9 numbers each.
const char* kMachadoPublished[3] = {
    // protanomaly
    "0.856167 0.182038 -0.038205 0.029342 0.955115 0.015544 -0.002880 -0.001563 1.004443 "
    "0.734766 0.334872 -0.069637 0.051840 0.919198 0.028963 -0.004928 -0.004209 1.009137 "
    "0.630323 0.465641 -0.095964 0.069181 0.890046 0.040773 -0.006308 -0.007724 1.014032 "
    "0.539009 0.579343 -0.118352 0.082546 0.866121 0.051332 -0.007136 -0.011959 1.019095 "
    "0.458064 0.679578 -0.137642 0.092785 0.846313 0.060902 -0.007494 -0.016807 1.024301 "
    "0.385450 0.769005 -0.154455 0.100526 0.829802 0.069673 -0.007442 -0.022190 1.029632 "
    "0.319627 0.849633 -0.169261 0.106241 0.815969 0.077790 -0.007025 -0.028051 1.035076 "
    "0.259411 0.923008 -0.182420 0.110296 0.804340 0.085364 -0.006276 -0.034346 1.040622 "
    "0.203876 0.990338 -0.194214 0.112975 0.794542 0.092483 -0.005222 -0.041043 1.046265 "
    "0.152286 1.052583 -0.204868 0.114503 0.786281 0.099216 -0.003882 -0.048116 1.051998",
    // deuteranomaly
    "0.866435 0.177704 -0.044139 0.049567 0.939063 0.011370 -0.003453 0.007233 0.996220 "
    "0.760729 0.319078 -0.079807 0.090568 0.889315 0.020117 -0.006027 0.013325 0.992702 "
    "0.675425 0.433850 -0.109275 0.125303 0.847755 0.026942 -0.007950 0.018572 0.989378 "
    "0.605511 0.528560 -0.134071 0.155318 0.812366 0.032316 -0.009376 0.023176 0.986200 "
    "0.547494 0.607765 -0.155259 0.181692 0.781742 0.036566 -0.010410 0.027275 0.983136 "
    "0.498864 0.674741 -0.173604 0.205199 0.754872 0.039929 -0.011131 0.030969 0.980162 "
    "0.457771 0.731899 -0.189670 0.226409 0.731012 0.042579 -0.011595 0.034333 0.977261 "
    "0.422823 0.781057 -0.203881 0.245752 0.709602 0.044646 -0.011843 0.037423 0.974421 "
    "0.392952 0.823610 -0.216562 0.263559 0.690210 0.046232 -0.011910 0.040281 0.971630 "
    "0.367322 0.860646 -0.227968 0.280085 0.672501 0.047413 -0.011820 0.042940 0.968881",
    // tritanomaly
    "0.926670 0.092514 -0.019184 0.021191 0.964503 0.014306 0.008437 0.054813 0.936750 "
    "0.895720 0.133330 -0.029050 0.029997 0.945400 0.024603 0.013027 0.104707 0.882266 "
    "0.905871 0.127791 -0.033662 0.026856 0.941251 0.031893 0.013410 0.148296 0.838294 "
    "0.948035 0.089490 -0.037526 0.014364 0.946792 0.038844 0.010853 0.193991 0.795156 "
    "1.017277 0.027029 -0.044306 -0.006113 0.958479 0.047634 0.006379 0.248708 0.744913 "
    "1.104996 -0.046633 -0.058363 -0.032137 0.971635 0.060503 0.001336 0.317922 0.680742 "
    "1.193214 -0.109812 -0.083402 -0.058496 0.979410 0.079086 -0.002346 0.403492 0.598854 "
    "1.257728 -0.139648 -0.118081 -0.078003 0.975409 0.102594 -0.003316 0.501214 0.502102 "
    "1.278864 -0.125333 -0.153531 -0.084748 0.957674 0.127074 -0.000989 0.601151 0.399838 "
    "1.255528 -0.076749 -0.178779 -0.078411 0.930809 0.147602 0.004733 0.691367 0.303900",
};

TEST(Cvd, ImageEqualsMachadosPublishedMatricesAtEveryTabulatedSeverity) {
  // A 4×4 image of assorted linear colours through the whole-image pass
  Image image(4, 4, 3);
  for (size_t i = 0; i < image.pixels.size(); ++i) image.pixels[i] = static_cast<float>(std::fmod(0.137 * i + 0.05, 1.0));
  const CvdType types[3] = {CvdType::protan, CvdType::deutan, CvdType::tritan};
  for (int t = 0; t < 3; ++t) {
    std::istringstream published(kMachadoPublished[t]);
    for (int step = 1; step <= 10; ++step) {
      double m[9];
      for (double& v : m) ASSERT_TRUE(published >> v);
      Image out = image;
      apply_cvd({types[t], step / 10.0}, out);
      for (int p = 0; p < 16; ++p)
        for (int r = 0; r < 3; ++r) {
          const float* c = &image.pixels[p * 3];
          const double expected = std::max(0.0, m[r * 3] * c[0] + m[r * 3 + 1] * c[1] + m[r * 3 + 2] * c[2]);
          EXPECT_NEAR(out.pixels[p * 3 + r], expected, 1e-3) << to_string(types[t]) << " severity " << step / 10.0;
        }
    }
  }
}

TEST(Cvd, BetweenTabulatedSeveritiesTheMatrixIsInterpolatedAndZeroIsIdentity) {
  const glm::dmat3 half = machado_matrix(CvdType::deutan, 0.45);
  const glm::dmat3 expected = 0.5 * (machado_table(CvdType::deutan, 4) + machado_table(CvdType::deutan, 5));
  for (int c = 0; c < 3; ++c)
    for (int r = 0; r < 3; ++r) EXPECT_NEAR(half[c][r], expected[c][r], 1e-12);
  const glm::dvec3 colour(0.2, 0.5, 0.7);
  const glm::dvec3 same = simulate_cvd({CvdType::protan, 0.0}, colour);
  for (int c = 0; c < 3; ++c) EXPECT_NEAR(same[c], colour[c], 1e-12);
  EXPECT_THROW(machado_matrix(CvdType::protan, 1.5), Error);
}

TEST(Cvd, DichromatsSeeEveryColourOfAConfusionLineAsOneColour) {
  // Brettel et al. 1997: colours that differ only in the missing cone's signal look the same
  const std::pair<CvdType, int> cases[] = {{CvdType::protanopia, 0}, {CvdType::deuteranopia, 1}, {CvdType::tritanopia, 2}};
  for (const auto& [type, cone] : cases)
    for (const glm::dvec3 base : {glm::dvec3(0.3, 0.4, 0.2), glm::dvec3(0.6, 0.2, 0.5), glm::dvec3(0.1, 0.5, 0.8)}) {
      const glm::dvec3 lms = rgb_to_lms(base);
      const glm::dvec3 seen = simulate_cvd({type}, base);
      for (double delta : {-0.3, -0.1, 0.15, 0.4}) {
        glm::dvec3 other = lms;
        other[cone] *= 1.0 + delta;  // on the confusion line through `base`
        const glm::dvec3 seen_other = simulate_cvd({type}, lms_to_rgb(other));
        for (int c = 0; c < 3; ++c) EXPECT_NEAR(seen_other[c], seen[c], 1e-9) << to_string(type);
      }
      // and colours off the line (another remaining cone changed) do not collapse
      glm::dvec3 off = lms;
      off[(cone + 1) % 3] *= 1.3;
      EXPECT_GT(glm::length(simulate_cvd({type}, lms_to_rgb(off)) - seen), 1e-3);
    }
  // the neutral axis is seen unchanged
  for (CvdType t : {CvdType::protanopia, CvdType::deuteranopia, CvdType::tritanopia}) {
    const glm::dvec3 grey = simulate_cvd({t}, glm::dvec3(0.4));
    for (int c = 0; c < 3; ++c) EXPECT_NEAR(grey[c], 0.4, 1e-9);
  }
}

TEST(Cvd, AchromatopsiaSeesOnlyLuminance) {
  const glm::dvec3 seen = simulate_cvd({CvdType::achromatopsia}, glm::dvec3(1, 0, 0));
  EXPECT_NEAR(seen.r, 0.2126729, 1e-9);
  EXPECT_EQ(seen.r, seen.g);
  EXPECT_EQ(seen.g, seen.b);
}

TEST(Field, StandardGridsHaveTheirLocationsInReadingOrder) {
  EXPECT_EQ(standard_grid("24-2", Eye::od).size(), 54u);
  EXPECT_EQ(standard_grid("30-2", Eye::od).size(), 76u);
  EXPECT_EQ(standard_grid("10-2", Eye::od).size(), 68u);
  // OS mirrors OD: the nasal step locations at +27°
  const auto os = standard_grid("24-2", Eye::os);
  EXPECT_NE(std::find(os.begin(), os.end(), glm::dvec2(27, 3)), os.end());
  EXPECT_THROW(standard_grid("60-4", Eye::od), Error);
  const std::string coords = std::string(FOVEAL_DATA_DIR) + "/fields/Coord_242.csv";
  if (!std::filesystem::exists(coords)) GTEST_SKIP() << "skipped: " << coords << " absent";
  std::ifstream in(coords);
  std::string line;
  std::getline(in, line);
  const auto grid = standard_grid("24-2", Eye::od);
  size_t i = 0;
  while (std::getline(in, line)) {
    double x, y;
    ASSERT_EQ(std::sscanf(line.c_str(), "%lf,%lf", &x, &y), 2);
    ASSERT_LT(i, grid.size());
    EXPECT_EQ(grid[i], glm::dvec2(x, y)) << "location " << i + 1;
    ++i;
  }
  EXPECT_EQ(i, 54u);
}

TEST(Field, ReadsLocatedAndGridFilesWithBomAndCrlf) {
  const auto located = parse_field_csv("\xEF\xBB\xBFx_deg,y_deg,total_deviation_db,eye\r\n3,3,-10,OD\r\n-3,3,-4,os\r\n", "f.csv");
  ASSERT_EQ(located.size(), 2u);
  EXPECT_EQ(located[0].eye, Eye::od);
  EXPECT_DOUBLE_EQ(located[0].points[0].loss_db, 10);
  EXPECT_DOUBLE_EQ(located[1].points[0].loss_db, 4);
  std::string grid = "sensitivity_db\n";
  for (int i = 0; i < 54; ++i) grid += "20\n";
  const auto g = parse_field_csv(grid, "g.csv", "24-2", Eye::od, 60);
  ASSERT_EQ(g.size(), 1u);
  EXPECT_EQ(g[0].points.size(), 52u);  // the two blind-spot locations are left out
  // sensitivity → loss with the age-normal model
  const NormalModel normal;
  const FieldPoint& first = g[0].points[0];  // (-9, 21)
  EXPECT_NEAR(first.loss_db, normal.sensitivity_db(60, std::hypot(9, 21)) - 20, 1e-12);
}

TEST(Field, TheAgeNormalModelIsCalixtosRegression) {
  const NormalModel n;
  // Calixto et al. 2006, subjects aged 20 or more: 28.7 − 0.050·age at the field's mean, −0.30 dB/°
  EXPECT_NEAR(n.sensitivity_db(20, n.mean_eccentricity_deg), 27.7, 1e-12);
  EXPECT_NEAR(n.sensitivity_db(70, n.mean_eccentricity_deg), 25.2, 1e-12);
  EXPECT_NEAR(n.sensitivity_db(50, 3) - n.sensitivity_db(50, 23), 6.0, 1e-12);
}

void expect_error(const std::string& text, const std::string& grid, const std::string& needle) {
  try {
    parse_field_csv(text, "bad.csv", grid);
    ADD_FAILURE() << "accepted: " << text;
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find(needle), std::string::npos) << e.what();
  }
}

TEST(Field, MalformedFilesNameFileLineAndReason) {
  expect_error("x_deg,y_deg,total_deviation_db\n3,3,\n", "", "bad.csv:2: total_deviation_db '' is not a number");
  expect_error("x_deg,y_deg,total_deviation_db\n3,3,-1\n3,3,-2\n", "", "bad.csv:3: location (3, 3) of OD appears twice");
  expect_error("x_deg,y_deg,sensitivity_db\n3,3,70\n", "", "bad.csv:2: sensitivity_db value 70 is out of range");
  expect_error("x_deg,y_deg,total_deviation_db\n3,3,-60\n", "", "out of range");
  expect_error("total_deviation_db\n-1\n-2\n", "24-2", "2 values for OD, the 24-2 grid has 54 locations");
  expect_error("x_deg,y_deg,total_deviation_db,eye\n3,3,-1,OU\n", "", "bad.csv:2: eye 'OU' is neither OD nor OS");
  expect_error("x_deg,y_deg,loss\n", "", "bad.csv:1: unknown column 'loss'");
  expect_error("x_deg,y_deg,total_deviation_db\n3,3\n", "", "bad.csv:2: 2 fields, the header has 3");
  expect_error("", "", "empty field file");
  expect_error("total_deviation_db\n-1\n", "", "name the grid");
}

TEST(Field, InterpolationNeverCrossesTheHorizontalMeridian) {
  PerimetryField f;
  for (const glm::dvec2 p : standard_grid("24-2", Eye::od)) f.points.push_back({p.x, p.y, 0, p.y > 0 ? 20.0 : 0.0});
  for (double x : {-25.0, -3.0, 0.0, 8.0, 20.0}) {
    EXPECT_DOUBLE_EQ(interpolate_loss_db(f, x, 0.01), 20.0);
    EXPECT_DOUBLE_EQ(interpolate_loss_db(f, x, -0.01), 0.0);
  }
  VisualField vf;
  vf.measured.push_back(f);
  vf.view = "both";  // no blind spot
  const FieldMap map = vf.map();
  for (double x : {-25.0, -3.0, 0.0, 8.0, 40.0}) {
    EXPECT_NEAR(map.loss_db(x, 0.01), 20.0, 1e-5);
    EXPECT_NEAR(map.loss_db(x, -0.01), 0.0, 1e-5);
  }
  // exact at the test locations, between them in between
  f.points[0].loss_db = 30;  // (-9, 21)
  EXPECT_DOUBLE_EQ(interpolate_loss_db(f, -9, 21), 30.0);
  const double between = interpolate_loss_db(f, -6, 21);
  EXPECT_GT(between, 20.0);
  EXPECT_LT(between, 30.0);
}

TEST(Field, TheBlindSpotSitsWhereTheEyesGeometryPutsIt) {
  VisualField vf;
  vf.generated.push_back({"central:2", std::nullopt});
  vf.view = "OD";
  const FieldMap od = vf.map();
  EXPECT_NEAR(od.loss_db(15.5, -1.5), kAbsoluteLossDb, 1e-3);
  EXPECT_NEAR(od.loss_db(15.5, 1.0), kAbsoluteLossDb, 1e-3);  // 7.5° high: up to 2.25° above the meridian
  EXPECT_NEAR(od.loss_db(15.5, 3.5), 0.0, 1e-3);
  EXPECT_NEAR(od.loss_db(-15.5, -1.5), 0.0, 1e-3);  // the nasal field has none
  vf.view = "OS";
  EXPECT_NEAR(vf.map().loss_db(-15.5, -1.5), kAbsoluteLossDb, 1e-3);
  vf.view = "both";  // each eye sees the other's blind spot
  EXPECT_NEAR(vf.map().loss_db(15.5, -1.5), 0.0, 1e-3);
}

TEST(Field, TheBinocularFieldIsTheBetterEyeAtEachLocation) {
  PerimetryField od, os;
  od.eye = Eye::od;
  os.eye = Eye::os;
  const auto grid = standard_grid("24-2", Eye::od);
  for (size_t i = 0; i < grid.size(); ++i) {
    od.points.push_back({grid[i].x, grid[i].y, 0, double((i * 7) % 25)});
    os.points.push_back({grid[i].x, grid[i].y, 0, double((i * 11) % 25)});
  }
  const PerimetryField ivf = integrated_field(od, os);
  VisualField vf;
  vf.measured = {od, os};
  const FieldMap map = vf.map();  // auto: both eyes → binocular
  for (size_t i = 0; i < grid.size(); ++i) {
    const double best = std::min(od.points[i].loss_db, os.points[i].loss_db);
    EXPECT_EQ(ivf.points[i].loss_db, best);
    if (!(grid[i].x == 15 && std::abs(grid[i].y) == 3))  // (the grid's blind-spot locations are not interpolated)
      EXPECT_NEAR(map.loss_db(grid[i].x, grid[i].y), best, 0.75) << grid[i].x << "," << grid[i].y;
  }
}

TEST(Field, GeneratedDefectsRespectTheirAnatomy) {
  const auto arcuate = generated_defect("arcuate:20", Eye::od);
  EXPECT_NEAR(arcuate(-10, 12), 20, 1e-9);  // superior nasal, 15.6° out
  EXPECT_EQ(arcuate(-10, -12), 0);          // the inferior field is spared
  EXPECT_EQ(arcuate(0, 3), 0);              // central field spared
  const auto step = generated_defect("nasal-step:15", Eye::od);
  EXPECT_NEAR(step(-25, 2), 15, 1e-9);
  EXPECT_EQ(step(-25, -2), 0);
  EXPECT_EQ(step(25, 2), 0);
  EXPECT_NEAR(generated_defect("nasal-step:15", Eye::os)(25, 2), 15, 1e-9);  // mirrored for OS
  EXPECT_NEAR(generated_defect("constriction:10:30", Eye::od)(0, 20), 30, 1e-9);
  EXPECT_EQ(generated_defect("constriction:10:30", Eye::od)(0, 5), 0);
  EXPECT_NEAR(generated_defect("central:5", Eye::od)(1, 1), 25, 1e-9);
  const auto hemi = generated_defect("hemianopia:left", Eye::os);
  EXPECT_NEAR(hemi(-5, 0), 25, 1e-9);
  EXPECT_EQ(hemi(5, 0), 0);
  const auto quad = generated_defect("quadrantanopia:upper-right:20", Eye::od);
  EXPECT_NEAR(quad(5, 5), 20, 1e-9);
  EXPECT_EQ(quad(5, -5), 0);
  EXPECT_EQ(quad(-5, 5), 0);
  EXPECT_THROW(generated_defect("central", Eye::od), Error);
  EXPECT_THROW(generated_defect("arcuate:90", Eye::od), Error);
  EXPECT_THROW(generated_defect("hemianopia:up", Eye::od), Error);
  EXPECT_THROW(generated_defect("spiral", Eye::od), Error);
}

// A grating image (vertical bars, period 8 px) about a mid grey, linear values
Image grating(int w, int h) {
  Image g(w, h, 3);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x)
      for (int c = 0; c < 3; ++c) g.at(x, y, c) = 0.5f + 0.3f * std::sin(2 * std::numbers::pi * x / 8.0);
  return g;
}

// RMS contrast of the rows [y0, y1) away from the left/right borders
double rms_contrast(const Image& im, int y0, int y1) {
  double sum = 0, sum2 = 0;
  size_t n = 0;
  for (int y = y0; y < y1; ++y)
    for (int x = 32; x < im.width - 32; ++x) {
      sum += im.at(x, y, 1);
      sum2 += im.at(x, y, 1) * im.at(x, y, 1);
      ++n;
    }
  const double mean = sum / n;
  return std::sqrt(std::max(0.0, sum2 / n - mean * mean)) / mean;
}

Retinotopy linear_retinotopy(int w, int h, glm::dvec2 gaze, double ppd) {
  Retinotopy r{w, h, std::vector<glm::vec2>(size_t(w) * h), ppd};
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) r.field_deg[size_t(y) * w + x] = glm::vec2((x + 0.5 - gaze.x) / ppd, (gaze.y - y - 0.5) / ppd);
  return r;
}

Impairments upper_loss(double db) {
  Impairments im;
  im.field.generated.push_back({fmt::format("altitudinal:{}:superior", db), std::nullopt});
  im.field.view = "both";
  return im;
}

TEST(FieldLoss, TheUpperHemifieldLosesLdBOfLocalContrastAndTheLowerNone) {
  const int w = 256, h = 256;
  const Image in = grating(w, h);
  const double c_in = rms_contrast(in, 0, h);
  for (double db : {3.0, 6.0, 10.0}) {
    const ImpairmentPasses passes(upper_loss(db));
    Image out = in;
    passes.apply(out, linear_retinotopy(w, h, {128, 128}, 10));
    const double upper = rms_contrast(out, 8, 96), lower = rms_contrast(out, 160, 248);
    EXPECT_NEAR(10 * std::log10(c_in / upper), db, 0.5) << db << " dB";
    EXPECT_NEAR(10 * std::log10(c_in / lower), 0.0, 0.05) << db << " dB";
    // the local mean luminance is kept
    double mean_in = 0, mean_out = 0;
    for (int y = 8; y < 96; ++y)
      for (int x = 32; x < w - 32; ++x) mean_in += in.at(x, y, 0), mean_out += out.at(x, y, 0);
    EXPECT_NEAR(mean_out / mean_in, 1.0, 0.01);
  }
}

// The row where the local contrast crosses halfway (in dB) between the upper and lower levels
double boundary_row(const Image& im) {
  std::vector<double> c(im.height);
  for (int y = 0; y < im.height; ++y) c[y] = 10 * std::log10(rms_contrast(im, y, y + 1));
  const double mid = 0.5 * (c[8] + c[im.height - 9]);
  for (int y = 8; y < im.height - 9; ++y)
    if (c[y] < mid && c[y + 1] >= mid) return y + (mid - c[y]) / (c[y + 1] - c[y]);
  return NAN;
}

TEST(FieldLoss, MovingTheGazeByDPixelsMovesTheBoundaryByDPixels) {
  const ImpairmentPasses passes(upper_loss(10));
  const Image in = grating(256, 320);
  Image a = in, b = in;
  passes.apply(a, linear_retinotopy(256, 320, {128, 120}, 10));
  passes.apply(b, linear_retinotopy(256, 320, {128, 157}, 10));
  const double ya = boundary_row(a), yb = boundary_row(b);
  EXPECT_NEAR(ya, 120, 2.0);
  EXPECT_NEAR(yb - ya, 37, 1.0);
}

TEST(FieldLoss, EveryModeLeavesAnUnimpairedFieldAloneAndChangesALostOne) {
  const Image in = grating(128, 128);
  for (FieldMode mode : {FieldMode::contrast, FieldMode::blur, FieldMode::grey, FieldMode::fill}) {
    Image none = in;
    apply_field_loss(none, std::vector<float>(128 * 128, 0.0f), mode);
    for (size_t i = 0; i < in.pixels.size(); ++i) ASSERT_NEAR(none.pixels[i], in.pixels[i], 1e-4) << to_string(mode);
    Image lost = in;
    apply_field_loss(lost, std::vector<float>(128 * 128, 40.0f), mode);
    EXPECT_LT(rms_contrast(lost, 16, 112), 0.1 * rms_contrast(in, 16, 112)) << to_string(mode);
  }
}

TEST(Glare, TheKernelIsTheCieEquationAtSampleAnglesAndItsSumTheScatteredFraction) {
  MediaParams m;
  m.age_years = 70;
  m.pigmentation = 0.5;
  m.cataract = 0.3;
  const double ppd = 10, s = std::pow(10.0, 0.3);
  const int r = 300;  // ±30°
  const std::vector<float> k = glare_kernel(ppd, r, r, m);
  const int w = 2 * r + 1;
  const double pixel_sr = std::pow(std::numbers::pi / 180 / ppd, 2);
  for (double deg : {1.0, 2.0, 5.0, 10.0, 25.0}) {
    const int dx = static_cast<int>(deg * ppd);
    // CIE 146:2002 with the cataract's straylight on the age-dependent term
    const double cie = 10 / std::pow(deg, 3) + s * (5 / (deg * deg) + 0.1 * 0.5 / deg) * (1 + std::pow(70 / 62.5, 4)) + 0.0025 * 0.5;
    EXPECT_NEAR(k[size_t(r) * w + r + dx] / (cie * pixel_sr), 1.0, 1e-5) << deg << "°";
  }
  // the kernel within 20° holds the equation's integral from 0.1° to 20°
  double inside = 0;
  for (int j = 0; j < w; ++j)
    for (int i = 0; i < w; ++i)
      if (std::hypot(i - r, j - r) <= 20 * ppd) inside += k[size_t(j) * w + i];
  EXPECT_NEAR(inside / cie_glare_fraction(0.1, 20, 70, 0.5, s), 1.0, 0.02);
  // the equation's values (CIE 146:2002) at 1° for a 25-year-old brown eye: 10 + 5·1.026 + 0.05·1.026 + 0.00125
  EXPECT_NEAR(cie_glare_psf(1.0, 25, 0.5), 10 + 5.05 * (1 + std::pow(25 / 62.5, 4)) + 0.00125, 1e-12);
  EXPECT_NEAR(cie_glare_psf(10.0, 25, 0.5), 0.01 + (0.05 + 0.005) * (1 + std::pow(25 / 62.5, 4)) + 0.00125, 1e-12);
}

TEST(Glare, ThePointSpreadKeepsEnergyAndFollowsTheEquation) {
  MediaParams m;
  m.age_years = 60;
  m.glare = true;
  const int n = 151;  // one pixel per 0.1° over 15°: no reduced grid
  const int c = n / 2;
  const double ppd = 10;
  Image delta(n, n, 3, 0.0f);
  for (int ch = 0; ch < 3; ++ch) delta.at(c, c, ch) = 1.0f;
  Image out = delta;
  apply_glare(out, ppd, m);
  const std::vector<float> k = glare_kernel(ppd, n - 1, n - 1, m);
  double eta = 0, landed = 0;
  const int kw = 2 * n - 1;
  for (int j = 0; j < kw; ++j)
    for (int i = 0; i < kw; ++i) {
      eta += k[size_t(j) * kw + i];
      if (std::abs(i - (n - 1)) <= c && std::abs(j - (n - 1)) <= c) landed += k[size_t(j) * kw + i];
    }
  double total = 0;
  for (int y = 0; y < n; ++y)
    for (int x = 0; x < n; ++x) total += out.at(x, y, 0);
  // what stays + what is scattered within the image; the rest left the image
  EXPECT_NEAR(total, 1.0 - eta + landed, 1e-4);
  EXPECT_GT(eta, landed);
  EXPECT_NEAR(out.at(c + 50, c, 1) / (cie_glare_psf(5.0, 60, 0.5) * std::pow(std::numbers::pi / 180 / ppd, 2)), 1.0, 1e-3);
  // a larger image goes through the reduced grid: the same scatter 5° out, within a few per cent
  Image big(640, 480, 3, 0.0f);
  for (int ch = 0; ch < 3; ++ch) big.at(320, 240, ch) = 1.0f;
  apply_glare(big, 40, m);
  double ring = 0;
  for (int a = 0; a < 360; a += 10)
    ring += big.at(320 + int(std::lround(200 * std::cos(a * std::numbers::pi / 180))),
                   240 + int(std::lround(200 * std::sin(a * std::numbers::pi / 180))), 0);
  EXPECT_NEAR(ring / 36 / (cie_glare_psf(5.0, 60, 0.5) * std::pow(std::numbers::pi / 180 / 40, 2)), 1.0, 0.05);
}

TEST(Media, LensYellowingFollowsPokornysAgeFactors) {
  MediaParams young, old;
  old.age_years = 75;
  const glm::dvec3 t25 = lens_transmittance(young), t75 = lens_transmittance(old);
  EXPECT_NEAR(t25.b, 1.0, 1e-12);
  // density added by 25 → 75 years: D1·([1.56 + 0.0667·15] − [1 + 0.02·(25 − 32)])
  const double extra = (1.56 + 0.0667 * 15) - (1 + 0.02 * (25 - 32));
  EXPECT_NEAR(-std::log10(t75.b), 0.25 * extra, 1e-12);
  EXPECT_LT(t75.b, t75.g);
  EXPECT_LT(t75.g, t75.r);
}

TEST(Metamorphopsia, DistortsOnlyNearTheFoveaAndTheSameForASeed) {
  Metamorphopsia m{0.5, 6, 3};
  EXPECT_EQ(m.displacement(10, 0), glm::dvec2(0));
  double largest = 0;
  for (double x = -5; x <= 5; x += 0.5)
    for (double y = -5; y <= 5; y += 0.5) largest = std::max(largest, glm::length(m.displacement(x, y)));
  EXPECT_GT(largest, 0.1);
  EXPECT_LT(largest, 2.0);
  EXPECT_EQ(m.displacement(1, 2), (Metamorphopsia{0.5, 6, 3}.displacement(1, 2)));
  EXPECT_NE(m.displacement(1, 2), (Metamorphopsia{0.5, 6, 4}.displacement(1, 2)));
}

TEST(Metamorphopsia, TheAmslerGridShowsTheScotomaAndTheDistortion) {
  Impairments healthy;
  const Image plain = amsler_grid(ImpairmentPasses(healthy), 10);
  Impairments amd = parse_eye_spec("amd:3:0.6").impair;
  const Image seen = amsler_grid(ImpairmentPasses(amd), 10);
  ASSERT_EQ(plain.width, seen.width);
  const int c = plain.width / 2;
  // the line 1° right of the centre: gone inside the scotoma (no contrast with the square beside it)
  EXPECT_GT(plain.at(c + 10, c + 5, 0) - plain.at(c + 15, c + 5, 0), 0.9f);
  EXPECT_LT(std::abs(seen.at(c + 10, c + 5, 0) - seen.at(c + 15, c + 5, 0)), 0.02f);
  double moved = 0;
  for (int y = 0; y < plain.height; ++y)
    for (int x = 0; x < plain.width; ++x) {
      const double r = std::hypot(x - c, y - c) / 10.0;
      if (r > 3.5 && r < 8) moved += std::abs(seen.at(x, y, 0) - plain.at(x, y, 0));
    }
  EXPECT_GT(moved, 50.0);                                                      // lines bent between the scotoma and 9°
  EXPECT_NEAR(seen.at(c + 100, c + 1, 0), plain.at(c + 100, c + 1, 0), 0.05);  // 10° out: unchanged
}

TEST(EyeSpec, PresetsJoinOpticsAndImpairments) {
  const EyeSpec s = parse_eye_spec("presbyopia:70+cataract:0.4+cvd:deutan:0.6+field:arcuate:20+field-mode:fill");
  EXPECT_EQ(s.eye.age_years, 70);
  EXPECT_EQ(s.impair.media.age_years, 70);
  EXPECT_EQ(s.impair.media.cataract, 0.4);
  EXPECT_TRUE(s.impair.media.glare);
  EXPECT_EQ(s.impair.cvd.type, CvdType::deutan);
  EXPECT_EQ(s.impair.cvd.severity, 0.6);
  ASSERT_EQ(s.impair.field.generated.size(), 1u);
  EXPECT_EQ(s.impair.field_mode, FieldMode::fill);
  EXPECT_EQ(parse_eye_spec("hyperopia:+2+achromatopsia").impair.cvd.type, CvdType::achromatopsia);
  EXPECT_EQ(parse_eye_spec("glaucoma").eye.glaucoma, 0.5);
  for (const char* bad : {"cataract:2", "cvd:purple", "cvd:protanopia:0.5", "field:", "field:spiral", "age:-3", "amd:50", "field:24-2",
                          "field-view:OU", "sparkles"})
    EXPECT_THROW(parse_eye_spec(bad), Error) << bad;
}

TEST(EyeSpec, ProfilesAreValidatedStrictlyWithJsonPaths) {
  const auto dir = std::filesystem::temp_directory_path() / "foveal-profile-test";
  std::filesystem::create_directories(dir);
  {
    std::ofstream f(dir / "od.csv");
    f << "x_deg,y_deg,total_deviation_db\n-3,3,-12\n3,3,-2\n-3,-3,0\n3,-3,0\n";
  }
  const std::string good = R"({"age": 66, "view": "OD", "colour_vision": {"type": "protan", "severity": 0.3},
    "eyes": {"OD": {"refraction": -1.5, "cataract": 0.2, "field": {"file": "od.csv"}},
             "OS": {"field": {"defect": "arcuate:20"}}}})";
  const EyeSpec s = parse_eye_profile(good, "p.json", dir.string());
  EXPECT_EQ(s.eye.refraction_d, -1.5);
  EXPECT_EQ(s.eye.age_years, 66);
  EXPECT_EQ(s.impair.media.cataract, 0.2);
  EXPECT_EQ(s.impair.cvd.type, CvdType::protan);
  ASSERT_EQ(s.impair.field.measured.size(), 1u);
  EXPECT_NEAR(ImpairmentPasses(s.impair).field_map().loss_db(-3, 3), 12, 0.5);
  auto error_of = [&](const std::string& json) {
    try {
      parse_eye_profile(json, "p.json", dir.string());
    } catch (const Error& e) {
      return std::string(e.what());
    }
    return std::string("accepted");
  };
  EXPECT_EQ(
      error_of(R"({"eyes": {"OD": {"refraction": -1.5, "colour": 1}}})"),
      "p.json: /eyes/OD/colour: unknown key (expected refraction, cylinder, axis, pupil_mm, glaucoma, cataract, field, metamorphopsia)");
  EXPECT_EQ(error_of(R"({"eyes": {"OD": {"refraction": "-1.5"}}})"), "p.json: /eyes/OD/refraction: must be a number");
  EXPECT_EQ(error_of(R"({"eyes": {"OD": {"cataract": 3}}})"), "p.json: /eyes/OD/cataract: must be in [0, 1], got 3");
  EXPECT_EQ(error_of(R"({"eyes": {"OU": {}}})"), "p.json: /eyes/OU: unknown key (expected OD, OS)");
  EXPECT_EQ(error_of(R"({"age": 50})"), "p.json: /: needs \"eyes\" with \"OD\" and/or \"OS\"");
  EXPECT_EQ(error_of(R"({"eyes": {"OD": {}}, "view": "OS"})"), "p.json: /view: OS is not among the profile's eyes");
  EXPECT_NE(error_of(R"({"eyes": {"OD": {"field": {"file": "missing.csv"}}}})").find("/eyes/OD/field"), std::string::npos);
  EXPECT_NE(error_of("{\"eyes\": ").find("p.json: not valid JSON"), std::string::npos);
  EXPECT_NE(error_of("{\"age\": 4444E54424}").find("p.json: not valid JSON"), std::string::npos);  // found by fuzzing
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace foveal
