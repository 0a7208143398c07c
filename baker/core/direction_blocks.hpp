// Direction blocks: the fixed grouping of a method's K azimuths that the farm (baker/farm) divides work by.
// A direction-dividing method (p1, hbao) sums its per-direction terms within each block starting from zero,
// then adds the block sums in block order. The blocks depend on K only, never on how many machines share
// the work, so `hfbake bake` and `hfbake merge` of any number of shards add the same floats in the same
// order: the same bits.
#pragma once

#include <algorithm>
#include <cstddef>
#include <string>
#include <utility>
#include <vector>

#include "core/error.hpp"
#include "core/layers.hpp"

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

// The merged blocks' layer `name`, moved out of `sums`: it must be there with `per_texel` floats for each of
// sums' texels (a "#2f" layer: two a double). The layers come from the farm's shard files, which a merge
// reads as untrusted input: a layer missing or of another size is an InputError without a file (the merge
// names the shards), never a read past its end.
inline std::vector<float> take_block_layer(LayerSet& sums, const std::string& name, std::size_t per_texel) {
  Layer* l = sums.find(name);
  const std::size_t texels = std::size_t(sums.width) * std::size_t(sums.height);
  if (!l || l->channels.size() != per_texel || l->data.size() != per_texel * texels)
    throw InputError("", "",
                     "the direction blocks hold " + std::string(l ? "another size of" : "no") + " layer " +
                         name + " (" + std::to_string(per_texel) +
                         " values a texel): not this job's blocks, bake them again");
  return std::move(l->data);
}

// The per-block layers "<prefix>@<k0>" of merged blocks (p1's and p2's horizons: block data that is placed,
// never added), each handed to `place(layer, k0)` with its channels directions k0, k0 + 1, ... of K. Together
// they must cover the K directions exactly once, each layer one direction block (the shards' files are
// untrusted: InputError without a file, as take_block_layer).
template <class Place>
void place_block_layers(const LayerSet& sums, const std::string& prefix, int K, Place&& place) {
  const std::string head = prefix + "@";
  std::vector<char> covered(std::size_t(std::max(K, 0)), 0);
  auto refuse = [&](const std::string& why) {
    throw InputError("", "", "the direction blocks' " + prefix + " layers " + why + ": bake them again");
  };
  for (const Layer& l : sums.layers) {
    if (l.name.rfind(head, 0) != 0) continue;
    const std::string digits = l.name.substr(head.size());
    if (digits.empty() || digits.size() > 9 || digits.find_first_not_of("0123456789") != std::string::npos)
      refuse("are misnamed (" + l.name + ")");
    const int k0 = std::stoi(digits), n = l.channel_count();
    const std::size_t texels = std::size_t(sums.width) * std::size_t(sums.height);
    bool a_block = false;  // [k0, k0 + n) is one of the K directions' blocks
    for (int b = 0; b < direction_block_count(K) && !a_block; ++b)
      a_block = direction_block_begin(b, K) == k0 && direction_block_begin(b + 1, K) == k0 + n;
    if (!a_block || l.data.size() != std::size_t(n) * texels)
      refuse("are not of this job's direction blocks");
    for (int k = k0; k < k0 + n; ++k) {
      if (covered[std::size_t(k)]) refuse("overlap");
      covered[std::size_t(k)] = 1;
    }
    place(l, k0);
  }
  if (std::count(covered.begin(), covered.end(), 1) != K) refuse("do not cover the directions");
}

}  // namespace hfbake
