// Tests of the device-neutral FrameRenderer: the CPU's is render_frame() with its own history, bit
// for bit, and a frame apart leaves that history alone; the CUDA backend is refused with a reason
// where there is none.
#include "foveal/render/frame_renderer.h"

#include "foveal/render/reuse.h"
#include "foveal/util/error.h"
#include "test_scenes.h"

#include <gtest/gtest.h>

#include <tbb/task_arena.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <span>
#include <thread>

using namespace foveal;

namespace {

using foveal_test::same_bits;

void expect_same_frame(const Frame& a, const Frame& b, int k) {
  EXPECT_TRUE(same_bits(a.color.pixels, b.color.pixels)) << "frame " << k;
  EXPECT_TRUE(same_bits(a.visibility, b.visibility)) << "frame " << k;
  EXPECT_EQ(a.ao_traced, b.ao_traced) << "frame " << k;
  EXPECT_TRUE(same_bits(a.gbuffer.depth, b.gbuffer.depth)) << "frame " << k;
  EXPECT_EQ(a.maps.rays, b.maps.rays) << "frame " << k;
  EXPECT_EQ(a.stats.ao_rays, b.stats.ao_rays) << "frame " << k;
  EXPECT_EQ(a.stats.history_pixels, b.stats.history_pixels) << "frame " << k;
  EXPECT_EQ(a.stats.denoised_pixels, b.stats.denoised_pixels) << "frame " << k;
  EXPECT_EQ(a.stats.ambient_constant, b.stats.ambient_constant) << "frame " << k;
}

// A camera sliding sideways, so that the history is reprojected and partly dropped.
Camera moved(const Camera& c, int k) {
  Camera m = c;
  m.eye += glm::vec3(0.04f * k, 0.01f * k, 0.0f);
  return m;
}

// A batch of `tasks` from the surfaces `g` of `scene`, its results into `blocked` and `done`.
AoRayBatch task_batch(const Scene& scene, const GBuffer& g, std::span<const AoRayTask> tasks, std::vector<uint32_t>& blocked,
                      std::vector<uint8_t>& done, uint64_t seed = 1) {
  blocked.assign(tasks.size(), 0);
  done.assign(tasks.size(), 0);
  const Bounds bounds = scene.bounds();
  AoRayBatch batch;
  batch.gbuffer = &g;
  batch.gbuffer_version = 1;
  batch.ao_distance = resolve_ao_distance(scene, bounds, std::nullopt);
  batch.epsilon = surface_epsilon(bounds);
  batch.seed = seed;
  batch.tasks = tasks;
  batch.blocked = blocked;
  batch.done = done;
  return batch;
}
}  // namespace

// A temporal sequence with every option on, the gaze moving, through the renderer equals the same
// sequence through render_frame() with an AoHistory of the caller's: the refactor changes no output.
TEST(FrameRenderer, CpuIsRenderFrameWithItsHistoryBitForBit) {
  const Scene box = make_builtin_scene("box");
  const Tracer tracer(box);
  const std::unique_ptr<FrameRenderer> renderer = make_frame_renderer(box, ComputeDevice::cpu);
  EXPECT_EQ(renderer->device(), ComputeDevice::cpu);
  EXPECT_EQ(renderer->trace_api(), "stream");
  EXPECT_EQ(renderer->triangles(), tracer.triangles());
  EXPECT_EQ(renderer->describe().rfind("cpu", 0), 0u) << renderer->describe();
  RenderParams p;
  p.width = 96, p.height = 60, p.foveation.max_rays = 64;
  p.reuse.adaptive = p.reuse.denoise = p.reuse.temporal = true;
  AoHistory history;
  for (int k = 0; k < 4; ++k) {
    p.gaze_px = glm::dvec2(30 + 8 * k, 25);
    const Frame expected = render_frame(tracer, box, moved(box.cameras.front(), k), p, {}, &history);
    const Frame got = renderer->render(moved(box.cameras.front(), k), p);
    expect_same_frame(got, expected, k);
    if (k > 0) EXPECT_GT(got.stats.history_pixels, 0u);
  }
  EXPECT_EQ(renderer->history_frames(), 4u);
  // Reset: the next temporal frame is the paper's frame again
  renderer->reset_history();
  EXPECT_EQ(renderer->history_frames(), 0u);
  history.clear();
  const Frame first = renderer->render(box.cameras.front(), p);
  expect_same_frame(first, render_frame(tracer, box, box.cameras.front(), p, {}, &history), 0);
  EXPECT_EQ(first.stats.history_pixels, 0u);
}

// A frame apart (a preview, a reference) neither reads nor changes the history: the next frame is
// the one the sequence would have had without it. The renderer over a borrowed tracer is the same.
TEST(FrameRenderer, AFrameApartLeavesTheHistoryAlone) {
  const Scene box = make_builtin_scene("box");
  const Tracer tracer(box);
  const std::unique_ptr<FrameRenderer> plain = make_frame_renderer(box, ComputeDevice::cpu);
  const std::unique_ptr<FrameRenderer> borrowed = make_frame_renderer(box, ComputeDevice::cpu, tracer);
  RenderParams p;
  p.width = 80, p.height = 50, p.foveation.max_rays = 32, p.gaze_px = glm::dvec2(40, 25);
  p.reuse.temporal = true;
  const Camera c = box.cameras.front();
  plain->render(c, p);
  borrowed->render(c, p);
  FrameOptions apart;
  apart.use_history = false;
  int progress_calls = 0;
  apart.progress = [&](double fraction) {
    EXPECT_GT(fraction, 0.0);
    EXPECT_LE(fraction, 1.0);
    ++progress_calls;
  };
  RenderParams preview = p;
  preview.width = 20, preview.height = 12, preview.gaze_px = glm::dvec2(10, 6);
  const Frame small = borrowed->render(c, preview, apart);
  EXPECT_EQ(small.stats.history_pixels, 0u);  // it did not read the history either
  EXPECT_GT(progress_calls, 0);
  EXPECT_EQ(borrowed->history_frames(), 1u);
  const Frame a = plain->render(moved(c, 1), p), b = borrowed->render(moved(c, 1), p);
  expect_same_frame(b, a, 1);
  EXPECT_GT(b.stats.history_pixels, 0u);
}

// Without a usable GPU the CUDA backend is refused with the reason, through the same factory; with
// one, it reports its device.
// The view's surfaces alone (the real-time loop's base) are a frame's G-buffer, bit for bit.
TEST(FrameRenderer, SurfacesAreAFramesGBuffer) {
  const Scene& scene = foveal_test::box();
  const std::unique_ptr<FrameRenderer> renderer = make_frame_renderer(scene, ComputeDevice::cpu);
  RenderParams p;
  p.width = 96;
  p.height = 60;
  p.foveation.max_rays = 4;
  const Camera camera = moved(scene.cameras.front(), 3);
  const Frame f = renderer->render(camera, p, {});
  const GBuffer g = renderer->surfaces(camera, p.width, p.height);
  EXPECT_EQ(g.width, 96);
  EXPECT_EQ(g.height, 60);
  EXPECT_EQ(g.prim, f.gbuffer.prim);
  EXPECT_TRUE(same_bits(g.depth, f.gbuffer.depth));
  auto flat = [](const std::vector<glm::vec3>& v) { return std::vector<float>(&v.front().x, &v.front().x + 3 * v.size()); };
  for (auto member : {&GBuffer::position, &GBuffer::normal, &GBuffer::geo_normal, &GBuffer::albedo, &GBuffer::view})
    EXPECT_TRUE(same_bits(flat(g.*member), flat(f.gbuffer.*member)));
  size_t hits = 0;
  for (size_t i = 0; i < g.prim.size(); ++i) hits += g.hit(i) ? 1 : 0;
  EXPECT_GT(hits, g.prim.size() / 2);
  // The default, which other devices use (a frame without AO rays), gives the same surfaces
  const GBuffer base = renderer->FrameRenderer::surfaces(camera, p.width, p.height);
  EXPECT_EQ(base.prim, g.prim);
  EXPECT_TRUE(same_bits(base.depth, g.depth));
  EXPECT_TRUE(same_bits(flat(base.position), flat(g.position)));
}

TEST(FrameRenderer, SurfacesInRowsAreTheViewsSurfaces) {
  const Scene& scene = foveal_test::box();
  const std::unique_ptr<FrameRenderer> renderer = make_frame_renderer(scene, ComputeDevice::cpu);
  const Camera camera = moved(scene.cameras.front(), 2);
  const GBuffer whole = renderer->surfaces(camera, 96, 61);
  auto flat = [](const std::vector<glm::vec3>& v) { return std::vector<float>(&v.front().x, &v.front().x + 3 * v.size()); };
  // Rows in uneven steps, appended, are the view's surfaces to the bit: on the CPU (the rows
  // asked for) and by the default other devices use (every row from the first asked for)
  for (const bool base : {false, true}) {
    GBuffer g;
    for (int y = 0; y < 61;) {
      const int y1 = std::min(61, y + 1 + y % 7);
      const GBuffer part =
          base ? renderer->FrameRenderer::surfaces_rows(camera, 96, 61, y, y1) : renderer->surfaces_rows(camera, 96, 61, y, y1);
      ASSERT_EQ(part.width, 96);
      ASSERT_GE(part.height, 1);
      ASSERT_LE(y + part.height, 61);
      if (!base) EXPECT_EQ(part.height, y1 - y);
      ASSERT_EQ(part.prim.size(), static_cast<size_t>(96 * part.height));
      g.prim.insert(g.prim.end(), part.prim.begin(), part.prim.end());
      g.depth.insert(g.depth.end(), part.depth.begin(), part.depth.end());
      for (auto member : {&GBuffer::position, &GBuffer::normal, &GBuffer::geo_normal, &GBuffer::albedo, &GBuffer::view})
        (g.*member).insert((g.*member).end(), (part.*member).begin(), (part.*member).end());
      y += part.height;
    }
    EXPECT_EQ(g.prim, whole.prim) << (base ? "default" : "cpu");
    EXPECT_TRUE(same_bits(g.depth, whole.depth));
    for (auto member : {&GBuffer::position, &GBuffer::normal, &GBuffer::geo_normal, &GBuffer::albedo, &GBuffer::view})
      EXPECT_TRUE(same_bits(flat(g.*member), flat(whole.*member)));
  }
  for (const auto& [y0, y1] : {std::pair{-1, 3}, std::pair{5, 5}, std::pair{60, 62}}) {
    EXPECT_THROW(renderer->surfaces_rows(camera, 96, 61, y0, y1), Error);
    EXPECT_THROW(renderer->FrameRenderer::surfaces_rows(camera, 96, 61, y0, y1), Error);
  }
}

TEST(FrameRenderer, CudaIsRefusedWithTheReasonWhereThereIsNone) {
  const Scene box = make_builtin_scene("box");
  if (availability().usable) {
    const std::unique_ptr<FrameRenderer> gpu = make_frame_renderer(box, ComputeDevice::cuda);
    EXPECT_EQ(gpu->device(), ComputeDevice::cuda);
    EXPECT_EQ(gpu->trace_api(), "bvh2");
    EXPECT_NE(gpu->describe().find(availability().name), std::string::npos);
    return;
  }
  try {
    make_frame_renderer(box, ComputeDevice::cuda);
    FAIL() << "a CUDA renderer was made without a usable GPU";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find(availability().reason), std::string::npos) << e.what();
  }
}

// The GPU's AO tasks (the real-time loop's rays) are the CPU's: on the same surfaces, each pixel's
// rays from the same place in its sequence are blocked alike, but for a ray that grazes an edge,
// where Embree's traversal and the GPU's BVH2 can part. Skipped without a GPU.
TEST(FrameRenderer, GpuAoTasksAreTheCpus) {
  if (!availability().usable) GTEST_SKIP() << "skipped: " << availability().reason;
  const Scene& scene = foveal_test::sphere_plane();
  const std::unique_ptr<FrameRenderer> cpu = make_frame_renderer(scene, ComputeDevice::cpu);
  const std::unique_ptr<FrameRenderer> gpu = make_frame_renderer(scene, ComputeDevice::cuda);
  const GBuffer g = cpu->surfaces(scene.cameras.front(), 200, 125);
  std::vector<AoRayTask> tasks;
  for (uint32_t i = 0; i < g.prim.size(); ++i)
    if (g.hit(i)) tasks.push_back({i, 5 + i % 7, 24});
  ASSERT_GT(tasks.size(), 10000u);
  std::vector<uint32_t> blocked[2];
  uint64_t traced[2] = {};
  for (int d = 0; d < 2; ++d) {
    std::vector<uint8_t> done;
    traced[d] = (d == 0 ? *cpu : *gpu).trace_ao_batch(task_batch(scene, g, tasks, blocked[d], done, 7));
    EXPECT_EQ(std::count(done.begin(), done.end(), uint8_t{1}), static_cast<std::ptrdiff_t>(tasks.size()));
  }
  EXPECT_EQ(traced[0], traced[1]);
  EXPECT_EQ(traced[0], tasks.size() * 24);
  size_t same = 0;
  uint64_t total[2] = {};
  for (size_t t = 0; t < tasks.size(); ++t) {
    same += blocked[0][t] == blocked[1][t] ? 1 : 0;
    total[0] += blocked[0][t];
    total[1] += blocked[1][t];
  }
  EXPECT_GT(total[0], traced[0] / 20);  // the sphere does block rays
  EXPECT_GE(same, tasks.size() * 99 / 100);
  EXPECT_NEAR(static_cast<double>(total[1]), static_cast<double>(total[0]), 1e-3 * static_cast<double>(total[0]));
  // A batch on the same surfaces again reuses what the GPU kept of them, with the same result
  std::vector<uint32_t> again;
  std::vector<uint8_t> done;
  gpu->trace_ao_batch(task_batch(scene, g, tasks, again, done, 7));
  EXPECT_EQ(again, blocked[1]);
}

// A view's surfaces on the GPU come by their own path (the primary rays alone, copied back through
// page-locked memory): its frame's G-buffer to the bit, the CPU's but where a ray grazes an edge,
// and their rows the rows of the whole. Skipped without a GPU.
TEST(FrameRenderer, GpuSurfacesAreItsFramesGBuffer) {
  if (!availability().usable) GTEST_SKIP() << "skipped: " << availability().reason;
  const Scene& scene = foveal_test::sphere_plane();
  const std::unique_ptr<FrameRenderer> cpu = make_frame_renderer(scene, ComputeDevice::cpu);
  const std::unique_ptr<FrameRenderer> gpu = make_frame_renderer(scene, ComputeDevice::cuda);
  const Camera& camera = scene.cameras.front();
  const int w = 203, h = 127;  // blocks that the image does not fill
  const size_t n = static_cast<size_t>(w) * h;
  for (int round = 0; round < 2; ++round) {  // the second reuses the first's buffers
    const GBuffer s = gpu->surfaces(camera, w, h);
    const GBuffer f = gpu->FrameRenderer::surfaces(camera, w, h);  // the default: a frame without AO rays
    EXPECT_EQ(s.width, w);
    EXPECT_EQ(s.height, h);
    ASSERT_EQ(s.prim.size(), n);
    EXPECT_EQ(s.prim, f.prim);
    EXPECT_TRUE(foveal_test::same_bits(s.depth, f.depth));
    EXPECT_EQ(s.position, f.position);
    EXPECT_EQ(s.normal, f.normal);
    EXPECT_EQ(s.geo_normal, f.geo_normal);
    EXPECT_EQ(s.albedo, f.albedo);
    EXPECT_EQ(s.view, f.view);
  }
  const GBuffer s = gpu->surfaces(camera, w, h);
  const GBuffer c = cpu->surfaces(camera, w, h);
  size_t hits = 0, same = 0, close = 0;
  for (size_t i = 0; i < n; ++i) {
    hits += c.hit(i) ? 1 : 0;
    same += c.hit(i) == s.hit(i) ? 1 : 0;
    close += c.hit(i) && s.hit(i) && glm::length(c.position[i] - s.position[i]) < 1e-3f ? 1 : 0;
  }
  EXPECT_GT(hits, n / 4);
  EXPECT_GE(same, n * 995 / 1000);
  EXPECT_GE(close, hits * 99 / 100);
  const GBuffer rows = gpu->surfaces_rows(camera, w, h, 40, h);
  EXPECT_EQ(rows.height, h - 40);
  EXPECT_EQ(rows.prim, std::vector<uint32_t>(s.prim.begin() + 40 * w, s.prim.end()));
  EXPECT_EQ(rows.position, std::vector<glm::vec3>(s.position.begin() + 40 * w, s.position.end()));
  EXPECT_THROW(gpu->surfaces(camera, 0, h), Error);
}

// The raw occlusion rate each device reports for the ray bound is a rate: positive and finite.
TEST(FrameRenderer, RawOcclusionRateIsMeasuredOnItsDevice) {
  const Scene& scene = foveal_test::sphere_plane();
  std::vector<Ray> rays;
  for (int i = 0; i < 4096; ++i) {
    Ray r;
    r.org = glm::vec3(-4.0f + 8.0f * (i % 64) / 64.0f, 0.01f, -4.0f + 8.0f * (i / 64) / 64.0f);
    r.dir = glm::normalize(glm::vec3(0.1f, 1.0f, 0.05f));
    r.tfar = 100.0f;
    rays.push_back(r);
  }
  for (const ComputeDevice device : {ComputeDevice::cpu, ComputeDevice::cuda}) {
    if (device == ComputeDevice::cuda && !availability().usable) continue;
    const double rate = make_frame_renderer(scene, device)->raw_occlusion_rays_per_ms(rays);
    EXPECT_GT(rate, 0.0) << to_string(device);
    EXPECT_TRUE(std::isfinite(rate)) << to_string(device);
  }
}

// A batch asked to stop (its deadline passed after the first chunk or launch) traces part of its
// tasks, with the results a whole batch gives them, and says which and how many rays: on the CPU
// whole chunks of about a thousand rays (taken by the threads in turn), on the GPU a prefix of its
// tasks, launches of about two million rays in the tasks' order.
TEST(FrameRenderer, ABatchStopsAtItsDeadlineWithAPrefixOfItsTasks) {
  const Scene& scene = foveal_test::sphere_plane();
  const std::unique_ptr<FrameRenderer> cpu = make_frame_renderer(scene, ComputeDevice::cpu);
  const GBuffer g = cpu->surfaces(scene.cameras.front(), 200, 125);
  std::vector<AoRayTask> tasks;
  for (uint32_t i = 0; i < g.prim.size(); ++i) tasks.push_back({i, 0, 400});  // misses among them: no rays
  for (const ComputeDevice device : {ComputeDevice::cpu, ComputeDevice::cuda}) {
    if (device == ComputeDevice::cuda && !availability().usable) continue;
    const std::unique_ptr<FrameRenderer> renderer = make_frame_renderer(scene, device);
    auto run = [&](bool stop, std::vector<uint32_t>& blocked, std::vector<uint8_t>& done) {
      AoRayBatch batch = task_batch(scene, g, tasks, blocked, done);
      std::atomic<int> asked{0};
      if (stop) batch.expired = [&] { return ++asked > 1; };
      return renderer->trace_ao_batch(batch);
    };
    std::vector<uint32_t> whole_blocked, part_blocked;
    std::vector<uint8_t> whole_done, part_done;
    const uint64_t whole = run(false, whole_blocked, whole_done);
    const uint64_t part = run(true, part_blocked, part_done);
    const auto n_done = static_cast<size_t>(std::count(part_done.begin(), part_done.end(), uint8_t{1}));
    EXPECT_EQ(std::count(whole_done.begin(), whole_done.end(), uint8_t{1}), static_cast<std::ptrdiff_t>(tasks.size())) << to_string(device);
    EXPECT_GT(n_done, 0u) << to_string(device);
    EXPECT_LT(n_done, tasks.size()) << to_string(device);
    EXPECT_LT(part, whole) << to_string(device);
    uint64_t rays = 0;
    for (size_t t = 0; t < tasks.size(); ++t) {
      if (device == ComputeDevice::cuda) EXPECT_EQ(part_done[t], t < n_done ? 1 : 0) << "task " << t;  // a prefix
      if (part_done[t]) {
        EXPECT_EQ(part_blocked[t], whole_blocked[t]) << to_string(device) << " task " << t;
        rays += g.hit(tasks[t].pixel) ? tasks[t].count : 0;
      }
    }
    EXPECT_EQ(part, rays) << to_string(device);
  }
}

// A thread the machine pauses mid-chunk (another process took its core) does not hold a batch that
// may leave it behind: the call returns once the batch has expired and the other threads' chunks
// are done, that chunk's rays dropped (its tasks not done, nothing written after the call), the
// rest as a whole batch gives them; finishing waits for it. A batch that may not leave it waits for
// the whole pause.
TEST(FrameRenderer, AChunkOfAPausedThreadIsLeftBehindOnceTheBatchHasExpired) {
  const Scene& scene = foveal_test::sphere_plane();
  const std::unique_ptr<FrameRenderer> cpu = make_frame_renderer(scene, ComputeDevice::cpu);
  const GBuffer g = cpu->surfaces(scene.cameras.front(), 200, 125);
  std::vector<AoRayTask> tasks;
  for (uint32_t i = 0; i < g.prim.size(); ++i) tasks.push_back({i, 0, 400});  // ~10 million rays: far more than the deadline allows
  std::vector<uint32_t> whole_blocked;
  std::vector<uint8_t> whole_done;
  cpu->trace_ao_batch(task_batch(scene, g, tasks, whole_blocked, whole_done));
  using clock = std::chrono::steady_clock;
  constexpr auto kPause = std::chrono::milliseconds(400);
  tbb::task_arena arena(2);  // the caller and one more thread
  for (const bool leave : {true, false}) {
    std::vector<uint32_t> blocked;
    std::vector<uint8_t> done;
    AoRayBatch batch = task_batch(scene, g, tasks, blocked, done);
    AoLeftBehind left;
    const auto caller = std::this_thread::get_id();
    std::atomic<bool> paused{false};
    std::atomic<clock::time_point> pause_start{};
    // The first chunk of the other thread pauses; the batch expires 10 ms later (however long that
    // thread took to start: on a busy machine, longer than a fixed deadline once allowed)
    batch.chunk_hook = [&] {
      if (std::this_thread::get_id() != caller && !paused.exchange(true)) {
        pause_start = clock::now();
        std::this_thread::sleep_for(kPause);
      }
    };
    batch.expired = [&] { return paused && clock::now() - pause_start.load() >= std::chrono::milliseconds(10); };
    if (leave) {
      batch.leave_behind_after_ms = 0.25;
      batch.left_behind = &left;
    }
    uint64_t traced = 0;
    arena.execute([&] { traced = cpu->trace_ao_batch(batch); });
    const auto returned = clock::now();
    if (!paused) GTEST_SKIP() << "skipped: no second thread took a chunk (a single core?)";
    const std::vector<uint32_t> blocked_then = blocked;
    const std::vector<uint8_t> done_then = done;
    if (!leave) {  // waited for the paused thread
      EXPECT_GE(returned - pause_start.load(), kPause);
      EXPECT_EQ(left.pending(), 0u);
      continue;
    }
    EXPECT_LT(returned - pause_start.load(), kPause / 2);
    EXPECT_EQ(left.pending(), 1u);
    const AoLeftBehind::Finished f = left.finish();
    EXPECT_EQ(f.chunks, 1u);
    EXPECT_GT(f.last, returned);  // it ended after the call had returned …
    EXPECT_EQ(left.pending(), 0u);
    EXPECT_EQ(blocked, blocked_then);  // … and wrote nothing
    EXPECT_EQ(done, done_then);
    const auto n_done = static_cast<size_t>(std::count(done.begin(), done.end(), uint8_t{1}));
    EXPECT_GT(n_done, 0u);
    EXPECT_LT(n_done, tasks.size());
    uint64_t rays = 0;
    for (size_t t = 0; t < tasks.size(); ++t)
      if (done[t]) {
        EXPECT_EQ(blocked[t], whole_blocked[t]) << "task " << t;
        rays += g.hit(tasks[t].pixel) ? tasks[t].count : 0;
      }
    EXPECT_EQ(traced, rays);
  }
}
