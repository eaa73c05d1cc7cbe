// The CUDA backend against the CPU renderer. Tests that need a GPU skip with the reason where
// none is usable (CI has none); the device choice is tested everywhere.
#include "foveal/cuda/gpu.h"
#include "foveal/experiments/gpu_benchmark.h"
#include "foveal/impair/profile.h"
#include "foveal/perception/eye.h"
#include "foveal/util/error.h"
#include "foveal/vision/simulate.h"

#include <gtest/gtest.h>
#include <opencv2/features2d.hpp>

#include <cstring>
#include <filesystem>
#include <random>
#include <set>
#include <tuple>

namespace foveal {
namespace {

#define FOVEAL_NEED_GPU()                                                             \
  do {                                                                                \
    if (!availability().usable) GTEST_SKIP() << "skipped: " << availability().reason; \
  } while (0)

TEST(GpuDevice, ChoiceFollowsAvailability) {
  const Availability& a = availability();
  EXPECT_EQ(choose_device("cpu"), ComputeDevice::cpu);
  EXPECT_EQ(choose_device("auto"), a.usable ? ComputeDevice::cuda : ComputeDevice::cpu);
  EXPECT_THROW(choose_device("opencl"), Error);
  if (a.usable) {
    EXPECT_EQ(choose_device("cuda"), ComputeDevice::cuda);
    EXPECT_FALSE(a.name.empty());
    EXPECT_GT(a.multiprocessors, 0);
  } else {
    // Unusable: a reason, and `cuda` refused with it
    EXPECT_FALSE(a.reason.empty());
    try {
      choose_device("cuda");
      ADD_FAILURE() << "--device cuda accepted without a GPU";
    } catch (const Error& e) {
      EXPECT_NE(std::string(e.what()).find(a.reason), std::string::npos) << e.what();
    }
    EXPECT_THROW(gpu::Renderer{make_builtin_scene("box")}, Error);
  }
}

// Frames of the GPU and the CPU for the same parameters.
struct Pair {
  Frame gpu, cpu;
};
Pair render_both(const Scene& scene, const Camera& camera, const RenderParams& p) {
  gpu::Renderer renderer(scene);
  const Tracer tracer(scene);
  return {renderer.render(camera, p), render_frame(tracer, scene, camera, p)};
}

// The GPU's frame against the CPU's: the same primary triangles (ties at shared edges aside), the
// same maps and ray counts, and AO visibility that differs only where rays graze an edge and land
// on the other side of it in float arithmetic (the G-buffer's positions and normals differ in
// their last bits): in most pixels by at most two rays, with no bias, and far inside the
// Monte-Carlo estimate's own spread (measured on an H100: 92-99 % of pixels within two rays,
// mean difference ≤ 5e-5, mean |difference| 0.02-0.19 of the estimate's standard error).
void expect_matches_cpu(const Pair& f) {
  const gpu::Agreement a = gpu::compare_frames(f.gpu, f.cpu);
  EXPECT_GE(a.primary_identical, 0.999);
  EXPECT_EQ(f.gpu.maps.rays, f.cpu.maps.rays);  // the same function of the same doubles
  EXPECT_EQ(f.gpu.stats.ao_rays, f.cpu.stats.ao_rays);
  EXPECT_GE(a.visibility_within_2_rays, 0.9);
  EXPECT_LT(std::abs(a.visibility_mean_signed), 2e-4);
  EXPECT_LT(a.noise_ratio, 0.25) << "mean |dV| " << a.visibility_mean_abs;
  // Colour: where the pixel's triangle and visibility agree, equal up to float rounding
  size_t same_inputs = 0, close = 0;
  const size_t n = f.gpu.color.pixels.size() / 3;
  for (size_t i = 0; i < n; ++i) {
    if (f.gpu.gbuffer.prim[i] != f.cpu.gbuffer.prim[i] || f.gpu.visibility[i] != f.cpu.visibility[i]) continue;
    ++same_inputs;
    bool ok = true;
    for (int c = 0; c < 3; ++c) ok &= std::abs(f.gpu.color.pixels[3 * i + c] - f.cpu.color.pixels[3 * i + c]) < 1e-4f;
    close += ok;
  }
  EXPECT_GT(same_inputs, n / 2);
  EXPECT_GE(close, same_inputs * 999 / 1000) << close << " of " << same_inputs;
}

TEST(Gpu, BuiltinBoxMatchesTheCpu) {
  FOVEAL_NEED_GPU();
  const Scene scene = make_builtin_scene("box");
  RenderParams p;
  p.width = 320;
  p.height = 200;
  p.foveation.max_rays = 64;
  p.gaze_px = glm::dvec2(100, 80);
  expect_matches_cpu(render_both(scene, scene.cameras.empty() ? default_camera(scene) : scene.cameras.front(), p));
}

TEST(Gpu, PaperSettingMatchesTheCpu) {
  FOVEAL_NEED_GPU();
  const std::string dragon = FOVEAL_DATA_DIR "/scenes/dragon/dragon.obj";
  if (!std::filesystem::exists(dragon)) GTEST_SKIP() << "skipped: " << dragon << " absent";
  const Scene scene = load_scene(FOVEAL_SOURCE_DIR "/scenes/dragon-box.json");
  RenderParams p;  // 840×525, n_max 400, γ 2
  p.gaze_px = glm::dvec2(418, 292);
  expect_matches_cpu(render_both(scene, find_camera(scene, "camera1"), p));
  p.mode = RenderMode::full;
  p.ambient_constant.reset();  // the `auto` constant from the fovea's mean visibility
  const Pair full = render_both(scene, find_camera(scene, "camera1"), p);
  expect_matches_cpu(full);
  EXPECT_NEAR(full.gpu.stats.ambient_constant, full.cpu.stats.ambient_constant, 1e-3);
}

TEST(Gpu, SchedulesAndRepeatsGiveTheSameImage) {
  FOVEAL_NEED_GPU();
  const Scene scene = make_builtin_scene("sphere-plane");
  const Camera camera = scene.cameras.empty() ? default_camera(scene) : scene.cameras.front();
  gpu::Renderer renderer(scene);
  RenderParams p;
  p.width = 300;
  p.height = 200;
  p.foveation.max_rays = 100;
  p.gaze_px = glm::dvec2(60, 150);
  const Frame a = renderer.render(camera, p);
  const Frame b = renderer.render(camera, p);
  renderer.set_ao_schedule(gpu::AoSchedule::per_pixel);
  const Frame c = renderer.render(camera, p);
  EXPECT_EQ(a.color.pixels, b.color.pixels);
  EXPECT_EQ(a.color.pixels, c.color.pixels);  // integer counts: the schedule cannot change a pixel
  EXPECT_EQ(a.visibility, c.visibility);
  // The fovea of a foveated frame is the full frame's, bit for bit
  p.mode = RenderMode::full;
  renderer.set_ao_schedule(gpu::AoSchedule::balanced);
  const Frame full = renderer.render(camera, p);
  size_t fovea = 0;
  for (size_t i = 0; i < a.maps.quality.size(); ++i)
    if (a.maps.quality[i] >= 1.0f) {
      ++fovea;
      EXPECT_EQ(std::memcmp(&a.color.pixels[3 * i], &full.color.pixels[3 * i], 3 * sizeof(float)), 0) << i;
    }
  EXPECT_GT(fovea, 100u);
  // A smaller frame after a larger one reuses the buffers correctly
  p.width = 64;
  p.height = 40;
  const Frame small = renderer.render(camera, p);
  EXPECT_EQ(small.color.width, 64);
  EXPECT_EQ(small.visibility.size(), 64u * 40u);
}

TEST(Gpu, RawTracingMatchesTheSharedTraversalOnTheCpu) {
  FOVEAL_NEED_GPU();
  const Scene scene = make_builtin_scene("box");
  gpu::Renderer renderer(scene);
  const Bvh& bvh = renderer.bvh();
  const BvhView view{bvh.nodes.data(), bvh.triangles.data()};
  std::mt19937 rng(7);
  std::uniform_real_distribution<float> u(-1, 1);
  const Bounds b = scene.bounds();
  std::vector<Ray> rays(20000);
  for (Ray& r : rays) {
    r.org = b.centre() + 0.4f * (b.hi - b.lo) * glm::vec3(u(rng), u(rng), u(rng));
    r.dir = glm::normalize(glm::vec3(u(rng), u(rng), u(rng)) + glm::vec3(0, 0, 1e-3f));
    r.tfar = u(rng) > 0 ? 1e30f : 0.3f * b.diagonal();
  }
  std::vector<Hit> hits(rays.size());
  std::vector<uint8_t> occluded(rays.size());
  renderer.intersect(rays, hits);
  renderer.occluded(rays, occluded);
  size_t same = 0, same_occ = 0;
  for (size_t i = 0; i < rays.size(); ++i) {
    Hit h;
    bvh_trace<false>(view, rays[i], &h);
    same += h.prim == hits[i].prim;
    same_occ += bvh_trace<true>(view, rays[i], nullptr) == (occluded[i] != 0);
  }
  EXPECT_GE(same, rays.size() * 9995 / 10000);
  EXPECT_GE(same_occ, rays.size() * 9995 / 10000);
  EXPECT_GT(renderer.measure_occlusion_rate(rays, 3), 0);
  EXPECT_GT(renderer.measure_intersection_rate(rays, 3), 0);
}

// ---- The second paper's passes ---------------------------------------------------------------

TEST(GpuDevice, VisionPassesRefusedWithoutAGpu) {
  if (availability().usable) GTEST_SKIP() << "skipped: a GPU is present";
  const Scene scene = make_builtin_scene("box");
  const Tracer tracer(scene);
  SimulateParams p;
  p.width = 64;
  p.height = 48;
  p.cuda = true;
  try {
    VisionSimulation sim(tracer, scene, p);
    ADD_FAILURE() << "a GPU simulation was made without a GPU";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find(availability().reason), std::string::npos) << e.what();
  }
}

// FAST on the GPU finds exactly cv::FAST's keypoints, with its scores, on the GPU's own image.
TEST(Gpu, VisionCornersAreOpenCvs) {
  FOVEAL_NEED_GPU();
  const Scene scene = make_builtin_scene("box");
  const SharpnessField field(scene.bounds(), default_voxel_size(scene.bounds()));
  gpu::VisionPasses passes(scene, field, {});
  const Camera camera = default_camera(scene);
  passes.trace(camera, 640, 480, 0.3f);
  const Image color = passes.color();
  const std::vector<uint8_t> grey = grey_8bit(color);
  const cv::Mat mat(color.height, color.width, CV_8UC1, const_cast<uint8_t*>(grey.data()));
  for (int threshold : {10, 20, 40}) {
    std::vector<cv::KeyPoint> expected;
    cv::FAST(mat, expected, threshold, true, cv::FastFeatureDetector::TYPE_9_16);
    const std::vector<Corner> got = passes.corners(threshold);
    ASSERT_GT(expected.size(), 20u) << threshold;
    std::multiset<std::tuple<float, float, float>> a, b;
    for (const Corner& c : got) a.insert({c.px.x - 0.5f, c.px.y - 0.5f, c.score});
    for (const cv::KeyPoint& k : expected) b.insert({k.pt.x, k.pt.y, k.response});
    EXPECT_EQ(a, b) << "threshold " << threshold;
    // and sorted by row, then column, as on the CPU
    EXPECT_TRUE(std::is_sorted(got.begin(), got.end(),
                               [](const Corner& l, const Corner& r) { return l.px.y != r.px.y ? l.px.y < r.px.y : l.px.x < r.px.x; }));
  }
}

// The GPU's blur of its own image with its own CoCs is the CPU's variable_blur of the same two,
// but for float rounding (fused multiply-adds).
TEST(Gpu, VisionBlurIsTheCpusOnTheSameInput) {
  FOVEAL_NEED_GPU();
  const Scene scene = make_builtin_scene("box");
  const Tracer tracer(scene);
  SimulateParams p;
  p.width = 320;
  p.height = 240;
  p.eye = parse_eye_preset("myopia:-2");
  p.cuda = true;
  VisionSimulation sim(tracer, scene, p);
  const Camera camera = default_camera(scene);
  for (int k = 0; k < 3; ++k) sim.step(camera);
  const Image cpu = variable_blur(sim.color(), sim.coc_px(), p.blur);
  const Image& gpu = sim.perceived();
  ASSERT_EQ(cpu.pixels.size(), gpu.pixels.size());
  double worst = 0;
  size_t blurred = 0;
  for (size_t i = 0; i < cpu.pixels.size(); ++i) worst = std::max(worst, double(std::abs(cpu.pixels[i] - gpu.pixels[i])));
  for (float c : sim.coc_px()) blurred += c > 2;
  EXPECT_LT(worst, 1e-4);
  EXPECT_GT(blurred, sim.coc_px().size() / 4);  // the test blurs something
}

// Whole steps: the same fixations (given), the same field (to the cells where float positions
// differ), the same blur, for a healthy, a glaucomatous and an astigmatic eye; and a GPU run
// repeats itself exactly.
TEST(Gpu, VisionStepsMatchTheCpu) {
  FOVEAL_NEED_GPU();
  const Scene scene = make_builtin_scene("box");
  const Tracer tracer(scene);
  const Camera camera = default_camera(scene);
  const std::vector<glm::vec2> fixations = {{160, 120}, {60, 80}, {250, 200}, {100, 190}, {200, 40}, {160, 120}};
  for (const char* eye : {"healthy", "glaucoma:0.7", "astigmatism:2@30+myopia:-1"}) {
    SimulateParams p;
    p.width = 320;
    p.height = 240;
    p.eye = parse_eye_preset(eye);
    p.blink_every = 4;
    VisionSimulation cpu(tracer, scene, p);
    p.cuda = true;
    VisionSimulation gpu(tracer, scene, p), again(tracer, scene, p);
    for (size_t k = 0; k < fixations.size(); ++k) {
      const StepStats a = cpu.step(camera, fixations[k]), b = gpu.step(camera, fixations[k]);
      again.step(camera, fixations[k]);
      EXPECT_EQ(a.blink, b.blink);
      EXPECT_NEAR(a.focus_vergence, b.focus_vergence, 1e-3) << eye << " step " << k;
      EXPECT_NEAR(a.sharp_fraction, b.sharp_fraction, 0.01) << eye << " step " << k;
      // CoCs: equal but where a pixel's cell or depth differs in the last bits
      const std::vector<float>& ca = cpu.coc_px();
      const std::vector<float>& cb = gpu.coc_px();
      size_t close = 0;
      for (size_t i = 0; i < ca.size(); ++i)
        close += (std::isinf(ca[i]) && std::isinf(cb[i])) || std::abs(ca[i] - cb[i]) <= 1e-3f * std::max(1.0f, std::abs(ca[i]));
      EXPECT_GE(double(close) / ca.size(), 0.99) << eye << " step " << k;
      double diff = 0;
      for (size_t i = 0; i < cpu.perceived().pixels.size(); ++i) diff += std::abs(cpu.perceived().pixels[i] - gpu.perceived().pixels[i]);
      EXPECT_LT(diff / cpu.perceived().pixels.size(), 2e-3) << eye << " step " << k;
      EXPECT_EQ(gpu.perceived().pixels, again.perceived().pixels) << eye << " step " << k;
    }
  }
}

// An impaired eye's passes on the GPU give the CPU's image (ImpairmentPasses::apply on the same
// input) for every kind of impairment and field-loss display, at a size whose glare grid divides
// the image and at one where it does not, and repeat themselves exactly.
TEST(Gpu, ImpairmentsAreTheCpusOnTheSameInput) {
  FOVEAL_NEED_GPU();
  const Scene scene = make_builtin_scene("box");
  const SharpnessField field(scene.bounds(), default_voxel_size(scene.bounds()));
  const Camera camera = default_camera(scene);
  for (auto [w, h] : {std::pair{640, 360}, {333, 250}}) {
    gpu::VisionPasses passes(scene, field, {});
    passes.trace(camera, w, h, 0.3f);
    passes.sharpness(CocModel{}, 1, false, 20.0f, 1.0f);  // no defocus: the blur leaves the image as traced
    for (const char* spec :
         {"cataract:0.5+field:arcuate:20+metamorphopsia:0.3+cvd:deutan:0.6", "presbyopia:70+field:central:5+field-mode:blur+cvd:protanopia",
          "field:constriction:15+field-mode:grey+achromatopsia", "cataract:0.8+field:arcuate:20+field-mode:fill+cvd:tritanopia",
          "metamorphopsia:1+cvd:tritan:0.4"}) {
      const ImpairmentPasses impair(parse_eye_spec(spec).impair);
      const CameraRetinotopy where(camera, w, h, glm::vec2(0.4f * w, 0.55f * h));
      passes.blur(0.0f);
      Image cpu = passes.perceived();
      const Image plain = cpu;
      impair.apply(cpu, expand(impair.needs_retinotopy() ? where.grid() : where.sizes()));
      const ImpairTimes t = passes.impair(impair, where);
      const Image gpu = passes.perceived();
      ASSERT_EQ(cpu.pixels.size(), gpu.pixels.size());
      double worst = 0, sum = 0, changed = 0;
      for (size_t i = 0; i < cpu.pixels.size(); ++i) {
        const double d = std::abs(double(cpu.pixels[i]) - gpu.pixels[i]);
        worst = std::max(worst, d);
        sum += d;
        changed += std::abs(double(cpu.pixels[i]) - plain.pixels[i]);
      }
      const double n = double(cpu.pixels.size());
      EXPECT_LT(worst, 1e-3) << spec << " at " << w << "x" << h;
      EXPECT_LT(sum / n, 1e-5) << spec << " at " << w << "x" << h;
      EXPECT_GT(changed / n, 0.001) << spec << ": the impairments change the image";
      EXPECT_GT(t.total_ms, 0.0) << spec;
      passes.blur(0.0f);
      passes.impair(impair, where);
      EXPECT_EQ(passes.perceived().pixels, gpu.pixels) << spec << ": a second run is the same image";
    }
  }
}

// Whole steps with an impaired eye: the GPU simulation's perceived image is the CPU's.
TEST(Gpu, ImpairedVisionStepsMatchTheCpu) {
  FOVEAL_NEED_GPU();
  const Scene scene = make_builtin_scene("box");
  const Tracer tracer(scene);
  const Camera camera = default_camera(scene);
  SimulateParams p;
  p.width = 320;
  p.height = 240;
  const EyeSpec spec = parse_eye_spec("cataract:0.5+field:arcuate:20+metamorphopsia:0.3+cvd:deutan:0.6");
  p.eye = spec.eye;
  p.impair = spec.impair;
  VisionSimulation cpu(tracer, scene, p);
  p.cuda = true;
  VisionSimulation gpu(tracer, scene, p);
  for (glm::vec2 fixation : {glm::vec2{160, 120}, glm::vec2{60, 80}, glm::vec2{250, 200}}) {
    const StepStats a = cpu.step(camera, fixation), b = gpu.step(camera, fixation);
    EXPECT_GT(b.impair.total_ms, 0.0);
    double diff = 0;
    for (size_t i = 0; i < cpu.perceived().pixels.size(); ++i) diff += std::abs(cpu.perceived().pixels[i] - gpu.perceived().pixels[i]);
    EXPECT_LT(diff / cpu.perceived().pixels.size(), 2e-3) << "fixation " << fixation.x << "," << fixation.y;
  }
}

}  // namespace
}  // namespace foveal
