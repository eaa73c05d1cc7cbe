// foveal/ui/overlays.cpp — see overlays.h.
#include "foveal/ui/overlays.h"

#include "foveal/io/plot.h"
#include "foveal/util/error.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <sstream>

namespace foveal {

void paste(Rgba8& dst, const Rgba8& src, int x0, int y0) {
  for (int y = 0; y < src.height; ++y) {
    const int ty = y0 + y;
    if (ty < 0 || ty >= dst.height) continue;
    for (int x = 0; x < src.width; ++x) {
      const int tx = x0 + x;
      if (tx >= 0 && tx < dst.width) std::copy_n(src.at(x, y), 4, dst.at(tx, ty));
    }
  }
}

Overlays parse_overlays(const std::string& text) {
  Overlays o{false, false, false, false, false};
  if (text == "none" || text.empty()) return o;
  if (text == "all") return {true, true, true, true, true};
  std::stringstream in(text);
  std::string name;
  while (std::getline(in, name, ',')) {
    if (name == "gaze")
      o.gaze = true;
    else if (name == "contours")
      o.contours = true;
    else if (name == "budget")
      o.budget = true;
    else if (name == "scanpath")
      o.scanpath = true;
    else if (name == "sharp")
      o.sharp = true;
    else
      fail("overlays: unknown overlay '{}' (gaze, contours, budget, scanpath, sharp, all or none)", name);
  }
  return o;
}

std::string to_string(const Overlays& o) {
  std::string s;
  for (auto [on, name] :
       {std::pair{o.gaze, "gaze"}, {o.contours, "contours"}, {o.budget, "budget"}, {o.scanpath, "scanpath"}, {o.sharp, "sharp"}})
    if (on) {
      if (!s.empty()) s += ',';
      s += name;
    }
  return s.empty() ? "none" : s;
}

QualityGrid::QualityGrid(const FoveationModel& model, int width, int height, int step)
    : width_(width), height_(height), step_(std::max(1, step)) {
  nx_ = (width + step_ - 1) / step_ + 1;
  ny_ = (height + step_ - 1) / step_ + 1;
  q_.resize(static_cast<size_t>(nx_) * ny_);
  tbb::parallel_for(0, ny_, [&](int j) {
    for (int i = 0; i < nx_; ++i)
      q_[static_cast<size_t>(j) * nx_ + i] = static_cast<float>(model.evaluate_at(i * step_, j * step_).quality);
  });
}

float QualityGrid::quality(double x_px, double y_px) const {
  const double gx = std::clamp(x_px / step_, 0.0, nx_ - 1.0), gy = std::clamp(y_px / step_, 0.0, ny_ - 1.0);
  const int i = std::min(static_cast<int>(gx), nx_ - 2), j = std::min(static_cast<int>(gy), ny_ - 2);
  const float fx = static_cast<float>(gx - i), fy = static_cast<float>(gy - j);
  const float* r0 = &q_[static_cast<size_t>(j) * nx_ + i];
  const float* r1 = r0 + nx_;
  return (r0[0] * (1 - fx) + r0[1] * fx) * (1 - fy) + (r1[0] * (1 - fx) + r1[1] * fx) * fy;
}

void QualityGrid::fill(std::vector<float>& q) const {
  q.resize(static_cast<size_t>(width_) * height_);
  // Per column: grid cell and weight, once; per row: the two grid rows blended, once
  std::vector<int> cell(width_);
  std::vector<float> weight(width_);
  for (int x = 0; x < width_; ++x) {
    const double gx = std::clamp((x + 0.5) / step_, 0.0, nx_ - 1.0);
    cell[x] = std::min(static_cast<int>(gx), nx_ - 2);
    weight[x] = static_cast<float>(gx - cell[x]);
  }
  tbb::parallel_for(0, height_, [&](int y) {
    const double gy = std::clamp((y + 0.5) / step_, 0.0, ny_ - 1.0);
    const int j = std::min(static_cast<int>(gy), ny_ - 2);
    const float fy = static_cast<float>(gy - j);
    std::vector<float> row(nx_);
    for (int i = 0; i < nx_; ++i) row[i] = q_[static_cast<size_t>(j) * nx_ + i] * (1 - fy) + q_[static_cast<size_t>(j + 1) * nx_ + i] * fy;
    float* out = q.data() + static_cast<size_t>(y) * width_;
    for (int x = 0; x < width_; ++x) out[x] = row[cell[x]] * (1 - weight[x]) + row[cell[x] + 1] * weight[x];
  });
}

namespace {

struct Canvas {
  Rgba8& image;
  int x0, y0, width, height;
  // alpha in 1/256 steps (256 = opaque)
  void blend(int x, int y, glm::u8vec3 c, int alpha = 256) {
    if (x < 0 || y < 0 || x >= width || y >= height) return;
    uint8_t* p = image.at(x0 + x, y0 + y);
    for (int k = 0; k < 3; ++k) p[k] = static_cast<uint8_t>((p[k] * (256 - alpha) + c[k] * alpha + 128) >> 8);
  }
  void dot(double x, double y, int radius, glm::u8vec3 c) {
    const int cx = static_cast<int>(std::floor(x)), cy = static_cast<int>(std::floor(y));
    for (int dy = -radius; dy <= radius; ++dy)
      for (int dx = -radius; dx <= radius; ++dx)
        if (dx * dx + dy * dy <= radius * radius) blend(cx + dx, cy + dy, c);
  }
  void line(glm::dvec2 a, glm::dvec2 b, int radius, glm::u8vec3 c) {
    const double len = glm::length(b - a);
    const int n = std::max(1, static_cast<int>(std::ceil(len)));
    if (len > 4.0 * (width + height)) return;  // far off the image
    for (int i = 0; i <= n; ++i) {
      const glm::dvec2 p = glm::mix(a, b, static_cast<double>(i) / n);
      dot(p.x, p.y, radius, c);
    }
  }
  void ring(glm::dvec2 centre, double r, double thickness, glm::u8vec3 c) {
    const int reach = static_cast<int>(std::ceil(r + thickness));
    const int cx = static_cast<int>(std::floor(centre.x)), cy = static_cast<int>(std::floor(centre.y));
    for (int y = cy - reach; y <= cy + reach; ++y)
      for (int x = cx - reach; x <= cx + reach; ++x) {
        const double d = glm::length(glm::dvec2(x + 0.5, y + 0.5) - centre);
        if (std::abs(d - r) <= thickness * 0.5) blend(x, y, c);
      }
  }
};

}  // namespace

void draw_overlays(Rgba8& image, int x0, int y0, int width, int height, const Overlays& which, const OverlayInputs& in) {
  Canvas canvas{image, x0, y0, width, height};
  // Region tints first, lines on top
  if (which.sharp && in.coc_px && in.coc_px->size() == static_cast<size_t>(width) * height) {
    tbb::parallel_for(0, height, [&](int y) {
      for (int x = 0; x < width; ++x)
        if ((*in.coc_px)[static_cast<size_t>(y) * width + x] < in.sharp_px) canvas.blend(x, y, {40, 220, 60}, 102);
    });
  }
  if ((which.budget || which.contours) && in.model) {
    // q(E) per pixel, interpolated from the coarse grid, once for both overlays
    const QualityGrid grid(*in.model, width, height, 2);
    std::vector<float> q(static_cast<size_t>(width) * height);
    grid.fill(q);
    if (which.budget) {
      // n(E)/n_max → colour through a table over q (1024 steps), half transparent
      const FoveationParams& fp = in.model->params();
      std::array<glm::u8vec3, 1025> table;
      for (int i = 0; i <= 1024; ++i)
        table[i] = heat_colour(fp.max_rays > 0 ? static_cast<float>(ao_ray_budget(i / 1024.0, fp)) / fp.max_rays : 0.0f);
      tbb::parallel_for(0, height, [&](int y) {
        for (int x = 0; x < width; ++x)
          canvas.blend(x, y, table[static_cast<size_t>(std::lround(std::clamp(q[static_cast<size_t>(y) * width + x], 0.0f, 1.0f) * 1024))],
                       128);
      });
    }
    if (which.contours) {
      // A pixel is on the contour of level L where q − L changes sign towards its right or lower neighbour
      static const std::pair<float, glm::u8vec3> levels[3] = {{0.999f, {255, 235, 40}}, {0.5f, {255, 140, 0}}, {0.25f, {230, 30, 30}}};
      tbb::parallel_for(0, height, [&](int y) {
        for (int x = 0; x < width; ++x) {
          const size_t i = static_cast<size_t>(y) * width + x;
          const float right = x + 1 < width ? q[i + 1] : q[i], below = y + 1 < height ? q[i + width] : q[i];
          for (const auto& [level, colour] : levels) {
            const bool in0 = q[i] >= level;
            if (in0 != (right >= level) || in0 != (below >= level)) {
              canvas.blend(x, y, colour);
              if (x + 1 < width) canvas.blend(x + 1, y, colour);
            }
          }
        }
      });
    }
  }
  if (which.scanpath && !in.scanpath.empty()) {
    const glm::u8vec3 path{80, 200, 255};
    for (size_t i = 1; i < in.scanpath.size(); ++i) canvas.line(in.scanpath[i - 1], in.scanpath[i], 1, path);
    for (size_t i = 0; i < in.scanpath.size(); ++i)
      canvas.dot(in.scanpath[i].x, in.scanpath[i].y, i + 1 == in.scanpath.size() ? 5 : 3, path);
  }
  if (which.gaze) {
    if (in.fixation) {
      canvas.ring(*in.fixation, 12, 4, {0, 0, 0});
      canvas.ring(*in.fixation, 12, 2, {255, 255, 255});
    }
    if (in.gaze) {
      const int arm = std::max(4, std::min(width, height) / 40);
      for (int d = -arm; d <= arm; ++d)
        for (int t = -1; t <= 1; ++t) {
          const int gx = static_cast<int>(std::floor(in.gaze->x)), gy = static_cast<int>(std::floor(in.gaze->y));
          canvas.blend(gx + d, gy + d + t, {255, 0, 0});
          canvas.blend(gx + d, gy - d + t, {255, 0, 0});
        }
    }
  }
}

}  // namespace foveal
