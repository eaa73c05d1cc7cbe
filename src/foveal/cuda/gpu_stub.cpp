// foveal/cuda/gpu_stub.cpp — the CUDA backend's interface in a build without a CUDA toolkit.
#include "foveal/cuda/gpu.h"

#include "foveal/util/error.h"

namespace foveal {

const Availability& availability() {
  static const Availability none = [] {
    Availability a;
    a.reason = FOVEAL_NO_CUDA_REASON;  // from the build's configuration (src/foveal/CMakeLists.txt)
    return a;
  }();
  return none;
}

std::string Availability::describe() const { return usable ? name : reason; }

}  // namespace foveal

namespace foveal::gpu {

const char* to_string(AoSchedule schedule) { return schedule == AoSchedule::balanced ? "balanced" : "per-pixel"; }

struct Renderer::Impl {};

Renderer::Renderer(const Scene&) { fail("device cuda: {}", availability().reason); }
Renderer::~Renderer() = default;
Frame Renderer::render(const Camera&, const RenderParams&, const FrameOutputs&) { fail("no CUDA backend"); }
const GpuPassTimes& Renderer::last_times() const { fail("no CUDA backend"); }
void Renderer::set_ao_schedule(AoSchedule) {}
void Renderer::reset_history() {}
uint32_t Renderer::history_frames() const { return 0; }
GBuffer Renderer::surfaces(const Camera&, int, int) { fail("no CUDA backend"); }
uint64_t Renderer::trace_ao_tasks(const AoRayBatch&) { fail("no CUDA backend"); }
void Renderer::prepare_ao_tasks(const GBuffer&, uint64_t) { fail("no CUDA backend"); }
AoSchedule Renderer::ao_schedule() const { return AoSchedule::balanced; }
const Bvh& Renderer::bvh() const { fail("no CUDA backend"); }
void Renderer::intersect(std::span<const Ray>, std::span<Hit>) { fail("no CUDA backend"); }
void Renderer::occluded(std::span<const Ray>, std::span<uint8_t>) { fail("no CUDA backend"); }
double Renderer::measure_occlusion_rate(std::span<const Ray>, int) { fail("no CUDA backend"); }
double Renderer::measure_intersection_rate(std::span<const Ray>, int) { fail("no CUDA backend"); }

struct VisionPasses::Impl {};

VisionPasses::VisionPasses(const Scene&, const SharpnessField&, const BlurParams&) { fail("device cuda: {}", availability().reason); }
VisionPasses::~VisionPasses() = default;
void VisionPasses::trace(const Camera&, int, int, float) { fail("no CUDA backend"); }
std::vector<Corner> VisionPasses::corners(int, bool) { fail("no CUDA backend"); }
float VisionPasses::depth_at(int, int, glm::vec3*) { fail("no CUDA backend"); }
void VisionPasses::blink() { fail("no CUDA backend"); }
size_t VisionPasses::sharpness(const CocModel&, uint32_t, bool, float, float) { fail("no CUDA backend"); }
void VisionPasses::blur(float) { fail("no CUDA backend"); }
ImpairTimes VisionPasses::impair(const ImpairmentPasses&, const CameraRetinotopy&) { fail("no CUDA backend"); }
Image VisionPasses::color() const { fail("no CUDA backend"); }
Image VisionPasses::perceived() const { fail("no CUDA backend"); }
std::vector<float> VisionPasses::coc_px() const { fail("no CUDA backend"); }
const VisionPassTimes& VisionPasses::last_times() const { fail("no CUDA backend"); }

}  // namespace foveal::gpu
