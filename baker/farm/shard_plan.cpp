#include "farm/shard_plan.hpp"

#include <charconv>

#include "core/direction_blocks.hpp"
#include "methods/method_table.hpp"

namespace hfbake {

std::optional<ShardId> parse_shard_id(const std::string& text) {
  const std::size_t slash = text.find('/');
  if (slash == std::string::npos) return std::nullopt;
  ShardId id;
  const char* b = text.data();
  const char* e = text.data() + text.size();
  auto r1 = std::from_chars(b, b + slash, id.index);
  auto r2 = std::from_chars(b + slash + 1, e, id.count);
  if (r1.ec != std::errc() || r1.ptr != b + slash || r2.ec != std::errc() || r2.ptr != e) return std::nullopt;
  if (id.count < 1 || id.count > 4096 || id.index < 0 || id.index >= id.count) return std::nullopt;
  return id;
}

std::string shard_id_text(ShardId id) {
  return std::to_string(id.index) + "/" + std::to_string(id.count);
}

int entry_direction_blocks(const BakeEntry& entry) {
  if (!entry.config) return 0;
  const MethodInfo* m = entry.config->method;
  if (!m->bake_block || !m->finish_blocks) return 0;
  const int K = entry.config->directions;
  return K > 0 ? direction_block_count(K) : 0;
}

int entry_stages(const BakeEntry& entry) {
  if (!entry.config) return 0;
  const MethodInfo* m = entry.config->method;
  return m->stages && m->bake_stage && m->finish_stages ? m->stages(*entry.config) : 0;
}

int entry_stage_blocks(const BakeEntry& entry, int stage) {
  if (entry_stages(entry) == 0) return 0;
  const MethodInfo* m = entry.config->method;
  if (!m->stage_blocks || !m->bake_stage_block || !m->finish_stage_blocks) return 0;
  return m->stage_blocks(*entry.config, stage);
}

std::vector<StageItem> stage_work(const Job& job, ShardId id, int stage) {
  std::vector<StageItem> out;
  const long long I = id.index, N = id.count;
  for (std::size_t e = 0; e < job.bakes.size(); ++e) {
    if (stage >= entry_stages(job.bakes[e])) continue;
    const long long B = entry_stage_blocks(job.bakes[e], stage);
    if (B == 0) {
      if (static_cast<long long>(e) % N == I) out.push_back({int(e), -1});
      continue;
    }
    for (long long b = I * B / N; b < (I + 1) * B / N; ++b) out.push_back({int(e), int(b)});
  }
  return out;
}

int job_stages(const Job& job) {
  int s = 0;
  for (const BakeEntry& e : job.bakes) s = std::max(s, entry_stages(e));
  return s;
}

ShardWork shard_work(const Job& job, int field_height, ShardId id) {
  ShardWork w;
  const long long I = id.index, N = id.count;
  for (std::size_t e = 0; e < job.bakes.size(); ++e) {
    const int B = entry_direction_blocks(job.bakes[e]);
    ShardWork::Entry x;
    x.entry = int(e);
    if (entry_stages(job.bakes[e]) > 0) {
      if (static_cast<long long>(e) % N == I) w.staged.push_back(int(e));
      continue;
    }
    if (B == 0) {
      if (static_cast<long long>(e) % N != I) continue;
      x.whole = true;
    } else {
      x.block_begin = int(I * B / N), x.block_end = int((I + 1) * B / N);
      if (x.block_begin == x.block_end) continue;
    }
    w.entries.push_back(x);
  }
  if (job.has_reference) {
    const long long R = (field_height + kReferenceBandRows - 1) / kReferenceBandRows;
    w.row_begin = int(std::min<long long>(field_height, I * R / N * kReferenceBandRows));
    w.row_end = int(std::min<long long>(field_height, (I + 1) * R / N * kReferenceBandRows));
  }
  return w;
}

std::filesystem::path shard_path(const Job& job, ShardId id) {
  return job.output.dir / "shards" /
         (job.name + ".shard-" + std::to_string(id.index) + "-of-" + std::to_string(id.count) + ".hfshard");
}

}  // namespace hfbake

namespace hfbake {

std::filesystem::path stage_path(const Job& job, int entry, int stage) {
  return job.output.dir / "shards" /
         (job.name + "." + job.bakes[std::size_t(entry)].stem + ".stage-" + std::to_string(stage) +
          ".hfshard");
}

}  // namespace hfbake

namespace hfbake {

std::filesystem::path stage_block_path(const Job& job, int entry, int stage, int block) {
  return job.output.dir / "shards" /
         (job.name + "." + job.bakes[std::size_t(entry)].stem + ".stage-" + std::to_string(stage) +
          ".block-" + std::to_string(block) + ".hfshard");
}

std::filesystem::path stage_item_path(const Job& job, int stage, StageItem item) {
  return item.block < 0 ? stage_path(job, item.entry, stage)
                        : stage_block_path(job, item.entry, stage, item.block);
}

bool is_shard_file_name(const Job& job, const std::string& filename) {
  const std::string tail = ".hfshard";
  if (filename.size() <= tail.size() ||
      filename.compare(filename.size() - tail.size(), tail.size(), tail) != 0)
    return false;
  const auto starts = [&filename](const std::string& head) { return filename.rfind(head, 0) == 0; };
  if (starts(job.name + ".shard-")) return true;
  for (const BakeEntry& e : job.bakes)
    if (starts(job.name + "." + e.stem + ".stage-")) return true;
  return false;
}

}  // namespace hfbake
