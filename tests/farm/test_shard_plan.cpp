// The farm's plan and shard file: every direction block and reference row is in exactly one shard for any
// shard count; the shard file round-trips and refuses truncation, damage and other jobs; the merge's block
// sums and row stacking against sums and copies written out by hand.
#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>
#include <tuple>
#include <vector>

#include "core/direction_blocks.hpp"
#include "core/error.hpp"
#include "farm/merge_blocks.hpp"
#include "farm/shard_file.hpp"
#include "farm/shard_plan.hpp"
#include "methods/method_table.hpp"

namespace hfbake {
namespace {

namespace fs = std::filesystem;

TEST(ShardPlan, ParsesShardIds) {
  ASSERT_TRUE(parse_shard_id("0/1"));
  EXPECT_EQ(parse_shard_id("3/4")->index, 3);
  EXPECT_EQ(parse_shard_id("3/4")->count, 4);
  for (const char* bad : {"4/4", "-1/4", "1/0", "1", "1/", "/4", "a/4", "1/4x", "1/5000", " 1/4"})
    EXPECT_FALSE(parse_shard_id(bad)) << bad;
}

TEST(ShardPlan, DirectionBlocksPartitionTheDirections) {
  for (int K : {1, 2, 3, 7, 8, 9, 16, 63, 64, 4096}) {
    const int B = direction_block_count(K);
    EXPECT_EQ(B, std::min(K, 8));
    EXPECT_EQ(direction_block_begin(0, K), 0);
    EXPECT_EQ(direction_block_begin(B, K), K);
    for (int b = 0; b < B; ++b) EXPECT_LT(direction_block_begin(b, K), direction_block_begin(b + 1, K));
  }
}

// A bake entry resolved by its method's reader (a 64² field of unit texels).
BakeEntry entry(const char* method, const nlohmann::json& params) {
  MethodContext context;
  context.field.width = context.field.height = 64;
  context.field.texel_size = 1;
  BakeEntry e;
  e.method = method;
  e.config = std::make_shared<const MethodConfig>(read_method_config(method, params, context));
  return e;
}

Job three_entry_job() {
  Job job;
  job.name = "j";
  job.output.dir = "/tmp/x";
  job.has_reference = true;
  job.bakes = {entry("p1", {{"directions", 16}}),      entry("vo", {{"radius", 2}}),  // vo runs whole
               entry("hbao", {{"directions", 5}}),     entry("lsao", {{"directions", 12}}),
               entry("farfield", {{"directions", 3}}), entry("hsao", {{"directions", 64}, {"radius", 2}})};
  return job;
}

TEST(ShardPlan, EveryBlockRowAndWholeMethodIsInExactlyOneShard) {
  for (int height : {1, 31, 32, 33, 1000}) {
    const Job job = three_entry_job();
    for (int N = 1; N <= 20; ++N) {
      // Blocks per entry: min(K, 8) for the direction-dividing methods; vo runs whole (one unit).
      std::vector<std::vector<int>> seen = {std::vector<int>(8), std::vector<int>(1), std::vector<int>(5),
                                            std::vector<int>(8), std::vector<int>(3), std::vector<int>(8)};
      std::vector<int> rows(height);
      for (int I = 0; I < N; ++I) {
        const ShardWork w = shard_work(job, height, {I, N});
        for (const ShardWork::Entry& e : w.entries) {
          EXPECT_EQ(e.whole, e.entry == 1) << "entry " << e.entry;
          if (e.whole)
            ++seen[1][0];
          else
            for (int b = e.block_begin; b < e.block_end; ++b)
              ++seen.at(std::size_t(e.entry)).at(std::size_t(b));
        }
        for (int r = w.row_begin; r < w.row_end; ++r) ++rows.at(std::size_t(r));
      }
      for (const auto& entry : seen)
        for (int c : entry) EXPECT_EQ(c, 1) << "N " << N;
      for (int c : rows) EXPECT_EQ(c, 1) << "N " << N << " height " << height;
    }
  }
}

// p2's stages: every stage's direction blocks (min(K, 8); stage 0 p1's, stage b bounce b's) each in exactly
// one shard, in block order; no stage beyond the entry's bounces.
TEST(ShardPlan, EveryStageBlockIsInExactlyOneShard) {
  Job job;
  job.name = "j";
  job.output.dir = "/tmp/x";
  job.bakes = {entry("p2", {{"directions", 16}, {"bounces", 2}}), entry("p1", {{"directions", 8}}),
               entry("p2", {{"directions", 5}, {"bounces", 1}})};
  ASSERT_EQ(job_stages(job), 3);
  EXPECT_EQ(entry_stage_blocks(job.bakes[0], 0), 8);
  EXPECT_EQ(entry_stage_blocks(job.bakes[0], 1), 8);
  EXPECT_EQ(entry_stage_blocks(job.bakes[2], 1), 5);
  EXPECT_EQ(entry_stage_blocks(job.bakes[1], 1), 0);
  for (int N = 1; N <= 11; ++N)
    for (int stage = 0; stage < 3; ++stage) {
      std::vector<std::vector<int>> seen(3);  // per entry: how often each block
      for (int e = 0; e < 3; ++e) seen[std::size_t(e)].assign(8, 0);
      for (int I = 0; I < N; ++I) {
        int last_entry = -1, last_block = -1;
        for (const StageItem& item : stage_work(job, {I, N}, stage)) {
          ASSERT_NE(item.entry, 1);
          EXPECT_GE(item.block, 0);
          if (item.entry == last_entry) {
            EXPECT_GT(item.block, last_block);
          }
          last_entry = item.entry, last_block = item.block;
          seen[std::size_t(item.entry)][std::size_t(item.block)] += 1;
        }
      }
      for (int e : {0, 2}) {
        const int stages = e == 0 ? 3 : 2;
        const int units = stage >= stages ? 0 : e == 0 ? 8 : 5;
        for (int u = 0; u < 8; ++u)
          EXPECT_EQ(seen[std::size_t(e)][std::size_t(u)], u < units ? 1 : 0)
              << "N " << N << " stage " << stage << " entry " << e << " unit " << u;
      }
    }
  EXPECT_EQ(stage_block_path(job, 0, 2, 7).filename(), "j..stage-2.block-7.hfshard");
}

TEST(MergeBlocks, AddsInBlockOrderAndKeepsPerBlockLayers) {
  auto block = [](float v, const char* kept) {
    LayerSet s;
    s.width = 2, s.height = 1;
    s.add("ao", {"Y"}).data = {v, 2 * v};
    s.add(kept, {"000"}).data = {v, v};
    return s;
  };
  LayerSet total;
  add_direction_block(total, block(1e8f, "horizon@0"));
  add_direction_block(total, block(1.0f, "horizon@4"));
  add_direction_block(total, block(-1e8f, "horizon@8"));
  // ((1e8 + 1) - 1e8) in float: 1e8 + 1 rounds to 1e8, so 0 -- the order, not the exact sum.
  EXPECT_EQ(total.find("ao")->data[0], 0.0f);
  ASSERT_TRUE(total.find("horizon@4"));
  EXPECT_EQ(total.find("horizon@4")->data[0], 1.0f);
  EXPECT_EQ(total.layers.size(), 4u);
}

// FloatBlocks against sums written out by hand: each block from zero in float, the blocks added in order.
TEST(MergeBlocks, FloatBlocksSumEachBlockFromZero) {
  for (int K : {1, 5, 8, 9, 20}) {
    std::vector<double> v(static_cast<std::size_t>(K));
    for (int k = 0; k < K; ++k) v[std::size_t(k)] = (k % 2 ? 1e8 : 1.0) * (k % 3 ? 1.0 : -1.0) + 0.1 * k;
    float expect = 0;
    for (int b = 0; b < direction_block_count(K); ++b) {
      float block = 0;
      for (int k = direction_block_begin(b, K); k < direction_block_begin(b + 1, K); ++k)
        block = float(double(block) + v[std::size_t(k)]);
      expect = b == 0 ? block : expect + block;
    }
    const FloatBlocks blocks(K);
    EXPECT_EQ(blocks.needs_partial(), K > 8);
    float total = 12345, partial = 0;
    for (int k = 0; k < K; ++k) blocks.add(k, v[std::size_t(k)], total, partial);
    EXPECT_EQ(total, expect) << "K " << K;
  }
}

TEST(MergeBlocks, SplitDoublesKeep48Bits) {
  SplitDouble t = split_double(1.0);
  add_split(t, split_double(1e-12));
  EXPECT_NEAR(join_double(t), 1.0 + 1e-12, 1e-15);
}

TEST(MergeBlocks, StacksRowBands) {
  std::vector<LayerSet> bands(2);
  for (int b = 0; b < 2; ++b) {
    bands[b].width = 2, bands[b].height = b + 1;
    bands[b].add("ao", {"Y"}).data.assign(std::size_t(2 * (b + 1)), float(b + 1));
  }
  const LayerSet all = stack_row_bands(std::move(bands), 3);
  EXPECT_EQ(all.find("ao")->data, (std::vector<float>{1, 1, 2, 2, 2, 2}));
}

TEST(ShardFile, RoundTripsAndRefusesDamage) {
  const fs::path dir = fs::temp_directory_path() / ("hfbake_shard_test_" + std::to_string(::getpid()));
  fs::create_directories(dir);
  const fs::path file = dir / "j.shard-1-of-2.hfshard";
  ShardIdentity id;
  id.job_name = "j", id.job_hash = "0123456789abcdef", id.version = "v1", id.id = {1, 2};
  id.width = 3, id.height = 2;
  LayerSet l;
  l.width = 3, l.height = 2;
  l.add("ao", {"Y"}).data = {1, 2, 3, 4, 5, 6};
  l.attributes.emplace_back("k", "v");
  {
    ShardWriter w(file, id);
    ShardPart p;
    p.entry = 0, p.kind = "block", p.block = 4;
    w.add(p, l);
    EXPECT_FALSE(fs::exists(file));  // not before commit
    w.commit();
  }
  ASSERT_TRUE(shard_is_complete(file, id));
  ShardReader r(file, id);
  ASSERT_EQ(r.parts().size(), 1u);
  EXPECT_EQ(r.parts()[0].block, 4);
  const LayerSet back = r.load(0);
  EXPECT_EQ(back.find("ao")->data, l.find("ao")->data);
  EXPECT_EQ(back.attributes, l.attributes);

  ShardIdentity other = id;
  other.job_hash = "fedcba9876543210";
  EXPECT_THROW(ShardReader(file, other), InputError);
  EXPECT_FALSE(shard_is_complete(file, other));
  // A file of one piece must hold that piece: another entry's, kind's or block's is refused.
  for (const auto& [entry, kind, block] : std::vector<std::tuple<int, std::string, int>>{
           {1, "block", 4}, {0, "stage-block", 4}, {0, "block", 3}}) {
    ShardIdentity piece = id;
    piece.part_entry = entry, piece.part_kind = kind, piece.part_block = block;
    EXPECT_FALSE(shard_is_complete(file, piece)) << entry << kind << block;
  }
  ShardIdentity piece = id;
  piece.part_entry = 0, piece.part_kind = "block", piece.part_block = 4;
  EXPECT_TRUE(shard_is_complete(file, piece));
  // A header byte changed (a channel's name, the attribute's text): the header's checksum refuses it.
  const std::string bytes = [&] {
    std::ifstream in(file, std::ios::binary);
    return std::string(std::istreambuf_iterator<char>(in), {});
  }();
  for (const std::string& from : {std::string("[\"Y\"]"), std::string("[\"k\",\"v\"]")}) {
    std::string forged = bytes;
    const std::size_t at = forged.rfind(from);
    ASSERT_NE(at, std::string::npos) << from;
    forged[at + 2] = 'Z';
    std::ofstream(dir / "h", std::ios::binary) << forged;
    try {
      ShardReader(dir / "h", id);
      ADD_FAILURE() << "a header with " << from << " changed was read";
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find("header checksum"), std::string::npos) << e.what();
    }
  }
  // Truncated: one byte short.
  const auto size = fs::file_size(file);
  fs::copy_file(file, dir / "t", fs::copy_options::overwrite_existing);
  fs::resize_file(dir / "t", size - 1);
  EXPECT_THROW(ShardReader(dir / "t", id), InputError);
  // A flipped data byte: the header reads, the layer's checksum does not match.
  {
    std::fstream f(file, std::ios::in | std::ios::out | std::ios::binary);
    f.seekp(20);
    f.put('\x7f');
  }
  ShardReader damaged(file, id);
  EXPECT_THROW(damaged.load(0), InputError);
  EXPECT_FALSE(shard_is_complete(file, id));
  EXPECT_THROW(ShardReader(dir / "missing", id), InputError);
  fs::remove_all(dir);
}

}  // namespace
}  // namespace hfbake
