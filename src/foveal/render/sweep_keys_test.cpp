// The sweeps' kept buckets: pixels sorted by bucket and, within one, in pixel order, the same
// whatever the thread count; a bucket computed again only where it was marked stale.
#include "foveal/render/sweep_keys.h"

#include <gtest/gtest.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <atomic>
#include <numeric>

namespace foveal {
namespace {

// A bucket per pixel from a hash: kNone for every fifth, else one of 9
int hashed(size_t i, uint32_t salt) {
  uint32_t h = static_cast<uint32_t>(i) * 2654435761u ^ salt;
  h ^= h >> 15;
  h *= 2246822519u;
  h ^= h >> 13;
  return h % 5 == 0 ? SweepKeys::kNone : static_cast<int>(h % 9);
}

TEST(SweepKeys, PixelsComeByBucketThenInPixelOrderWhateverTheThreadCount) {
  const size_t n = 100'003;  // (blocks of 16,384 and a part)
  std::vector<uint32_t> expected;
  for (int b = 0; b < 9; ++b)
    for (size_t i = 0; i < n; ++i)
      if (hashed(i, 7) == b) expected.push_back(static_cast<uint32_t>(i));
  for (const int threads : {1, 2, 5}) {
    SweepKeys keys;
    keys.reset(n);
    std::vector<uint32_t> order;
    size_t placed = 0;
    tbb::task_arena(threads).execute([&] { placed = keys.sweep<9>([](size_t i) { return hashed(i, 7); }, order); });
    ASSERT_EQ(placed, expected.size()) << threads << " threads";
    EXPECT_TRUE(std::equal(expected.begin(), expected.end(), order.begin())) << threads << " threads";
  }
}

TEST(SweepKeys, OnlyStaleBucketsAreComputedAgain) {
  const size_t width = 300, n = width * 200;
  SweepKeys keys;
  keys.reset(n);
  EXPECT_TRUE(keys.wide());
  std::atomic<size_t> computed{0};
  std::vector<uint32_t> order;
  uint32_t salt = 1;
  auto sweep = [&] {
    computed = 0;
    return keys.sweep<9>(
        [&](size_t i) {
          ++computed;
          return hashed(i, salt);
        },
        order);
  };
  sweep();
  EXPECT_EQ(computed, n);  // a fresh set: every pixel
  EXPECT_FALSE(keys.wide());
  // The buckets change for every pixel, but only those marked are computed again: the sort sees the
  // others' old buckets
  salt = 2;
  for (const size_t i : {size_t{0}, size_t{17}, n - 1}) keys.stale(i);
  keys.stale(n);  // (past the end: nothing)
  sweep();
  EXPECT_EQ(computed, 3u);
  EXPECT_FALSE(keys.wide());
  for (size_t i = 0; i < n; ++i)
    ASSERT_EQ(keys.keys()[i], (i == 0 || i == 17 || i == n - 1) ? hashed(i, 2) : hashed(i, 1)) << "pixel " << i;
  // A box of the maps: its pixels, clipped to the image, and the next sweep is a wide one
  keys.stale_box(glm::ivec4(-5, 190, 10, 260), width);  // x in [0, 10), y in [190, 200)
  EXPECT_TRUE(keys.wide());
  for (size_t i = 0; i < n; ++i) EXPECT_EQ(keys.keys()[i] == SweepKeys::kStale, i % width < 10 && i / width >= 190) << "pixel " << i;
  sweep();
  EXPECT_EQ(computed, 100u);
  keys.stale_all();
  EXPECT_TRUE(keys.wide());
  const size_t placed = sweep();
  EXPECT_EQ(computed, n);
  size_t with_bucket = 0;
  for (size_t i = 0; i < n; ++i) with_bucket += hashed(i, 2) >= 0;
  EXPECT_EQ(placed, with_bucket);
}

}  // namespace
}  // namespace foveal
