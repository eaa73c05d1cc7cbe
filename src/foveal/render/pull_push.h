// foveal/render/pull_push.h — a field known at scattered pixels, estimated everywhere else.
//
// The real-time loop shows, for a pixel that will get AO rays but has none yet (a fresh view's
// periphery, a fresh fovea), an estimate of its visibility from the pixels around it that have
// rays. Pull-push (Gortler, Grzeszczuk, Szeliski & Cohen 1996, "The Lumigraph", SIGGRAPH, §3.4):
// the known values and their coverage are averaged down a pyramid of halved resolutions, a cell
// counting as known once its children together cover it (pull), then each level, from the
// coarsest, keeps its own mean where its cell is known and takes the coarser level's, upsampled
// bilinearly, where it is not — in proportion to its weight (push). An unknown pixel thus takes
// the mean of the known pixels nearest it, blended smoothly across scales: no edge where the
// known region ends. Every estimate is a weighted mean of known values. The upsampling is
// OpenCV's (cv::resize, INTER_LINEAR); what is written here is the masked pyramid, which no
// library call does.
#pragma once

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cstddef>
#include <utility>
#include <vector>

namespace foveal {

class PullPush {
 public:
  // Pull: the pyramid of a width×height field, `at(i)` giving pixel i's (known, value). Keeps its
  // memory between calls (none fresh for the same size).
  template <class At>
  void pull(int width, int height, const At& at);
  // The same pull in parts, a few rows a step (the real-time loop's view built over frames): after
  // prepare(width, height), the first level's rows [y0, y1) of first_rows(height) (each from two
  // rows of pixels), in any order; then, once every row is pulled, the coarser levels
  template <class At>
  void pull_rows(int width, int height, const At& at, int y0, int y1);
  void pull_levels();
  static int first_rows(int height) { return (height + 1) / 2; }
  // The memory of a width×height field's pyramid, written (so that its pages are touched) before
  // a pull needs it; a field no larger than one before costs nothing
  void prepare(int width, int height);
  // Push: every pixel's estimate, from the coarsest level down (the last, to the pixels, is
  // OpenCV's bilinear upsampling). False, and no estimate, where no pixel is known.
  bool push();
  // Pixel i's estimate after a push() that found a known pixel (at a known pixel: its own cell's
  // mean, not necessarily its value)
  float estimate(size_t i) const { return pixels_[i]; }

 private:
  struct Size {
    int width, height;
  };
  // One level of the pull from the level below, `in(i)` its cells' weight × value and weight: its
  // cell rows [y0, y1)
  template <class In>
  static void pull_level(int in_width, int in_height, const In& in, Size out, float* sum, float* cover, int y0, int y1);

  Size pixels_size_{0, 0};
  std::vector<Size> sizes_;  // the levels from the first halving (rounded up) to a single cell
  // Per level: the cell's weight times the mean of its known values, its weight (the coverage of
  // its children, at most 1), and the estimate; then the pixels' estimates
  std::vector<std::vector<float>> sum_, cover_, estimate_;
  std::vector<float> pixels_;
};

template <class In>
void PullPush::pull_level(int in_width, int in_height, const In& in, Size out, float* sum, float* cover, int y0, int y1) {
  // Each cell: the means over its 2×2 children (fewer at an odd edge), clamped — a cell is as
  // covered as its children together, at most fully (Gortler et al.'s clamp): one known child of
  // four makes it known, with that child's value, so that an estimate comes from the finest level
  // that has known pixels near it rather than from a mean diluted over coarser ones. (By hand
  // rather than cv::resize's INTER_AREA, whose odd sizes take a general path fifteen times slower.)
  tbb::parallel_for(tbb::blocked_range<int>(y0, y1, 16), [&](const tbb::blocked_range<int>& rows) {
    for (int by = rows.begin(); by != rows.end(); ++by)
      for (int bx = 0; bx < out.width; ++bx) {
        float s = 0, c = 0;
        for (int y = 2 * by; y < std::min(in_height, 2 * by + 2); ++y)
          for (int x = 2 * bx; x < std::min(in_width, 2 * bx + 2); ++x) {
            const auto [cs, cc] = in(static_cast<size_t>(y) * static_cast<size_t>(in_width) + static_cast<size_t>(x));
            s += cs;
            c += cc;
          }
        const float w = std::min(1.0f, c);
        const size_t cell = static_cast<size_t>(by) * static_cast<size_t>(out.width) + static_cast<size_t>(bx);
        sum[cell] = c > 0 ? w * (s / c) : 0.0f;
        cover[cell] = w;
      }
  });
}

template <class At>
void PullPush::pull(int width, int height, const At& at) {
  prepare(width, height);
  pull_rows(width, height, at, 0, first_rows(height));
  pull_levels();
}

template <class At>
void PullPush::pull_rows(int width, int height, const At& at, int y0, int y1) {
  // The first level from the pixels
  pull_level(
      width, height,
      [&](size_t i) {
        const auto [known, value] = at(i);
        return std::pair{known ? value : 0.0f, known ? 1.0f : 0.0f};
      },
      sizes_[0], sum_[0].data(), cover_[0].data(), y0, y1);
}

}  // namespace foveal
