// foveal/util/sampling.h — hashing, scrambled Sobol points and hemisphere mapping.
//
// Every random choice in foveal is a pure function of (seed, pixel, sample index), so an
// image does not depend on the thread count or on the order in which tiles run.
#pragma once

#include "foveal/util/hd.h"

#include <glm/glm.hpp>

#include <bit>
#include <cmath>
#include <cstdint>
#include <numbers>

namespace foveal {

// 32-bit integer hash with good avalanche (lowbias32, C. Wellons).
FOVEAL_HD constexpr uint32_t hash32(uint32_t x) {
  x ^= x >> 16;
  x *= 0x7feb352dU;
  x ^= x >> 15;
  x *= 0x846ca68bU;
  x ^= x >> 16;
  return x;
}

// Hash of several words, order-sensitive.
FOVEAL_HD constexpr uint32_t hash_combine(uint32_t seed, uint32_t value) {
  return hash32(seed ^ (value + 0x9e3779b9U + (seed << 6) + (seed >> 2)));
}

// Seed of one pixel: the same for a pixel whatever the render mode or thread count.
FOVEAL_HD constexpr uint32_t pixel_seed(uint64_t seed, uint32_t x, uint32_t y) {
  uint32_t h = hash_combine(hash32(static_cast<uint32_t>(seed)), static_cast<uint32_t>(seed >> 32));
  return hash_combine(hash_combine(h, x), y);
}

// Reverse the bits of a 32-bit word.
FOVEAL_HD constexpr uint32_t reverse_bits(uint32_t x) {
  x = ((x >> 1) & 0x55555555U) | ((x & 0x55555555U) << 1);
  x = ((x >> 2) & 0x33333333U) | ((x & 0x33333333U) << 2);
  x = ((x >> 4) & 0x0F0F0F0FU) | ((x & 0x0F0F0F0FU) << 4);
  x = ((x >> 8) & 0x00FF00FFU) | ((x & 0x00FF00FFU) << 8);
  return (x >> 16) | (x << 16);
}

// First two dimensions of the Sobol (0,2)-sequence as 32-bit fixed point.
FOVEAL_HD constexpr uint32_t sobol_dim0(uint32_t index) { return reverse_bits(index); }
FOVEAL_HD constexpr uint32_t sobol_dim1(uint32_t index) {
  uint32_t result = 0;
  for (uint32_t v = 1U << 31; index != 0; index >>= 1, v ^= v >> 1)
    if (index & 1U) result ^= v;
  return result;
}

// Fixed point [0, 2^32) to float in [0, 1).
FOVEAL_HD inline float to_unit_float(uint32_t bits) { return static_cast<float>(bits >> 8) * 0x1p-24f; }

// The first 2^16 points of the 2-D Sobol sequence, computed once (512 KiB).
const uint32_t* sobol_table_2d();
inline constexpr uint32_t kSobolTableSize = 1U << 16;

// One pixel's scramble of the 2-D Sobol sequence: an XOR mask per dimension.
struct SobolScramble {
  uint32_t x = 0, y = 0;
  const uint32_t* table = nullptr;  // sobol_table_2d(), looked up once per pixel, not per ray
};
// `table` is sobol_table_2d() or, on the GPU, its copy in device memory.
FOVEAL_HD inline SobolScramble sobol_scramble(uint32_t pixel_hash, const uint32_t* table) {
  return {hash32(pixel_hash ^ 0xa511e9b3U), hash32(pixel_hash ^ 0x63d83595U), table};
}
inline SobolScramble sobol_scramble(uint32_t pixel_hash) { return sobol_scramble(pixel_hash, sobol_table_2d()); }

// The k-th point of a 2-D Sobol sequence under a pixel's scramble; values in [0,1).
// Random digit scrambling (an XOR per dimension) keeps the (0,2) stratification of every
// power-of-two prefix, so any ray count n gets well-spread directions, and costs one
// instruction per ray where hash-based Owen scrambling cost about ten per ray (measured).
FOVEAL_HD inline glm::vec2 sobol_2d(uint32_t k, SobolScramble scramble) {
  uint32_t s0, s1;
  if (k < kSobolTableSize) {
    s0 = scramble.table[2 * k];
    s1 = scramble.table[2 * k + 1];
  } else {
    s0 = sobol_dim0(k);
    s1 = sobol_dim1(k);
  }
  return {to_unit_float(s0 ^ scramble.x), to_unit_float(s1 ^ scramble.y)};
}

// The k-th point of the 2-D Sobol sequence scrambled by one pixel's hash.
inline glm::vec2 scrambled_sobol_2d(uint32_t k, uint32_t pixel_hash) { return sobol_2d(k, sobol_scramble(pixel_hash)); }

// (cos 2πt, sin 2πt) for t in [0, 1) (t ≥ 0 required): quadrant reduction and odd/even Taylor polynomials on
// [0, π/2), absolute error below 4e-6, without branches (the quadrant of a Sobol point is
// unpredictable). Written here because libm's sincos was a tenth of the cost of an AO ray
// (measured), and directions need no more precision than this.
FOVEAL_HD inline glm::vec2 cos_sin_2pi(float t) {
  const float q4 = t * 4.0f;  // t ≥ 0: truncation is floor, and cheaper than floorf without SSE4.1
  const int whole = static_cast<int>(q4);
  const auto quadrant = static_cast<uint32_t>(whole) & 3U;
  const float a = (q4 - static_cast<float>(whole)) * (std::numbers::pi_v<float> * 0.5f);
  const float a2 = a * a;
  const float s = a * (1.0f + a2 * (-1.0f / 6 + a2 * (1.0f / 120 + a2 * (-1.0f / 5040 + a2 * (1.0f / 362880)))));
  const float c = 1.0f + a2 * (-0.5f + a2 * (1.0f / 24 + a2 * (-1.0f / 720 + a2 * (1.0f / 40320 + a2 * (-1.0f / 3628800)))));
  // Rotate by quadrant·90°: odd quadrants swap the pair, then flip signs (q 1, 2: x; q 2, 3: y)
  const bool odd = (quadrant & 1U) != 0;
  const float x = odd ? s : c, y = odd ? c : s;
  const uint32_t flip_x = ((quadrant + 1U) & 2U) << 30, flip_y = (quadrant & 2U) << 30;
  return {std::bit_cast<float>(std::bit_cast<uint32_t>(x) ^ flip_x), std::bit_cast<float>(std::bit_cast<uint32_t>(y) ^ flip_y)};
}

// atan2(y, x) for y ≥ 0 (an angle in [0, π], e.g. between unit vectors from |a × b| and a·b):
// reduction to [0, 1] and Abramowitz & Stegun's polynomial 4.4.47 (absolute error 1.2e-5 rad,
// 0.0007°). Written here
// because libm's atan2 was three quarters of the vision simulation's per-pixel CoC pass (measured).
FOVEAL_HD inline float angle_atan2(float y, float x) {
  const float ax = std::abs(x), lo = std::min(ax, y), hi = std::max(ax, y);
  const float a = hi > 0 ? lo / hi : 0.0f, s = a * a;
  float r = a * (0.9998660f + s * (-0.3302995f + s * (0.1801410f + s * (-0.0851330f + s * 0.0208351f))));
  if (y > ax) r = std::numbers::pi_v<float> * 0.5f - r;
  if (x < 0) r = std::numbers::pi_v<float> - r;
  return r;
}

// Cosine-weighted direction on the +z hemisphere from a point of the unit square (pdf cos/pi).
FOVEAL_HD inline glm::vec3 cosine_hemisphere(glm::vec2 u) {
  const float r = std::sqrt(u.x);
  const glm::vec2 cs = cos_sin_2pi(u.y);
  return {r * cs.x, r * cs.y, std::sqrt(std::max(0.0f, 1.0f - u.x))};
}

// Orthonormal basis around a unit normal (Duff et al. 2017), branchless and NaN-free.
struct Frame3 {
  glm::vec3 t, b, n;  // tangent, bitangent, normal
  FOVEAL_HD glm::vec3 to_world(glm::vec3 v) const { return t * v.x + b * v.y + n * v.z; }
};
FOVEAL_HD inline Frame3 make_frame(glm::vec3 n) {
  const float sign = std::copysign(1.0f, n.z);
  const float a = -1.0f / (sign + n.z);
  const float b = n.x * n.y * a;
  return {{1.0f + sign * n.x * n.x * a, sign * b, -sign * n.x}, {b, sign + n.y * n.y * a, -n.y}, n};
}

}  // namespace foveal
