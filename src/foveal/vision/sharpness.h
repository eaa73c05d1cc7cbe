// foveal/vision/sharpness.h — the sharpness field: what the eye has seen sharply, and when.
//
// A uniform voxel grid over the scene bounds. Each cell keeps the smallest CoC (visual angle,
// degrees) seen there and the step it was seen at. Cells starve: at step t the effective CoC is
// coc · (1 + s)^(t − stamp), evaluated lazily (no pass over the grid). A blink empties the field
// in O(1): each cell also records the epoch it was written in, and a blink starts a new epoch.
#pragma once

#include "foveal/scene/scene.h"
#include "foveal/util/hd.h"

#include <glm/glm.hpp>

#include <bit>
#include <cmath>
#include <cstdint>
#include <limits>
#include <vector>

#if !defined(__CUDA_ARCH__)
#include <atomic>
#endif

namespace foveal {

// The field as plain arrays in host or device memory: what one pixel reads and writes, written
// once for the CPU's class below and the GPU's kernels.
struct SharpnessFieldView {
  glm::vec3 origin{0};
  float voxel = 1;
  glm::ivec3 dims{0};
  float* coc = nullptr;
  uint32_t* stamp = nullptr;
  uint32_t* written = nullptr;    // epoch of the last write
  const float* growth = nullptr;  // (1 + s)^age for ages below growth_size
  uint32_t growth_size = 0;
  uint32_t epoch = 1;
  double log_growth = 0;  // log(1 + s)

  // Cell index of a point, or −1 outside the grid (and for NaN).
  FOVEAL_HD int64_t cell(glm::vec3 p) const {
    const glm::vec3 g = (p - origin) / voxel;
    if (!(g.x >= 0 && g.y >= 0 && g.z >= 0)) return -1;
    const glm::ivec3 c(g);
    if (c.x >= dims.x || c.y >= dims.y || c.z >= dims.z) return -1;
    return (int64_t(c.z) * dims.y + c.y) * dims.x + c.x;
  }
  // Effective (starved) CoC of a cell at step t; infinity if never seen in this epoch.
  FOVEAL_HD float effective(int64_t c, uint32_t step) const {
    if (c < 0 || written[c] != epoch) return std::numeric_limits<float>::infinity();
    const uint32_t age = step >= stamp[c] ? step - stamp[c] : 0;
    const float g = age < growth_size ? growth[age] : static_cast<float>(std::exp(log_growth * double(age)));
    return coc[c] * g;
  }
  // Keep `value` at step t if it is smaller than the cell's effective CoC; returns whether it was.
  FOVEAL_HD bool update(int64_t c, float value, uint32_t step) const {
    if (c < 0 || !(value < effective(c, step))) return false;
    coc[c] = value;
    stamp[c] = step;
    written[c] = epoch;
    return true;
  }
};

// One step's update of the field from every pixel at once, in any order (the GPU's threads; the
// CPU's loop updates in pixel order). Both keep, for each cell, the smallest of its pixels' CoCs
// when that is below the cell's effective CoC: every pixel offer()s its CoC, recording its cell's
// smallest CoC and first pixel with 64-bit atomic minima, then apply() lets that first pixel
// write the cell. A key is (~serial) << 32 | value, so a later step's keys lie below every earlier
// one's: the two arrays start all ones and are never cleared; `serial` counts the updating steps.
struct ConcurrentFieldUpdate {
  unsigned long long* cell_min = nullptr;    // per cell: the smallest CoC's bits this serial
  unsigned long long* cell_owner = nullptr;  // per cell: the first pixel this serial
  uint32_t serial = 1;

  FOVEAL_HD unsigned long long key(uint32_t low) const { return (static_cast<unsigned long long>(~serial) << 32) | low; }

  // Non-negative floats order as their bits; zero of either sign is 0, NaN lies above infinity
  // (never kept, as on the CPU).
  FOVEAL_HD static uint32_t order_bits(float v) { return v == 0.0f ? 0 : std::bit_cast<uint32_t>(v); }
  FOVEAL_HD static void atomic_min(unsigned long long* p, unsigned long long v) {
#if defined(__CUDA_ARCH__)
    atomicMin(p, v);
#else
    std::atomic_ref<unsigned long long> a(*p);
    unsigned long long now = a.load(std::memory_order_relaxed);
    while (v < now && !a.compare_exchange_weak(now, v, std::memory_order_relaxed)) {}
#endif
  }

  // Pass 1, every pixel: its cell (−1: none) and this step's CoC (≥ 0).
  FOVEAL_HD void offer(int64_t c, float coc, uint32_t pixel) const {
    if (c < 0) return;
    atomic_min(&cell_min[c], key(order_bits(coc)));
    atomic_min(&cell_owner[c], key(pixel));
  }
  // Pass 2, every pixel, after all of pass 1: the cell's first pixel updates it; whether it did.
  FOVEAL_HD bool apply(const SharpnessFieldView& field, int64_t c, uint32_t pixel, uint32_t step) const {
    if (c < 0 || cell_owner[c] != key(pixel)) return false;
    return field.update(c, std::bit_cast<float>(static_cast<uint32_t>(cell_min[c] & 0xffffffffULL)), step);
  }
};

// The starvation rate's rule (throws Error naming `starvation`): the field's, checked also where a
// simulation's settings are, before any field is built.
void validate_starvation(double starvation);

class SharpnessField {
 public:
  // `voxel` is the cell edge in scene units; the grid covers `bounds` (slightly padded).
  SharpnessField(const Bounds& bounds, float voxel, double starvation = 0.015);
  // Moves keep the arrays (and so the view's pointers); a copy would not.
  SharpnessField(SharpnessField&&) = default;
  SharpnessField& operator=(SharpnessField&&) = default;
  SharpnessField(const SharpnessField&) = delete;
  SharpnessField& operator=(const SharpnessField&) = delete;

  // Cell index of a point, or −1 outside the grid.
  int64_t cell(glm::vec3 p) const { return view_.cell(p); }
  // Effective (starved) CoC of a cell at step t; infinity if never seen in this epoch.
  float effective(int64_t cell, uint32_t step) const { return view_.effective(cell, step); }
  float effective(glm::vec3 p, uint32_t step) const { return view_.effective(view_.cell(p), step); }
  // Keep `coc` at step t if it is smaller than the cell's effective CoC; returns whether it was.
  bool update(int64_t cell, float coc, uint32_t step) { return view_.update(cell, coc, step); }
  // A blink: every cell becomes unseen.
  void blink() { ++view_.epoch; }
  // The arrays (a GPU copy of the field starts from them) and the growth table.
  const SharpnessFieldView& view() const { return view_; }
  const std::vector<float>& growth_table() const { return growth_; }

  glm::ivec3 dims() const { return view_.dims; }
  float voxel() const { return view_.voxel; }
  size_t cells() const { return coc_.size(); }
  double starvation() const { return starvation_; }

  static constexpr float kUnseen = std::numeric_limits<float>::infinity();

 private:
  double starvation_;
  SharpnessFieldView view_;  // points into the vectors below
  std::vector<float> coc_;
  std::vector<uint32_t> stamp_;
  std::vector<uint32_t> written_;  // epoch of the last write
  std::vector<float> growth_;      // (1 + s)^age for small ages
};

// A voxel edge for a scene: its bounding-box diagonal / `divisions` (default 256 along the diagonal),
// grown until the grid has at most `max_cells` cells.
float default_voxel_size(const Bounds& bounds, int divisions = 256, size_t max_cells = size_t(1) << 26);

}  // namespace foveal
