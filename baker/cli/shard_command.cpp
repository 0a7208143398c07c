#include "cli/shard_command.hpp"

#include <time.h>

#include <algorithm>
#include <charconv>
#include <chrono>
#include <optional>
#include <set>
#include <string_view>

#include "cli/method_dispatch.hpp"
#include "cli/outputs.hpp"
#include "cli/progress.hpp"
#include "cli/scene_inputs.hpp"
#include "cli/scene_loader.hpp"
#include "cli/version.hpp"
#include "core/error.hpp"
#include "core/safe_file.hpp"
#include "farm/build_id.hpp"
#include "farm/merge_blocks.hpp"
#include "job/content_hash.hpp"
#include "methods/method_table.hpp"
#include "reference/bake_reference.hpp"

namespace hfbake {
namespace fs = std::filesystem;

namespace {

ShardIdentity identity_of(const Job& job, ShardId id, int width, int height) {
  return shard_identity(job, id, width, height);
}

// This process as the owner of a temporary shard file: <pid>+<start>@<host> (as staging folders name it).
// Rows [r0, r1) of a whole-field LayerSet.
LayerSet rows_of(const LayerSet& all, int r0, int r1) {
  LayerSet out;
  out.width = all.width, out.height = r1 - r0;
  out.attributes = all.attributes;
  for (const Layer& l : all.layers) {
    Layer& d = out.add(l.name, l.channels);
    const std::size_t row = std::size_t(all.width) * l.channels.size();
    std::copy(l.data.begin() + std::ptrdiff_t(row * r0), l.data.begin() + std::ptrdiff_t(row * r1),
              d.data.begin());
  }
  return out;
}

// A part's layers as the header lists them: (name, channels); a per-block layer "<name>@<k>" by its name
// before the '@' (its channels are its block's directions).
std::vector<std::pair<std::string, std::size_t>> layout_of(const ShardPart& part) {
  std::vector<std::pair<std::string, std::size_t>> out;
  for (const auto& l : part.layers) {
    const std::string n = l.at("name").get<std::string>();
    const std::size_t at = n.find('@');
    out.emplace_back(n.substr(0, at), at == std::string::npos ? l.at("channels").size() : 0);
  }
  return out;
}

// Layers as a message names them: "ao 1, horizon 16" (name and channel count).
std::string layout_text(const std::vector<std::pair<std::string, std::size_t>>& layout) {
  std::string s;
  for (const auto& [name, channels] : layout)
    s += (s.empty() ? "" : ", ") + name + " " + std::to_string(channels);
  return s.empty() ? "none" : s;
}

// The shard count in the name of a shard file of job `job` (<job>.shard-<i>-of-<n>.hfshard, i and n decimal
// digits that fit an int), or nullopt for any other name.
std::optional<int> shard_count_in_name(const std::string& name, const std::string& job) {
  const std::string head = job + ".shard-", tail = ".hfshard";
  if (name.size() <= head.size() + tail.size() || name.compare(0, head.size(), head) != 0 ||
      name.compare(name.size() - tail.size(), tail.size(), tail) != 0)
    return std::nullopt;
  const std::string_view mid(name.data() + head.size(), name.size() - head.size() - tail.size());
  const std::size_t of = mid.find("-of-");
  if (of == std::string_view::npos) return std::nullopt;
  auto number = [](std::string_view t) -> std::optional<int> {
    int v = 0;
    const auto [end, ec] = std::from_chars(t.data(), t.data() + t.size(), v);
    if (t.empty() || ec != std::errc() || end != t.data() + t.size() || t.front() == '-') return std::nullopt;
    return v;
  };
  if (!number(mid.substr(0, of))) return std::nullopt;
  return number(mid.substr(of + 4));
}

}  // namespace

std::string shard_version() {
  const std::string id = executable_build_id();
  return id.empty() ? std::string(hfbake_version())
                    : std::string(hfbake_version()) + "+build." + id.substr(0, 16);
}

ShardIdentity shard_identity(const Job& job, ShardId id, int width, int height) {
  ShardIdentity identity;
  identity.job_name = job.name, identity.job_hash = job_content_hash(job), identity.version = shard_version();
  identity.id = id, identity.width = width, identity.height = height;
  return identity;
}

ShardIdentity stage_identity(const Job& job, int entry, int stage, int width, int height) {
  const BakeEntry& e = job.bakes[std::size_t(entry)];
  ShardIdentity id = shard_identity(job, {stage, entry_stages(e)}, width, height);
  id.what = "stage " + std::to_string(stage) + " of " + e.stem;
  id.part_entry = entry, id.part_kind = "stage", id.part_block = stage;
  // A whole stage's file is its task's own piece; a divided stage's is made from its blocks by the next
  // stage's tasks (stage_state_to_rebuild), whose re-run makes it again.
  if (entry_stage_blocks(e, stage) == 0)
    id.redo = "bake it again with --stage " + std::to_string(stage) +
              " --shard I/N, I = " + std::to_string(entry) + " mod N";
  else
    id.redo = "bake stage " + std::to_string(stage + 1) + " again, --stage " + std::to_string(stage + 1) +
              " with every --shard I/N: it makes this file from the blocks of stage " + std::to_string(stage);
  return id;
}

bool stage_state_to_rebuild(const Job& job, int entry, int stage, int width, int height) {
  const BakeEntry& e = job.bakes[std::size_t(entry)];
  if (stage <= 0 || stage >= entry_stages(e) || entry_stage_blocks(e, stage - 1) == 0) return false;
  // The state after `stage` as a complete file: nothing reads the state before it any more.
  if (shard_is_complete(stage_path(job, entry, stage), stage_identity(job, entry, stage, width, height)))
    return false;
  return !shard_is_complete(stage_path(job, entry, stage - 1),
                            stage_identity(job, entry, stage - 1, width, height));
}

ShardIdentity stage_item_identity(const Job& job, int stage, StageItem item, int width, int height) {
  if (item.block < 0) return stage_identity(job, item.entry, stage, width, height);
  const BakeEntry& e = job.bakes[std::size_t(item.entry)];
  ShardIdentity id = shard_identity(job, {item.block, entry_stage_blocks(e, stage)}, width, height);
  id.what = "direction block " + std::to_string(item.block) + " of stage " + std::to_string(stage) + " of " +
            e.stem;
  id.part_entry = item.entry, id.part_kind = "stage-block", id.part_block = item.block, id.part_stage = stage;
  id.redo = "bake it with --stage " + std::to_string(stage) + " and the --shard I/N that holds the block";
  return id;
}

StageSources::StageSources(const Job& job, int entry, int stage, int width, int height)
    : job_(job), entry_(entry), stage_(stage) {
  const ShardIdentity whole = stage_identity(job, entry, stage, width, height);
  const int B = entry_stage_blocks(job.bakes[std::size_t(entry)], stage);
  if (B == 0 || shard_is_complete(stage_path(job, entry, stage), whole)) {
    state_.emplace(stage_path(job, entry, stage), whole);
    return;
  }
  // Every block of the stage, then the state before it (none before stage 0).
  for (int b = 0; b < B; ++b)
    blocks_.emplace_back(stage_block_path(job, entry, stage, b),
                         stage_item_identity(job, stage, {entry, b}, width, height));
  if (stage > 0)
    state_.emplace(stage_path(job, entry, stage - 1), stage_identity(job, entry, stage - 1, width, height));
}

double StageSources::seconds() const {
  double s = state_ ? state_->parts().at(0).seconds : 0;
  for (const ShardReader& r : blocks_) s += r.parts().at(0).seconds;
  return s;
}

double StageSources::cpu_seconds() const {
  double s = state_ ? state_->parts().at(0).cpu_seconds : 0;
  for (const ShardReader& r : blocks_) s += r.parts().at(0).cpu_seconds;
  return s;
}

LayerSet StageSources::load(const Scene& scene, const RunControl& rc) {
  LayerSet state = state_ ? state_->load(0) : LayerSet();
  if (blocks_.empty()) return state;
  LayerSet total;
  for (ShardReader& r : blocks_) add_direction_block(total, r.load(0));  // in block order
  const BakeEntry& e = job_.bakes[std::size_t(entry_)];
  const MethodConfig& c = entry_config(e);
  try {
    return c.method->finish_stage_blocks(scene, c, stage_, std::move(state), std::move(total), rc);
  } catch (const InputError&) {
    throw;
  } catch (const std::runtime_error& err) {
    // The blocks passed their checksums but do not fit together (a block moved from another stage): name
    // the files, the first and the state they were added to.
    const std::string state_file = state_ ? ", added to " + state_->file().string() : "";
    throw InputError(blocks_.front().file().string(), "",
                     std::string(err.what()) + " (this stage's " + std::to_string(blocks_.size()) +
                         " direction block files" + state_file +
                         "): bake the stage's blocks again with --stage " + std::to_string(stage_));
  }
}

fs::path bake_shard(const Job& job, ShardId id, Progress& progress, const std::atomic<bool>& cancel,
                    JobOutcome& outcome, const ReferenceCache* cache, int stage) {
  const FieldSize size = probe_field_size(job);
  const ShardIdentity identity = identity_of(job, id, size.width, size.height);
  const fs::path path = shard_path(job, id);
  const std::string label = job.name + " [shard " + shard_id_text(id) + "]";
  const ShardWork work = shard_work(job, size.height, id);
  {  // shards/ is written and cleaned: a link there would take both outside the output folder
    std::error_code ec;
    fs::create_directories(path.parent_path(), ec);
    if (!is_real_directory(path.parent_path()))
      throw InputError(job.file.string(), job.output.dir_key,
                       path.parent_path().string() +
                           " is not a folder (a link?): outputs are written inside " +
                           job.output.dir.string() + " only");
  }
  for (const fs::path& p : remove_stale_temporaries(path.parent_path()))
    progress.message(label + ": removed " + p.string() + " (left by a process that no longer runs)");
  // The staged entries' pieces of stage `stage` (stage 0 beside the shard's other work) not yet complete,
  // and the entries whose pieces are complete but whose state before the stage is to be made again.
  const std::vector<StageItem> items = stage_work(job, id, stage);
  std::vector<StageItem> todo;
  for (const StageItem& item : items)
    if (!shard_is_complete(stage_item_path(job, stage, item),
                           stage_item_identity(job, stage, item, size.width, size.height)))
      todo.push_back(item);
  std::vector<int> rebuild;
  for (const StageItem& item : items) {
    const int e = item.entry;
    if ((rebuild.empty() || rebuild.back() != e) &&
        std::none_of(todo.begin(), todo.end(), [e](const StageItem& t) { return t.entry == e; }) &&
        stage_state_to_rebuild(job, e, stage, size.width, size.height))
      rebuild.push_back(e);
  }
  const bool shard_done = stage > 0 || shard_is_complete(path, identity);
  if (shard_done && todo.empty() && rebuild.empty()) {
    progress.message(label + (stage > 0 ? " stage " + std::to_string(stage) : std::string()) +
                     ": nothing to bake (complete or no such stage)");
    return stage > 0 ? fs::path() : path;
  }
  // The state before the stage of each entry with work or to rebuild (its file, or the files it is merged
  // from), checked before loading anything.
  std::map<int, StageSources> previous;
  auto open_previous = [&](int e) {
    if (!previous.count(e))
      previous.emplace(std::piecewise_construct, std::forward_as_tuple(e),
                       std::forward_as_tuple(job, e, stage - 1, size.width, size.height));
  };
  if (stage > 0)
    for (const StageItem& item : todo) open_previous(item.entry);
  for (const int e : rebuild) open_previous(e);
  progress.begin(job.name, "load");
  const auto t_load = std::chrono::steady_clock::now();
  const Scene scene = load_scene(job, [&](double f) { progress.update(job.name, "load", f); });
  progress.end(job.name, "load", seconds_since(t_load));

  // A step's run control (cancel flag, progress under the step's name), its progress line begun.
  auto begin_step = [&](const std::string& step) {
    RunControl rc;
    rc.cancel = &cancel;
    rc.progress = [&progress, &job, step](double f) { progress.update(job.name, step, f); };
    progress.begin(job.name, step);
    return rc;
  };
  // The state before the stage of entry e: its file, or merged from the blocks and written as that stage's
  // file, so that later readers find it whole.
  auto load_state = [&](int e) {
    StageSources& src = previous.at(e);
    if (!src.merged()) return src.load(scene, RunControl{});
    const std::string step = job.bakes[std::size_t(e)].stem + "@stage" + std::to_string(stage - 1);
    const RunControl rc = begin_step(step);
    const auto t0 = std::chrono::steady_clock::now();
    LayerSet merged = src.load(scene, rc);
    ShardWriter w(stage_path(job, e, stage - 1), stage_identity(job, e, stage - 1, size.width, size.height),
                  temporary_owner());
    ShardPart part;
    part.entry = e, part.kind = "stage", part.block = stage - 1;
    part.seconds = src.seconds(), part.cpu_seconds = src.cpu_seconds();
    w.add(std::move(part), merged);
    if (cancel.load()) throw Cancelled();
    w.commit();
    progress.end(job.name, step, seconds_since(t0));
    return merged;
  };
  for (const int e : rebuild) {
    if (cancel.load()) throw Cancelled();
    load_state(e);
  }
  // The state before the stage, per entry: loaded once.
  int state_entry = -1;
  LayerSet state;
  double state_seconds = 0, state_cpu = 0;
  for (std::size_t t = 0; t < todo.size(); ++t) {
    if (cancel.load()) throw Cancelled();
    const StageItem item = todo[t];
    const int e = item.entry;
    const BakeEntry& entry = job.bakes[std::size_t(e)];
    const MethodInfo* m = find_method(entry.method);
    if (stage > 0 && state_entry != e) {
      state_entry = e;
      state_seconds = previous.at(e).seconds(), state_cpu = previous.at(e).cpu_seconds();
      state = load_state(e);
    }
    const std::string step = entry.stem + "@stage" + std::to_string(stage) +
                             (item.block >= 0 ? "#" + std::to_string(item.block) : std::string());
    const RunControl rc = begin_step(step);
    const auto t0 = std::chrono::steady_clock::now();
    const double cpu0 = process_cpu_seconds();
    ShardWriter writer(stage_item_path(job, stage, item),
                       stage_item_identity(job, stage, item, size.width, size.height), temporary_owner());
    ShardPart part;
    part.entry = e, part.kind = item.block < 0 ? "stage" : "stage-block";
    part.block = item.block < 0 ? stage : item.block;
    part.stage = item.block < 0 ? 0 : stage;
    // A whole stage's file: the seconds of this stage and the earlier ones (the merge reports the entry's
    // total); a block's: its own.
    double seconds = 0, cpu = 0;
    if (item.block < 0) seconds = state_seconds, cpu = state_cpu;
    // The state for this piece: the last piece of the entry takes it, the others a copy.
    const bool last_of_entry = t + 1 == todo.size() || todo[t + 1].entry != e;
    LayerSet prev;
    if (stage > 0) prev = last_of_entry ? std::move(state) : LayerSet(state);
    const LayerSet out =
        item.block < 0
            ? m->bake_stage(scene, entry_config(entry), stage, std::move(prev), rc)
            : m->bake_stage_block(scene, entry_config(entry), stage, item.block, std::move(prev), rc);
    if (last_of_entry) state_entry = -1, state = LayerSet();
    part.seconds = seconds + seconds_since(t0), part.cpu_seconds = cpu + process_cpu_seconds() - cpu0;
    progress.end(job.name, step, part.seconds);
    outcome.methods[step] = {{"seconds", part.seconds}, {"cpu_seconds", part.cpu_seconds}};
    writer.add(std::move(part), out);
    if (cancel.load()) throw Cancelled();
    writer.commit();
  }
  if (shard_done && todo.empty()) return stage_path(job, rebuild.front(), stage - 1);
  if (shard_done) return stage > 0 ? stage_item_path(job, stage, todo.front()) : path;

  ShardWriter writer(path, identity, temporary_owner());
  auto run = [&](const std::string& step, ShardPart part, auto&& compute) {
    if (cancel.load()) throw Cancelled();
    const RunControl rc = begin_step(step);
    const auto t0 = std::chrono::steady_clock::now();
    const double cpu0 = process_cpu_seconds();
    const LayerSet layers = compute(rc);
    part.seconds = seconds_since(t0), part.cpu_seconds = process_cpu_seconds() - cpu0;
    progress.end(job.name, step, part.seconds);
    outcome.methods[step] = {{"seconds", part.seconds}, {"cpu_seconds", part.cpu_seconds}};
    writer.add(std::move(part), layers);
  };
  for (const ShardWork::Entry& e : work.entries) {
    const BakeEntry& entry = job.bakes[std::size_t(e.entry)];
    if (e.whole) {
      ShardPart part;
      part.entry = e.entry, part.kind = "whole";
      run(entry.stem, part, [&](const RunControl& rc) { return run_method(entry, scene, rc); });
      continue;
    }
    const MethodInfo* m = find_method(entry.method);
    for (int b = e.block_begin; b < e.block_end; ++b) {
      ShardPart part;
      part.entry = e.entry, part.kind = "block", part.block = b;
      run(entry.stem + "#" + std::to_string(b), part,
          [&](const RunControl& rc) { return m->bake_block(scene, entry_config(entry), b, rc); });
    }
  }
  if (work.row_end > work.row_begin) {
    ShardPart part;
    part.entry = -1, part.kind = "rows", part.row_begin = work.row_begin, part.row_end = work.row_end;
    run("reference", part, [&](const RunControl& rc) {
      if (cache) {
        ReferenceCache::Entry cached;
        if (cache->load(reference_cache_key(job), cached) == CacheLookup::hit &&
            cached.layers.width == size.width && cached.layers.height == size.height)
          return rows_of(cached.layers, work.row_begin, work.row_end);
      }
      ReferenceOptions o = job_reference_options(job);
      o.row_begin = work.row_begin, o.row_end = work.row_end;
      return bake_reference(scene, o, rc);
    });
  }
  if (cancel.load()) throw Cancelled();
  writer.commit();
  return path;
}

namespace {

// The shard counts in the names of the job's shard files in its shards folder; InputError when the folder is
// there but not a real folder.
std::set<int> shard_counts_in_folder(const Job& job) {
  const fs::path dir = job.output.dir / "shards";
  std::set<int> counts;
  std::error_code ec;
  if (fs::exists(fs::symlink_status(dir, ec)) && !is_real_directory(dir))
    throw InputError(dir.string(), "",
                     "is not a folder (a file or a link): the shards are read from inside " +
                         job.output.dir.string() + " only");
  for (const auto& f : fs::directory_iterator(dir, ec))
    if (const auto n = shard_count_in_name(f.path().filename().string(), job.name)) counts.insert(*n);
  return counts;
}

}  // namespace

void check_shards_folder(const Job& job, int count) {
  for (const int c : shard_counts_in_folder(job))
    if (c != count)
      throw InputError((job.output.dir / "shards").string(), "",
                       "holds shards of job " + job.name + " for " + std::to_string(c) +
                           " shards, which a merge of " + std::to_string(count) +
                           " would refuse: remove them (" + job.name + ".shard-*-of-" + std::to_string(c) +
                           ".hfshard) or give --shards " + std::to_string(c));
}

MergedShards::MergedShards(const Job& job, int width, int height) : job_(job), height_(height) {
  // How many shards: from the names in the shards folder (one count only).
  const fs::path dir = job.output.dir / "shards";
  const std::set<int> counts = shard_counts_in_folder(job);
  if (counts.empty())
    throw InputError(dir.string(), "", "no shards of job " + job.name + " (bake them with --shard I/N)");
  if (counts.size() > 1) {
    std::string list;
    for (int c : counts) list += (list.empty() ? "" : ", ") + std::to_string(c);
    throw InputError(dir.string(), "",
                     "shards of job " + job.name + " for different shard counts (" + list +
                         "): remove the ones of the count not wanted");
  }
  count_ = *counts.begin();
  // Staged entries: their last stage's file, whichever shard made it.
  for (std::size_t e = 0; e < job.bakes.size(); ++e)
    if (const int S = entry_stages(job.bakes[e]); S > 0)
      stages_.emplace(std::piecewise_construct, std::forward_as_tuple(int(e)),
                      std::forward_as_tuple(job, int(e), S - 1, width, height));
  for (int i = 0; i < count_; ++i) {
    const ShardId id{i, count_};
    readers_.emplace_back(shard_path(job, id), identity_of(job, id, width, height));
    // The parts must be those this hfbake's plan gives the shard.
    // In the writer's order: each entry whole or its blocks, then the reference's rows.
    const ShardWork w = shard_work(job, height, id);
    std::vector<ShardPart> expect;
    auto part = [&](int entry, const char* kind, int block, int row_begin, int row_end) {
      ShardPart p;
      p.entry = entry, p.kind = kind, p.block = block, p.row_begin = row_begin, p.row_end = row_end;
      expect.push_back(std::move(p));
    };
    for (const ShardWork::Entry& e : w.entries) {
      if (e.whole) part(e.entry, "whole", 0, 0, 0);
      for (int b = e.block_begin; !e.whole && b < e.block_end; ++b) part(e.entry, "block", b, 0, 0);
    }
    if (w.row_end > w.row_begin) part(-1, "rows", 0, w.row_begin, w.row_end);
    const std::vector<ShardPart>& parts = readers_.back().parts();
    bool same = parts.size() == expect.size();
    for (std::size_t p = 0; same && p < parts.size(); ++p) {
      const ShardPart &a = parts[p], &b = expect[p];
      same = a.entry == b.entry && a.kind == b.kind && (a.kind != "block" || a.block == b.block) &&
             (a.kind != "rows" || (a.row_begin == b.row_begin && a.row_end == b.row_end));
    }
    if (!same)
      throw InputError(
          readers_.back().file().string(), "",
          "shard " + shard_id_text(id) + " holds other parts than this job's plan: bake it again");
    // The parts' layers must be the plan's too: a whole entry's are its resolved layers with their channels;
    // the direction blocks of an entry (and the reference's row bands) all have one layout, the first
    // one's, each layer once, whose layers the method's finish_blocks then takes by name and size.
    for (const ShardPart& part : parts) {
      const auto layout = layout_of(part);
      const std::string where =
          part.entry < 0 ? std::string("/reference") : job.bakes[std::size_t(part.entry)].pointer;
      auto refuse = [&](const std::string& want) {
        throw InputError(readers_.back().file().string(), "",
                         "shard " + shard_id_text(id) + ": the part of " + where +
                             " holds layers and channels (" + layout_text(layout) +
                             ") other than this job's plan (" + want + "): bake it again");
      };
      if (part.kind == "whole") {
        const MethodConfig& config = entry_config(job.bakes[std::size_t(part.entry)]);
        std::vector<std::pair<std::string, std::size_t>> want;
        for (const std::string& n : config.layers)
          want.emplace_back(n, std::size_t(layer_channel_count(n, config.directions)));
        if (layout != want) refuse(layout_text(want));
        continue;
      }
      std::set<std::string> names;
      for (const auto& l : layout)
        if (!names.insert(l.first).second) refuse("each layer once");
      const auto [first, inserted] = part_layouts_.emplace(part.entry, layout);
      if (!inserted && first->second != layout) refuse(layout_text(first->second));
    }
  }
}

LayerSet MergedShards::method(int entry, const Scene& scene, const RunControl& rc) {
  const BakeEntry& e = job_.bakes[std::size_t(entry)];
  const int B = entry_direction_blocks(e);
  if (auto st = stages_.find(entry); st != stages_.end())
    return entry_config(e).method->finish_stages(scene, entry_config(e), st->second.load(scene, rc), rc);
  LayerSet total;
  for (ShardReader& r : readers_)
    for (std::size_t p = 0; p < r.parts().size(); ++p) {
      const ShardPart& part = r.parts()[p];
      if (part.entry != entry) continue;
      if (part.kind == "whole") return r.load(p);
      add_direction_block(total, r.load(p));  // shards hold ascending blocks; shards in order
    }
  if (B == 0 || total.layers.empty())
    throw InputError(job_.file.string(), e.pointer, "no shard holds " + e.stem);
  try {
    return entry_config(e).method->finish_blocks(scene, entry_config(e), std::move(total), rc);
  } catch (const InputError& x) {
    if (!x.file().empty()) throw;
    // The blocks' layers (take_block_layer, place_block_layers): the shards are what is wrong.
    throw InputError((job_.output.dir / "shards").string(), e.pointer, x.what());
  }
}

LayerSet MergedShards::reference() {
  std::vector<LayerSet> bands;
  for (ShardReader& r : readers_)
    for (std::size_t p = 0; p < r.parts().size(); ++p)
      if (r.parts()[p].entry == -1) bands.push_back(r.load(p));
  return stack_row_bands(std::move(bands), height_);
}

double MergedShards::seconds(int entry) const {
  if (auto st = stages_.find(entry); st != stages_.end()) return st->second.seconds();
  double s = 0;
  for (const ShardReader& r : readers_)
    for (const ShardPart& p : r.parts())
      if (p.entry == entry) s += p.seconds;
  return s;
}

double MergedShards::cpu_seconds(int entry) const {
  if (auto st = stages_.find(entry); st != stages_.end()) return st->second.cpu_seconds();
  double s = 0;
  for (const ShardReader& r : readers_)
    for (const ShardPart& p : r.parts())
      if (p.entry == entry) s += p.cpu_seconds;
  return s;
}

}  // namespace hfbake
