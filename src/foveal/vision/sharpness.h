// foveal/vision/sharpness.h — the sharpness field: what the eye has seen sharply, and when.
//
// A uniform voxel grid over the scene bounds. Each cell keeps the smallest CoC (visual angle,
// degrees) seen there and the step it was seen at. Cells starve: at step t the effective CoC is
// coc · (1 + s)^(t − stamp), evaluated lazily (no pass over the grid). A blink empties the field
// in O(1): each cell also records the epoch it was written in, and a blink starts a new epoch.
#pragma once

#include "foveal/scene/scene.h"

#include <glm/glm.hpp>

#include <cstdint>
#include <limits>
#include <vector>

namespace foveal {

class SharpnessField {
 public:
  // `voxel` is the cell edge in scene units; the grid covers `bounds` (slightly padded).
  SharpnessField(const Bounds& bounds, float voxel, double starvation = 0.015);

  // Cell index of a point, or −1 outside the grid.
  int64_t cell(glm::vec3 p) const;
  // Effective (starved) CoC of a cell at step t; infinity if never seen in this epoch.
  float effective(int64_t cell, uint32_t step) const;
  float effective(glm::vec3 p, uint32_t step) const;
  // Keep `coc` at step t if it is smaller than the cell's effective CoC; returns whether it was.
  bool update(int64_t cell, float coc, uint32_t step);
  // A blink: every cell becomes unseen.
  void blink() { ++epoch_; }

  glm::ivec3 dims() const { return dims_; }
  float voxel() const { return voxel_; }
  size_t cells() const { return coc_.size(); }
  double starvation() const { return starvation_; }

  static constexpr float kUnseen = std::numeric_limits<float>::infinity();

 private:
  glm::vec3 origin_;
  float voxel_;
  glm::ivec3 dims_;
  double starvation_;
  double log_growth_;
  uint32_t epoch_ = 1;
  std::vector<float> coc_;
  std::vector<uint32_t> stamp_;
  std::vector<uint32_t> written_;  // epoch of the last write
  std::vector<float> growth_;      // (1 + s)^age for small ages
};

// A voxel edge for a scene: its bounding-box diagonal / `divisions` (default 256 along the diagonal),
// grown until the grid has at most `max_cells` cells.
float default_voxel_size(const Bounds& bounds, int divisions = 256, size_t max_cells = size_t(1) << 26);

}  // namespace foveal
