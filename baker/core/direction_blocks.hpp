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

namespace hfbake {

// Float sums by blocks, for a method that accumulates per texel in float one direction at a time, k
// ascending (lsao, farfield): each block is summed from zero (one rounding per direction), and the block
// sums are added to the total in float in block order (the first block is taken as it is) -- what
// farm/merge_blocks.cpp add_direction_block does with blocks baked elsewhere. A block of one direction
// needs no partial sum; others keep theirs in `partial` (a float per texel and channel) between directions.
class FloatBlocks {
 public:
  explicit FloatBlocks(int K) : K_(std::max(K, 1)), first_end_(direction_block_begin(1, K_)) {
    multi_ = direction_block_count(K_) < K_;
  }
  // Whether some block holds more than one direction (then `partial` is read and written).
  bool needs_partial() const { return multi_; }
  // Direction k's value v for one texel channel: total (the caller's sum) and partial (its block's).
  void add(int k, double v, float& total, float& partial) const {
    const int b = block_of(k);
    const bool starts = k == direction_block_begin(b, K_), ends = k + 1 == direction_block_begin(b + 1, K_);
    const float p = float((starts ? 0.0 : double(partial)) + v);
    if (!ends) {
      partial = p;
      return;
    }
    total = k < first_end_ ? p : total + p;
  }

 private:
  int block_of(int k) const {
    // The block b with begin(b) <= k < begin(b + 1) (begin(b) = b K / B, B <= 8).
    const int B = direction_block_count(K_);
    int b = int((long long)k * B / K_);
    while (b + 1 < B && direction_block_begin(b + 1, K_) <= k) ++b;
    while (b > 0 && direction_block_begin(b, K_) > k) --b;
    return b;
  }
  int K_, first_end_;
  bool multi_ = false;
};

}  // namespace hfbake
