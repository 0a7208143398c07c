// Direction blocks: the fixed grouping of a method's K azimuths that the farm (baker/farm) divides work by.
// A direction-dividing method (p1, hbao) sums its per-direction terms within each block starting from zero,
// then adds the block sums in block order. The blocks depend on K only, never on how many machines share
// the work, so `hfbake bake` and `hfbake merge` of any number of shards add the same floats in the same
// order: the same bits.
#pragma once

#include <algorithm>

namespace hfbake {

inline constexpr int kDirectionBlocks = 8;  // at most; fewer when K < 8 (one direction each)

inline int direction_block_count(int K) {
  return std::max(1, std::min(K, kDirectionBlocks));
}
// First direction of block b (b = direction_block_count(K) gives K).
inline int direction_block_begin(int b, int K) {
  return int((long long)b * K / direction_block_count(K));
}

// A double carried as two floats (hi + lo, about 48 bits): how a method whose sums are double passes them
// through float layers (the shard files). A block's double sum is split once; a total adds blocks by
// join + join, split again (add_split), in bake and merge alike, so both round identically.
struct SplitDouble {
  float hi = 0, lo = 0;
};
inline SplitDouble split_double(double x) {
  const float hi = float(x);
  return {hi, float(x - double(hi))};
}
inline double join_double(SplitDouble s) {
  return double(s.hi) + double(s.lo);
}
inline void add_split(SplitDouble& total, SplitDouble block) {
  total = split_double(join_double(total) + join_double(block));
}

}  // namespace hfbake
