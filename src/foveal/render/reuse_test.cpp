// Tests of quality per ray: temporal accumulation, adaptive rays and the edge-stopping filter.
#include "foveal/render/reuse.h"
#include "foveal/util/error.h"
#include "foveal/util/parallel.h"
#include "test_scenes.h"

#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <map>
#include <optional>
#include <string>

using namespace foveal;

namespace {

const Scene& scene(const std::string& name) {
  static std::map<std::string, Scene> scenes;
  auto it = scenes.find(name);
  if (it == scenes.end()) it = scenes.emplace(name, make_builtin_scene(name)).first;
  return it->second;
}

using foveal_test::same_bits;

// RMS of (V − truth) over the pixels that hit the scene.
double rms_error(const Frame& f, const std::vector<float>& truth) {
  double sum = 0;
  size_t count = 0;
  for (size_t i = 0; i < truth.size(); ++i)
    if (f.gbuffer.hit(i)) {
      sum += (f.visibility[i] - truth[i]) * (f.visibility[i] - truth[i]);
      ++count;
    }
  return std::sqrt(sum / count);
}

// builtin:sphere-plane seen from above, and the analytic AO on its plane: under a sphere of
// R = 1 whose centre is at height H = 2, the cosine-weighted occlusion at horizontal distance d is
// R²H/(H² + d²)^{3/2}. No value where pixel i misses the plane or lies under the sphere from above.
const Camera kTopCamera{"top", {0.0f, 6.0f, 0.01f}, {0.0f, 0.0f, 0.0f}, {0, 1, 0}, 50.0f};
std::optional<double> plane_visibility(const Frame& f, size_t i) {
  const glm::vec3 x = f.gbuffer.position[i];
  if (!f.gbuffer.hit(i) || std::fabs(x.y) > 1e-3f) return std::nullopt;
  const double d2 = x.x * x.x + x.z * x.z;
  if (d2 < 1.2 * 1.2) return std::nullopt;
  return 1.0 - 2.0 / std::pow(4.0 + d2, 1.5);
}

}  // namespace

TEST(Reuse, FirstTemporalFrameIsThePapersFrame) {
  // No history: frame 0 casts every pixel's n(E) rays from the start of its sequence
  const Scene& box = scene("box");
  const Tracer tracer(box);
  RenderParams p;
  p.width = 96, p.height = 60, p.foveation.max_rays = 32, p.gaze_px = glm::dvec2(30, 20);
  const Frame paper = render_frame(tracer, box, box.cameras.front(), p);
  p.reuse.temporal = true;
  AoHistory history;
  const Frame first = render_frame(tracer, box, box.cameras.front(), p, {}, &history);
  EXPECT_TRUE(same_bits(first.visibility, paper.visibility));
  EXPECT_EQ(first.stats.ao_rays, paper.stats.ao_rays);
  EXPECT_EQ(history.frames(), 1u);
  // The next frame keeps every pixel's history and casts n/F rays a pixel
  const Frame second = render_frame(tracer, box, box.cameras.front(), p, {}, &history);
  size_t hits = 0;
  for (size_t i = 0; i < second.visibility.size(); ++i) hits += second.gbuffer.hit(i);
  EXPECT_EQ(second.stats.history_pixels, hits);
  EXPECT_LT(second.stats.ao_rays, paper.stats.ao_rays / 3);
  EXPECT_FALSE(same_bits(second.visibility, paper.visibility));
}

TEST(Reuse, StillViewConvergesToTheReference) {
  // A still camera and gaze: the error against a 4096-ray truth falls as 1/√rays while history
  // grows (64 rays, then 16 a frame up to H = 16 frames of 16), below a 64-ray reference's own error
  const Scene& s = scene("sphere-plane");
  const Tracer tracer(s);
  const Camera camera = s.cameras.front();
  RenderParams p;
  p.width = 64, p.height = 40, p.mode = RenderMode::full, p.foveation.max_rays = 4096, p.seed = 11;
  const std::vector<float> truth = render_frame(tracer, s, camera, p).visibility;
  p.foveation.max_rays = 64, p.seed = 2;
  const Frame reference = render_frame(tracer, s, camera, p);
  const double reference_error = rms_error(reference, truth);
  p.seed = 1;
  p.reuse.temporal = true;
  AoHistory history;
  std::vector<double> errors;
  for (int k = 0; k < 13; ++k) errors.push_back(rms_error(render_frame(tracer, s, camera, p, {}, &history), truth));
  // 64 rays, then 80, 96, …, 256 after 13 frames: 1/√4 of the first error, allowing 25 %
  EXPECT_LT(errors.back(), 0.5 * 1.25 * errors.front());
  EXPECT_LT(errors[4], errors.front());  // 128 rays
  EXPECT_LT(errors.back(), errors[4]);
  EXPECT_LT(errors.back(), reference_error);
  // The cap: H = 16 frames of 16 rays where q = 1
  EXPECT_FLOAT_EQ(history_cap_rays(64, 1.0f, p.reuse), 256.0f);
  EXPECT_FLOAT_EQ(history_cap_rays(64, 0.1f, p.reuse), 64.0f);  // F = 4 frames in the periphery
}

TEST(Reuse, MovingCameraConvergesWithoutDrift) {
  // The camera slides 0.3 px a frame over the plane under the sphere, seen from above, with q = 1
  // everywhere (the strictest reach, 0.1 px): every plane pixel keeps history, the history's
  // rays stay centred on its point (bilinear reprojection, weighed down where their mean origin
  // drifts), and after 16 frames the error against the analytic V is well below a 64-ray frame's
  // own. Nearest-pixel history drifted a fraction of a pixel a frame and lost the fovea.
  const Scene& s = scene("sphere-plane");
  const Tracer tracer(s);
  const Camera start = kTopCamera;
  RenderParams p;
  p.width = 80, p.height = 80, p.mode = RenderMode::full, p.foveation.max_rays = 64;
  const float pixel = 2.0f * std::tan(glm::radians(start.fov_deg) * 0.5f) * 6.0f / static_cast<float>(p.height);
  auto camera_at = [&](int k) {
    Camera c = start;
    c.eye.x += 0.3f * pixel * static_cast<float>(k);
    c.look.x += 0.3f * pixel * static_cast<float>(k);
    return c;
  };
  // RMS error against the analytic V over the plane outside the sphere's shadow from above
  auto plane_error = [](const Frame& f) {
    double sum = 0;
    size_t count = 0;
    for (size_t i = 0; i < f.visibility.size(); ++i) {
      const std::optional<double> truth = plane_visibility(f, i);
      if (!truth) continue;
      sum += (f.visibility[i] - *truth) * (f.visibility[i] - *truth);
      ++count;
    }
    return std::sqrt(sum / static_cast<double>(count));
  };
  constexpr int kFrames = 16;
  p.seed = 3;
  const double reference_error = plane_error(render_frame(tracer, s, camera_at(kFrames - 1), p));
  p.seed = 1;
  p.reuse.temporal = true;
  AoHistory history;
  Frame f;
  for (int k = 0; k < kFrames; ++k) {
    if (k == kFrames - 1) {
      // The weighing-down: with this frame's n/F rays at the point, the history's mean origin
      // comes within 0.1 px of it
      RenderParams plain = p;
      plain.reuse.temporal = false;
      const Frame probe = render_frame(tracer, s, camera_at(k), plain);
      AoCounts counts;
      history.reproject(probe.gbuffer, probe.maps, p.reuse, counts);
      const float m = static_cast<float>(refresh_rays(p.foveation.max_rays, p.reuse.temporal_frames));
      size_t kept = 0, plane = 0;
      for (size_t i = 0; i < counts.cast.size(); ++i) {
        if (!probe.gbuffer.hit(i) || std::fabs(probe.gbuffer.position[i].y) > 1e-3f) continue;
        ++plane;
        if (!(counts.cast[i] > 0)) continue;
        ++kept;
        const glm::vec3 mean = (counts.origin_sum[i] + m * probe.gbuffer.position[i]) / (counts.cast[i] + m);
        const float footprint = pixel * glm::length(probe.gbuffer.position[i] - camera_at(k).eye) / 6.0f;
        ASSERT_LE(glm::length(mean - probe.gbuffer.position[i]), 0.101f * footprint) << "pixel " << i;
      }
      EXPECT_GT(kept, plane * 95 / 100);
    }
    f = render_frame(tracer, s, camera_at(k), p, {}, &history);
  }
  EXPECT_GT(f.stats.history_pixels, 3000u);
  EXPECT_LT(f.stats.ao_rays, 64ull * 6400 / 3);  // n/F rays at most pixels
  const double error = plane_error(f);
  EXPECT_LT(error, 0.7 * reference_error) << "temporal " << error << ", 64-ray frame " << reference_error;
}

TEST(Reuse, DisocclusionLeavesNoGhost) {
  // Frames of a sphere over a plane, then the sphere gone: the pixels that saw the sphere now see
  // the open plane, reject their history and show V = 1 exactly
  const Scene& with = scene("sphere-plane");
  const Scene& without = scene("plane");
  const Tracer tracer_with(with), tracer_without(without);
  const Camera camera = with.cameras.front();
  RenderParams p;
  p.width = 80, p.height = 50, p.mode = RenderMode::full, p.foveation.max_rays = 32;
  p.reuse.temporal = true;
  AoHistory history;
  Frame before;
  for (int k = 0; k < 3; ++k) before = render_frame(tracer_with, with, camera, p, {}, &history);
  const Frame after = render_frame(tracer_without, without, camera, p, {}, &history);
  size_t revealed = 0, occluded_before = 0;
  for (size_t i = 0; i < after.visibility.size(); ++i) {
    if (!after.gbuffer.hit(i) || !before.gbuffer.hit(i)) continue;
    if (std::fabs(before.gbuffer.position[i].y) < 1e-3f) continue;  // the plane then too
    ++revealed;
    occluded_before += before.visibility[i] < 0.99f;
    EXPECT_EQ(after.visibility[i], 1.0f) << "pixel " << i;
    EXPECT_EQ(after.ao_traced[i], 32) << "a revealed pixel starts afresh with n rays";
  }
  EXPECT_GT(revealed, 200u);
  EXPECT_GT(occluded_before, 50u);  // the sphere's lower half was dark: a ghost would show
  // The plane's pixels kept their history except where the sphere's shadow was contradicted
  EXPECT_GT(after.stats.history_pixels, 0u);
}

TEST(Reuse, AdaptiveStopsAtTheMinimumOnAnOpenPlane) {
  // V = 1 everywhere: each pixel stops at the first round whose all-open standard error is below
  // τ(E), the smallest count the model allows, and its visibility is exactly 1
  const Scene& s = scene("plane");
  const Tracer tracer(s);
  RenderParams p;
  p.width = 120, p.height = 75, p.foveation.max_rays = 400, p.gaze_px = glm::dvec2(40, 40);
  p.reuse.adaptive = true;
  const Frame f = render_frame(tracer, s, s.cameras.front(), p);
  const AoSampling sampling = ao_sampling(p.reuse, 0);
  size_t checked = 0, saved = 0;
  for (size_t i = 0; i < f.visibility.size(); ++i) {
    if (!f.gbuffer.hit(i) || f.maps.rays[i] == 0) continue;
    const int n = f.maps.rays[i];
    int expected = std::min(n, p.reuse.adaptive_min_rays);
    while (expected < n &&
           visibility_standard_error(static_cast<float>(expected), static_cast<float>(expected)) * f.maps.quality[i] > sampling.tau_fovea)
      expected = std::min(n, 2 * expected);
    ASSERT_EQ(f.ao_traced[i], expected) << "pixel " << i;
    ASSERT_EQ(f.visibility[i], 1.0f);
    ++checked;
    saved += expected < n;
  }
  EXPECT_GT(checked, 5000u);
  EXPECT_GT(saved, checked / 2);
  EXPECT_LT(f.stats.ao_rays, 64ull * checked);  // at most 64 rays where q = 1 (0.71/k ≤ 0.0125 at k = 64)
}

TEST(Reuse, AdaptiveKeepsTheSphereOverThePlaneWithinItsError) {
  // On the plane under a sphere (R = 1, centre at height H = 2) the cosine-weighted occlusion at
  // horizontal distance d is R²H/(H² + d²)^{3/2}. Each adaptive pixel's error, in units of the
  // standard error it stopped at (≤ τ(E)), has an RMS of at most 1.
  const Scene& s = scene("sphere-plane");
  const Tracer tracer(s);
  const Camera camera = kTopCamera;
  RenderParams p;
  p.width = 80, p.height = 80, p.foveation.max_rays = 400;
  p.reuse.adaptive = true;
  p.reuse.tolerance = 0.5;  // a looser τ than the default, so that many pixels stop early
  const Frame f = render_frame(tracer, s, camera, p);
  const float tau_fovea = ao_sampling(p.reuse, 0).tau_fovea;
  double z2 = 0;
  size_t count = 0, stopped_early = 0;
  for (size_t i = 0; i < f.visibility.size(); ++i) {
    const std::optional<double> truth = plane_visibility(f, i);
    if (!truth || f.maps.rays[i] == 0) continue;
    const double tau = tau_fovea / f.maps.quality[i];
    z2 += (f.visibility[i] - *truth) * (f.visibility[i] - *truth) / (tau * tau);
    ++count;
    stopped_early += f.ao_traced[i] < f.maps.rays[i];
  }
  ASSERT_GT(count, 1000u);
  EXPECT_GT(stopped_early, count / 8);  // measured 17 % at tolerance 0.5: most of the plane is partly occluded
  EXPECT_LT(std::sqrt(z2 / count), 1.0) << "RMS error / τ";
}

TEST(Reuse, FilterNeverMixesAcrossADepthStepACreaseOrAnotherAo) {
  // A hand-made G-buffer: the left half a near plane, the right half a far one, both facing the
  // camera, q = 0.1 (the widest footprint). Nothing may mix across a depth step or a crease;
  // on one plane, what differs by far more than its noise (a crevice's AO beside the open
  // surface) stays apart, and what differs by less (noise) is pooled.
  const int w = 24, h = 12;
  GBuffer g;
  g.width = w, g.height = h;
  const size_t n = static_cast<size_t>(w) * h;
  FoveationMaps maps;
  maps.width = w, maps.height = h;
  maps.quality.assign(n, 0.1f), maps.rays.assign(n, 1), maps.blend.assign(n, 1.0f), maps.eccentricity.assign(n, 30.0f);
  AoCounts counts;
  // `open(x, y)` of `cast` rays at each pixel
  auto build = [&](float far_depth, glm::vec3 far_normal, float cast, const std::function<float(int, int)>& open) {
    g.prim.assign(n, 0), g.position.resize(n), g.normal.resize(n), g.geo_normal.resize(n), g.albedo.assign(n, glm::vec3(0.5f));
    g.depth.resize(n), g.view.assign(n, glm::vec3(0, 0, -1));
    counts.open.resize(n), counts.cast.assign(n, cast);
    for (int y = 0; y < h; ++y)
      for (int x = 0; x < w; ++x) {
        const size_t i = static_cast<size_t>(y) * w + x;
        const bool left = x < w / 2;
        const float depth = left ? 10.0f : far_depth;
        g.depth[i] = depth;
        g.position[i] = glm::vec3((x - w / 2) * 0.01f * depth, (y - h / 2) * 0.01f * depth, -depth);
        g.normal[i] = g.geo_normal[i] = left ? glm::vec3(0, 0, 1) : far_normal;
        counts.open[i] = open(x, y);
      }
  };
  auto halves = [&](float left_open, float right_open) { return [=](int x, int) { return x < w / 2 ? left_open : right_open; }; };
  auto filtered = [&] {
    std::vector<float> v(n);
    for (size_t i = 0; i < n; ++i) v[i] = counts.open[i] / counts.cast[i];
    AoReuseParams reuse;
    reuse.denoise = true;
    denoise_visibility(g, maps, counts, reuse, glm::degrees(2.0f * std::atan(0.01f * h / 2)), v);  // 0.01 rad a pixel
    return v;
  };
  build(20.0f, glm::vec3(0, 0, 1), 1, halves(0, 1));  // a depth step: twice as far; one ray a pixel
  for (size_t i = 0; i < n; ++i) EXPECT_EQ(filtered()[i], counts.open[i]) << "depth step, pixel " << i;
  build(10.0f, glm::vec3(1, 0, 0), 1, halves(0, 1));  // a crease: the same depth, normals 90° apart
  std::vector<float> crease = filtered();
  for (size_t i = 0; i < n; ++i) EXPECT_EQ(crease[i], counts.open[i]) << "crease, pixel " << i;
  // Control: one continuous plane — one ray a pixel is all noise, and the filter mixes across the boundary
  build(10.0f, glm::vec3(0, 0, 1), 1, halves(0, 1));
  const std::vector<float> plane = filtered();
  size_t mixed = 0;
  for (size_t i = 0; i < n; ++i) mixed += plane[i] > 0.0f && plane[i] < 1.0f;
  EXPECT_GT(mixed, static_cast<size_t>(2 * h));
  // One plane at q = 0.5 (a 3×3 window; the range weight's k(E) = 1/√q = 1.4), V = 0.2 beside
  // V = 0.8 from 20 rays a pixel (each noisier than τ there, so filtered): 0.6 apart is 4.6
  // standard errors of the difference, over three k(E) — two AOs, kept apart
  maps.quality.assign(n, 0.5f);
  build(10.0f, glm::vec3(0, 0, 1), 20, halves(4, 16));
  const std::vector<float> step = filtered();
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x)
      EXPECT_NEAR(step[static_cast<size_t>(y) * w + x], x < w / 2 ? 0.2f : 0.8f, 0.01f) << "AO step, pixel " << x << "," << y;
  // One plane, 0.45 and 0.55 in a checkerboard (less than one standard error apart): noise, pooled
  build(10.0f, glm::vec3(0, 0, 1), 20, [](int x, int y) { return (x + y) % 2 ? 11.0f : 9.0f; });
  const std::vector<float> checker = filtered();
  double off = 0;
  for (float v : checker) off += std::fabs(v - 0.5f) / static_cast<double>(n);
  EXPECT_LT(off, 0.025) << "mean |V - 0.5| (0.05 before the filter)";
}

TEST(Reuse, FilterLeavesTheFoveaAlone) {
  EXPECT_EQ(denoise_max_radius(1.0f, AoReuseParams{}), 0);
  EXPECT_EQ(denoise_max_radius(0.5f, AoReuseParams{}), 1);
  EXPECT_EQ(denoise_max_radius(0.2f, AoReuseParams{}), 4);
  EXPECT_EQ(denoise_max_radius(0.01f, AoReuseParams{}), kMaxDenoiseRadius);
}

TEST(Reuse, SameFramesForAnyThreadCount) {
  const Scene& box = scene("box");
  const Tracer tracer(box);
  const Camera a = box.cameras.front();
  Camera b = a;
  b.eye += glm::vec3(0.15f, 0.05f, 0.0f);  // the camera moves between the frames
  RenderParams p;
  p.width = 96, p.height = 60, p.foveation.max_rays = 64, p.gaze_px = glm::dvec2(40, 30);
  p.reuse.adaptive = p.reuse.denoise = p.reuse.temporal = true;
  auto run = [&](int threads) {
    const ThreadScope scope(threads);
    AoHistory history;
    render_frame(tracer, box, a, p, {}, &history);
    return render_frame(tracer, box, b, p, {}, &history);
  };
  const Frame one = run(1);
  EXPECT_GT(one.stats.history_pixels, 1000u);
  EXPECT_GT(one.stats.denoised_pixels, 0u);
  for (int threads : {2, 5}) {
    const Frame f = run(threads);
    EXPECT_TRUE(same_bits(f.visibility, one.visibility)) << threads << " threads";
    EXPECT_TRUE(same_bits(f.color.pixels, one.color.pixels)) << threads << " threads";
    EXPECT_EQ(f.stats.ao_rays, one.stats.ao_rays);
  }
}

// Two views of the box a little to the side of each other, with counts for every pixel of the
// first (the history's tests)
struct TwoViews {
  const Scene& s = scene("box");
  const Tracer tracer{s};
  RenderParams p = [] {
    RenderParams r;
    r.width = 80;
    r.height = 50;
    r.foveation.max_rays = 64;
    return r;
  }();
  Camera a = s.cameras.front(), b = moved(a);
  GBuffer ga = trace_primary(tracer, s, a, p.width, p.height), gb = trace_primary(tracer, s, b, p.width, p.height);
  FoveationMaps ma = foveation_maps(p, {40, 25}), mb = foveation_maps(p, {44, 25});
  size_t n = ga.prim.size();
  AoCounts counts = counts_of(ga);
  static Camera moved(Camera c) {
    c.eye += 0.02f * glm::cross(c.look - c.eye, c.up);
    return c;
  }
  static AoCounts counts_of(const GBuffer& g) {
    AoCounts c;
    for (size_t i = 0; i < g.prim.size(); ++i) {
      c.cast.push_back(16.0f + static_cast<float>(i % 5));
      c.open.push_back(static_cast<float>(i % 13));
      c.origin_sum.push_back(c.cast.back() * g.position[i] + glm::vec3(0.001f * static_cast<float>(i % 3)));
    }
    return c;
  }
};

TEST(Reuse, ReprojectingInRowsIsReprojectingTheView) {
  // A history of one view, reprojected into a view a little to the side: row by row in uneven
  // steps (what the real-time loop does while a size comes back) or at once, the same counts
  TwoViews v;
  const Camera& a = v.a;
  const RenderParams& p = v.p;
  const GBuffer &ga = v.ga, &gb = v.gb;
  const FoveationMaps &ma = v.ma, &mb = v.mb;
  const size_t n = v.n;
  const AoCounts& counts = v.counts;
  AoHistory history;
  history.store(ga, a, ma, p.reuse, counts);
  AoCounts whole, rows;
  const uint64_t kept = history.reproject(gb, mb, p.reuse, whole);
  EXPECT_GT(kept, n / 2);
  rows.open.assign(n, 0.0f);
  rows.cast.assign(n, 0.0f);
  rows.origin_sum.assign(n, glm::vec3(0.0f));
  uint64_t kept_rows = 0;
  for (int y = 0; y < p.height; y += 1 + y % 4)
    kept_rows += history.reproject_rows(gb, mb, p.reuse, rows, y, std::min(p.height, y + 1 + y % 4));
  EXPECT_EQ(kept_rows, kept);
  EXPECT_TRUE(same_bits(rows.open, whole.open));
  EXPECT_TRUE(same_bits(rows.cast, whole.cast));
  for (size_t i = 0; i < n; ++i) ASSERT_EQ(rows.origin_sum[i], whole.origin_sum[i]) << i;
  // Rows the counts do not hold yet are refused, with the rows named
  AoCounts short_counts;
  short_counts.open.assign(n / 2, 0.0f);
  short_counts.cast.assign(n / 2, 0.0f);
  short_counts.origin_sum.assign(n / 2, glm::vec3(0.0f));
  EXPECT_NO_THROW(history.reproject_rows(gb, mb, p.reuse, short_counts, 0, p.height / 2));
  EXPECT_THROW(history.reproject_rows(gb, mb, p.reuse, short_counts, 0, p.height), Error);
  EXPECT_THROW(history.reproject_rows(gb, mb, p.reuse, rows, 3, 2), Error);
}

TEST(Reuse, StoringInRowsIsStoringTheView) {
  // A view kept a few rows at a time (what the real-time loop does while a size comes back) or at
  // once: reprojected into a view a little to the side, the same counts. Empty until the last row.
  const TwoViews v;
  AoHistory whole, rows;
  whole.store(v.ga, v.a, v.ma, v.p.reuse, v.counts);
  const AoHistory::PixelCounts pixel = [&](size_t i, glm::vec3, float& open, float& cast, glm::vec3& origin_sum) {
    open = v.counts.open[i];
    cast = v.counts.cast[i];
    origin_sum = v.counts.origin_sum[i];
  };
  rows.begin_rows(v.p.width, v.p.height, v.a);
  for (int y = 0; y < v.p.height; y += 1 + y % 4) {
    EXPECT_TRUE(rows.empty()) << "row " << y;
    rows.store_rows(v.ga, v.ma, v.p.reuse, pixel, y, std::min(v.p.height, y + 1 + y % 4));
  }
  ASSERT_FALSE(rows.empty());
  EXPECT_EQ(rows.rows_stored(), v.p.height);
  EXPECT_EQ(rows.frames(), whole.frames());
  AoCounts from_whole, from_rows;
  const uint64_t kept = whole.reproject(v.gb, v.mb, v.p.reuse, from_whole);
  EXPECT_GT(kept, v.n / 2);
  EXPECT_EQ(rows.reproject(v.gb, v.mb, v.p.reuse, from_rows), kept);
  EXPECT_TRUE(same_bits(from_rows.open, from_whole.open));
  EXPECT_TRUE(same_bits(from_rows.cast, from_whole.cast));
  for (size_t i = 0; i < v.n; ++i) ASSERT_EQ(from_rows.origin_sum[i], from_whole.origin_sum[i]) << i;
  // Rows out of order, past the view, or of another view are refused, the rows named
  AoHistory bad;
  bad.begin_rows(v.p.width, v.p.height, v.a);
  EXPECT_THROW(bad.store_rows(v.ga, v.ma, v.p.reuse, pixel, 2, 4), Error);
  bad.store_rows(v.ga, v.ma, v.p.reuse, pixel, 0, 2);
  EXPECT_THROW(bad.store_rows(v.ga, v.ma, v.p.reuse, pixel, 2, v.p.height + 1), Error);
  EXPECT_THROW(bad.store_rows(v.gb, v.ma, v.p.reuse, pixel, 2, 1), Error);
  const GBuffer small = trace_primary(v.tracer, v.s, v.a, v.p.width / 2, v.p.height / 2);
  EXPECT_THROW(bad.store_rows(small, v.ma, v.p.reuse, pixel, 2, 3), Error);
  EXPECT_THROW(bad.begin_rows(0, 10, v.a), Error);
  // A whole store meanwhile abandons the rows
  bad.store(v.ga, v.a, v.ma, v.p.reuse, v.counts);
  EXPECT_THROW(bad.store_rows(v.ga, v.ma, v.p.reuse, pixel, 2, 3), Error);
}

TEST(Reuse, RejectsBadParameters) {
  RenderParams p;
  p.reuse.adaptive_min_rays = 0;
  EXPECT_THROW(validate(p), Error);
  p = RenderParams{};
  p.reuse.denoise_radius = 9;
  EXPECT_THROW(validate(p), Error);
  p = RenderParams{};
  p.reuse.temporal_frames = 0;
  EXPECT_THROW(validate(p), Error);
  p = RenderParams{};
  p.reuse.tolerance = 0;
  EXPECT_THROW(validate(p), Error);
  // The contradiction test: 40 % occluded history against 16 open fresh rays
  EXPECT_TRUE(history_contradicted(240, 400, 16, 16));
  EXPECT_FALSE(history_contradicted(380, 400, 16, 16));
}
