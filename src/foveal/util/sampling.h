// foveal/util/sampling.h — hashing, scrambled Sobol points and hemisphere mapping.
//
// Every random choice in foveal is a pure function of (seed, pixel, sample index), so an
// image does not depend on the thread count or on the order in which tiles run.
#pragma once

#include <glm/glm.hpp>

#include <cmath>
#include <cstdint>
#include <numbers>

namespace foveal {

// 32-bit integer hash with good avalanche (lowbias32, C. Wellons).
constexpr uint32_t hash32(uint32_t x) {
  x ^= x >> 16;
  x *= 0x7feb352dU;
  x ^= x >> 15;
  x *= 0x846ca68bU;
  x ^= x >> 16;
  return x;
}

// Hash of several words, order-sensitive.
constexpr uint32_t hash_combine(uint32_t seed, uint32_t value) {
  return hash32(seed ^ (value + 0x9e3779b9U + (seed << 6) + (seed >> 2)));
}

// Seed of one pixel: the same for a pixel whatever the render mode or thread count.
constexpr uint32_t pixel_seed(uint64_t seed, uint32_t x, uint32_t y) {
  uint32_t h = hash_combine(hash32(static_cast<uint32_t>(seed)), static_cast<uint32_t>(seed >> 32));
  return hash_combine(hash_combine(h, x), y);
}

// Reverse the bits of a 32-bit word.
constexpr uint32_t reverse_bits(uint32_t x) {
  x = ((x >> 1) & 0x55555555U) | ((x & 0x55555555U) << 1);
  x = ((x >> 2) & 0x33333333U) | ((x & 0x33333333U) << 2);
  x = ((x >> 4) & 0x0F0F0F0FU) | ((x & 0x0F0F0F0FU) << 4);
  x = ((x >> 8) & 0x00FF00FFU) | ((x & 0x00FF00FFU) << 8);
  return (x >> 16) | (x << 16);
}

// First two dimensions of the Sobol (0,2)-sequence as 32-bit fixed point.
constexpr uint32_t sobol_dim0(uint32_t index) { return reverse_bits(index); }
constexpr uint32_t sobol_dim1(uint32_t index) {
  uint32_t result = 0;
  for (uint32_t v = 1U << 31; index != 0; index >>= 1, v ^= v >> 1)
    if (index & 1U) result ^= v;
  return result;
}

// Hash-based nested uniform (Owen) scramble of a fixed-point value (Burley 2020).
// Written here because no packaged library offers it; it keeps the (0,2) stratification of
// every power-of-two prefix, so any ray count n gets well-spread directions.
constexpr uint32_t owen_scramble(uint32_t value, uint32_t seed) {
  uint32_t x = reverse_bits(value);
  x += seed;
  x ^= x * 0x6c50b47cU;
  x ^= x * 0xb82f1e52U;
  x ^= x * 0xc7afe638U;
  x ^= x * 0x8d22f6e6U;
  return reverse_bits(x);
}

// Fixed point [0, 2^32) to float in [0, 1).
inline float to_unit_float(uint32_t bits) {
  return static_cast<float>(bits >> 8) * 0x1p-24f;
}

// The k-th point of a 2-D Sobol sequence scrambled by one pixel's seed; values in [0,1).
inline glm::vec2 scrambled_sobol_2d(uint32_t k, uint32_t pixel_hash) {
  return {to_unit_float(owen_scramble(sobol_dim0(k), hash32(pixel_hash ^ 0xa511e9b3U))),
          to_unit_float(owen_scramble(sobol_dim1(k), hash32(pixel_hash ^ 0x63d83595U)))};
}

// Cosine-weighted direction on the +z hemisphere from a point of the unit square (pdf cos/pi).
inline glm::vec3 cosine_hemisphere(glm::vec2 u) {
  const float r = std::sqrt(u.x);
  const float phi = 2.0f * std::numbers::pi_v<float> * u.y;
  return {r * std::cos(phi), r * std::sin(phi), std::sqrt(std::max(0.0f, 1.0f - u.x))};
}

// Orthonormal basis around a unit normal (Duff et al. 2017), branchless and NaN-free.
struct Frame3 {
  glm::vec3 t, b, n;  // tangent, bitangent, normal
  glm::vec3 to_world(glm::vec3 v) const { return t * v.x + b * v.y + n * v.z; }
};
inline Frame3 make_frame(glm::vec3 n) {
  const float sign = std::copysign(1.0f, n.z);
  const float a = -1.0f / (sign + n.z);
  const float b = n.x * n.y * a;
  return {{1.0f + sign * n.x * n.x * a, sign * b, -sign * n.x}, {b, sign + n.y * n.y * a, -n.y}, n};
}

}  // namespace foveal
