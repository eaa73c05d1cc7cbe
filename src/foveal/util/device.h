// foveal/util/device.h — where the passes run: the CPU or the CUDA backend.
//
// Declared here, below every module, so that the renderer, the vision simulation, the drivers and
// the front ends choose a device without knowing the backend. availability() is implemented by
// the CUDA backend (cuda/gpu_renderer.cu) or, in a build without a CUDA toolkit, by its stub
// (cuda/gpu_stub.cpp), which says why there is none.
#pragma once

#include <string>

namespace foveal {

enum class ComputeDevice { cpu, cuda };
const char* to_string(ComputeDevice device);
// "auto" → cuda when a GPU is usable, else cpu; "cpu"; "cuda" → Error with the reason when it is
// unusable. Throws Error for any other name; errors name the parameter `device`.
ComputeDevice choose_device(const std::string& name);
// One line for the user: "cuda (NVIDIA H100 …)" or "cpu (no GPU: reason)".
std::string describe_device(ComputeDevice device);

// What the process can use, found once; never throws.
struct Availability {
  bool compiled = false;  // this build has the CUDA backend
  bool usable = false;    // and a GPU answered
  std::string reason;     // why not, when not usable
  std::string name;       // the GPU's name
  int compute_major = 0, compute_minor = 0;
  int multiprocessors = 0;
  double memory_gib = 0;
  std::string describe() const;  // "NVIDIA H100 80GB HBM3 (compute 9.0, 132 SMs, 79.1 GiB)" or the reason
};
const Availability& availability();

}  // namespace foveal
