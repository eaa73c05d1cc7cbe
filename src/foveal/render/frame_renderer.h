// foveal/render/frame_renderer.h — one renderer for every device.
//
// A FrameRenderer holds a scene ready to trace on one device (the CPU with Embree and oneTBB, or
// the CUDA backend), runs render_frame()'s passes for a camera and RenderParams, and keeps the
// temporal history that params.reuse.temporal frames build on. Every caller — render, replay,
// view, the quality sequences, the Python Renderer — renders through it and never branches on the
// device. The CUDA implementation lives in cuda/ (make_cuda_frame_renderer) and is reached only
// through make_frame_renderer(): no header of this module includes the backend.
#pragma once

#include "foveal/render/render.h"
#include "foveal/util/device.h"

#include <chrono>
#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <span>
#include <string>

namespace foveal {

// Which buffers a frame must bring back besides the colour and the stats. The CPU fills every
// buffer whatever is asked (they are its working memory); the GPU copies back only these.
struct FrameOutputs {
  bool visibility = true;  // Frame::visibility, and Frame::ao_traced with params.reuse
  bool maps = true;        // Frame::maps
  bool gbuffer = true;     // Frame::gbuffer
  static FrameOutputs colour_only() { return {false, false, false}; }
};

// How one frame is made, besides the camera and the params.
struct FrameOptions {
  FrameOutputs outputs;
  // The AO pass's finished fraction in (0, 1], from one thread at a time (the CPU reports it; a
  // GPU frame takes milliseconds and does not). It may throw to abandon the frame.
  std::function<void(double)> progress;
  // With params.reuse.temporal: build on the kept history and leave this frame's rays there.
  // false: a frame apart (a preview, a reference) that neither reads nor changes the history.
  bool use_history = true;
};

// AO rays that continue pixels' sequences: the real-time loop's unit of work (render/realtime.h).
// Pixel i's rays are those the AO pass would cast ([first, first + count) of its scrambled Sobol
// sequence), so rays added frame after frame are the paper's pixel's first rays in order.
struct AoRayTask {
  uint32_t pixel = 0;  // y·width + x
  uint32_t first = 0;  // index of the first ray in the pixel's sequence
  uint32_t count = 0;  // rays to cast
};
// The chunks of a batch that its call left behind rather than wait for
// (AoRayBatch::leave_behind_after_ms): still running on threads the machine had paused, their rays
// dropped. finish() — and the destructor — waits for them; until then the batch's tasks, outputs
// and surfaces must stay as they were.
struct AoBatchWork;  // the backend's (render.cpp)
class AoLeftBehind {
 public:
  AoLeftBehind();
  ~AoLeftBehind();
  AoLeftBehind(const AoLeftBehind&) = delete;
  AoLeftBehind& operator=(const AoLeftBehind&) = delete;
  struct Finished {
    uint32_t chunks = 0;                           // chunks that had been left behind (0: none, nothing waited for)
    std::chrono::steady_clock::time_point last{};  // when the last of them ended
  };
  // Wait for the chunks left behind, if any
  Finished finish();
  // Chunks left behind and not yet finished with
  uint32_t pending() const { return chunks_; }
  // The backend's: keep a batch's work with `chunks` left behind
  void hold(std::unique_ptr<AoBatchWork> work, uint32_t chunks);

 private:
  std::unique_ptr<AoBatchWork> work_;
  uint32_t chunks_ = 0;
};

struct AoRayBatch {
  const GBuffer* gbuffer = nullptr;  // the surfaces the rays leave from
  uint64_t gbuffer_version = 0;      // changes whenever *gbuffer does (a backend may keep a copy until then)
  float ao_distance = 0, epsilon = 0;
  uint64_t seed = 1;
  std::span<const AoRayTask> tasks;  // in priority order: a deadline leaves the tail undone
  std::span<uint32_t> blocked;       // out, per task: rays found blocked
  std::span<uint8_t> done;           // out, per task: 1 once its rays were traced
  // Asked before each chunk of tasks (the CPU's, about a thousand rays) or launch (the GPU's, about
  // two million rays; each launch is then waited for): true stops the batch there.
  std::function<bool()> expired;
  double slowdown = 1;  // tests only: each chunk takes this many times as long (a slower tracer)
  // The CPU: once the batch has expired (expired() said so), wait at most this long (ms) for the
  // chunks other threads are still tracing, then return without them; unset: wait for every chunk
  // taken. A chunk left behind is one whose thread the machine paused mid-chunk (another process
  // took its core): it ends in the background with its rays dropped (its tasks stay not done), held
  // in *left_behind, which must then be set. Waiting for such a thread made a frame late by the
  // length of its pause (docs/realtime.md, "A thread the machine pauses"). The GPU waits for its
  // launches and leaves nothing behind.
  std::optional<double> leave_behind_after_ms;
  AoLeftBehind* left_behind = nullptr;
  std::function<void()> chunk_hook;  // tests only: run by every chunk before its rays (a thread's pause)
};

class FrameRenderer {
 public:
  virtual ~FrameRenderer() = default;
  // One frame: render_frame()'s passes on this renderer's device.
  virtual Frame render(const Camera& camera, const RenderParams& params, const FrameOptions& options = {}) = 0;
  // Forget the temporal history: the next temporal frame is the paper's frame.
  virtual void reset_history() = 0;
  // Temporal frames stored since the last reset.
  virtual uint32_t history_frames() const = 0;
  // Trace a batch of AO rays; returns the rays traced (those of the tasks marked done).
  virtual uint64_t trace_ao_batch(const AoRayBatch& batch) = 0;
  // Make ready to trace batches from these surfaces (the same `version` as the batches'), so that
  // the first batch pays none of it: the GPU uploads them, sizes its buffers for a task per pixel
  // and loads its kernel. Nothing to do on the CPU.
  virtual void prepare_ao_batches(const GBuffer& /*surfaces*/, uint64_t /*version*/) {}
  // The view's surfaces alone (the G-buffer of a frame at width × height): what the real-time loop
  // traces when its camera moves. By default a frame without AO rays; the CPU and the GPU trace the
  // primary rays only (a frame's foveation maps, AO pass and shading were 40 of its 82 ms at 840×525
  // on the CPU; on the GPU a frame's copy-back was most of a view's cost).
  virtual GBuffer surfaces(const Camera& camera, int width, int height);
  // Rows from y0 of those surfaces, at least one and at most up to y1 (0 <= y0 < y1 <= height), as
  // a G-buffer of width × (rows returned): what the real-time loop traces a few rows at a time in
  // what its frames leave, when a camera at rest gets back its size. The CPU traces the rows asked
  // for; by default every row from y0 comes at once, from surfaces() (a device that traces a view's
  // surfaces within a frame). Throws Error for rows outside the view.
  virtual GBuffer surfaces_rows(const Camera& camera, int width, int height, int y0, int y1);
  // The device's raw occlusion rate on `rays` (rays per millisecond): Embree's stream API on the
  // CPU, the GPU's any-hit kernel over rays already on the device. The bound a ray budget is
  // judged against (`bench latency`'s ray bound).
  virtual double raw_occlusion_rays_per_ms(std::span<const Ray> rays) = 0;

  virtual ComputeDevice device() const = 0;
  // One line for the user: "cpu", or "cuda (NVIDIA H100 …)".
  std::string describe() const { return describe_device(device()); }
  virtual size_t triangles() const = 0;       // triangles traced
  virtual double build_ms() const = 0;        // the acceleration structure's build time
  virtual std::string trace_api() const = 0;  // how rays are traced: "stream", "packet8", "single" (Embree) or "bvh2" (the GPU)
};

// A renderer for the scene on `device`; throws Error with the reason when the CUDA backend is
// chosen and unavailable. The scene must outlive the renderer. On the CPU, `api` is how occlusion
// rays are handed to Embree.
std::unique_ptr<FrameRenderer> make_frame_renderer(const Scene& scene, ComputeDevice device, TraceApi api = TraceApi::stream);
// The same on the CPU over a tracer the caller already has (it must outlive the renderer); the
// CUDA backend builds its own BVH and ignores it.
std::unique_ptr<FrameRenderer> make_frame_renderer(const Scene& scene, ComputeDevice device, const Tracer& tracer);
// The CUDA backend's implementation (cuda/gpu_frame_renderer.cpp): the GPU's passes over the same
// per-pixel functions; throws Error with the reason when the backend is unavailable.
std::unique_ptr<FrameRenderer> make_cuda_frame_renderer(const Scene& scene);

}  // namespace foveal
