#pragma once
// The real-time loop's sweeps (realtime.h): each pixel's priority bucket, kept between sweeps and
// computed again only where it may have changed, and the pixels sorted by it.
//
// A sweep orders every pixel for the periphery's rays (by the perceived variance its next rays
// remove) or for the rays ahead of the gaze (by eccentricity). A pixel's bucket depends on its own
// rays and its own foveation maps alone, so between two sweeps it changes only for the pixels
// that were traced and where the maps were evaluated again. Computed at every pixel, the buckets
// took 1.6–1.9 ms of a periphery sweep's 2.4–2.8 ms at 840×525 on two cores (bench latency, IRF S1,
// the dragon box), every frame while a view's periphery filled in; the sort took the rest, one
// thread's pass over every pixel twice, and now runs on all of them.
#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <vector>

#include <glm/glm.hpp>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

namespace foveal {

class SweepKeys {
 public:
  static constexpr int8_t kNone = -1;   // the pixel takes no part in the sweep (converged, no surface)
  static constexpr int8_t kStale = -2;  // to be computed again

  // n pixels, every bucket stale (the arrays' pages are touched here, not in a frame's sweep)
  void reset(size_t n) {
    key_.assign(n, kStale);
    wide_ = true;
  }
  size_t size() const { return key_.size(); }
  // Every bucket stale: new maps everywhere, a new view or size, rays kept from a view before
  void stale_all() {
    std::fill(key_.begin(), key_.end(), kStale);
    wide_ = true;
  }
  // Pixel i's rays changed
  void stale(size_t i) {
    if (i < key_.size()) key_[i] = kStale;
  }
  // The maps changed in the rectangle [box.x, box.z) × [box.y, box.w) of a width-wide image
  void stale_box(glm::ivec4 box, size_t width) {
    if (width == 0) return;
    const size_t height = key_.size() / width;
    for (int y = std::max(0, box.y); y < box.w && static_cast<size_t>(y) < height; ++y)
      for (int x = std::max(0, box.x); x < box.z && static_cast<size_t>(x) < width; ++x)
        key_[static_cast<size_t>(y) * width + static_cast<size_t>(x)] = kStale;
    wide_ = true;
  }
  // Whether the next sweep computes buckets over a wide area (everything, or a box of the maps'):
  // its cost is then a full sweep's, which the loop must fit before its deadline
  bool wide() const { return wide_; }

  // The stale buckets computed again by key(i) (a value in [kNone, Keys)), in parallel; then the
  // pixels with a bucket into `order` by bucket and, within one, in pixel order (a counting sort,
  // stable and the same whatever the thread count); returns how many.
  template <size_t Keys, class Key>
  size_t sweep(const Key& key, std::vector<uint32_t>& order) {
    static_assert(Keys <= 127);
    const size_t n = key_.size();
    tbb::parallel_for(tbb::blocked_range<size_t>(0, n, kBlock), [&](const tbb::blocked_range<size_t>& r) {
      for (size_t i = r.begin(); i != r.end(); ++i)
        if (key_[i] == kStale) key_[i] = static_cast<int8_t>(key(i));
    });
    wide_ = false;
    // Per block of kBlock pixels, how many in each bucket; then each (bucket, block)'s first place
    // in `order`, buckets first and blocks in order within one; then each block places its pixels
    const size_t blocks = (n + kBlock - 1) / kBlock;
    count_.assign(blocks * Keys, 0);
    tbb::parallel_for(tbb::blocked_range<size_t>(0, blocks, 1), [&](const tbb::blocked_range<size_t>& r) {
      for (size_t b = r.begin(); b != r.end(); ++b) {
        uint32_t* c = &count_[b * Keys];
        for (size_t i = b * kBlock, e = std::min(n, i + kBlock); i < e; ++i)
          if (key_[i] >= 0) ++c[static_cast<size_t>(key_[i])];
      }
    });
    uint32_t placed = 0;
    for (size_t k = 0; k < Keys; ++k)
      for (size_t b = 0; b < blocks; ++b) {
        const uint32_t c = count_[b * Keys + k];
        count_[b * Keys + k] = placed;
        placed += c;
      }
    order.resize(n);
    tbb::parallel_for(tbb::blocked_range<size_t>(0, blocks, 1), [&](const tbb::blocked_range<size_t>& r) {
      for (size_t b = r.begin(); b != r.end(); ++b) {
        uint32_t* next = &count_[b * Keys];
        for (size_t i = b * kBlock, e = std::min(n, i + kBlock); i < e; ++i)
          if (key_[i] >= 0) order[next[static_cast<size_t>(key_[i])]++] = static_cast<uint32_t>(i);
      }
    });
    return placed;
  }

  // Each pixel's bucket as of the latest sweep (kStale where it changed since; tests)
  const std::vector<int8_t>& keys() const { return key_; }

 private:
  static constexpr size_t kBlock = 16384;
  std::vector<int8_t> key_;
  std::vector<uint32_t> count_;
  bool wide_ = true;
};

}  // namespace foveal
