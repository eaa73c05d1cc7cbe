// foveal/cuda/gpu_common.cpp — choosing the device (util/device.h); the same with and without the CUDA backend.
#include "foveal/util/device.h"

#include "foveal/util/error.h"

namespace foveal {

const char* to_string(ComputeDevice device) { return device == ComputeDevice::cuda ? "cuda" : "cpu"; }

ComputeDevice choose_device(const std::string& name) {
  if (name == "cpu") return ComputeDevice::cpu;
  if (name == "auto") return availability().usable ? ComputeDevice::cuda : ComputeDevice::cpu;
  if (name == "cuda") {
    if (!availability().usable) fail("device cuda: unavailable: {}", availability().reason);
    return ComputeDevice::cuda;
  }
  fail("device: unknown device '{}' (known: auto, cpu, cuda)", name);
}

std::string describe_device(ComputeDevice device) {
  const Availability& a = availability();
  if (device == ComputeDevice::cuda) return "cuda (" + a.describe() + ")";
  return a.usable ? "cpu" : "cpu (no GPU: " + a.reason + ")";
}

}  // namespace foveal
