// The shard file: what one `hfbake bake JOB --shard I/N` computed, for `hfbake merge`.
//
// Layout: the magic line "hfbake shard 2\n"; the parts' float data (little-endian float32, each layer's
// values as in memory), written as each part is computed; then one line of JSON (the header: the job's
// name and content hash, the hfbake version, I, N, the field's size, and per part its entry, kind, block
// or rows, seconds, layers with their byte offsets and an FNV-1a checksum of its bytes), and a line with the
// FNV-1a checksum of the header's line; then a 24-byte trailer: "hfbake shard end" and the header's offset
// as 8 little-endian bytes. A file is written under a temporary name beside its final one and renamed when
// complete, so a shard file is whole or absent; the trailer and the header's and each part's checksums catch
// a file truncated or damaged afterwards.
//
// A shard file is read as untrusted input: only a regular file is opened (never blocking on a FIFO), and
// every part's claims (its kind, size, rows, layers' channels, floats and offsets) must match the job's
// field and lie inside the file before anything is allocated from them.
#pragma once

#include <cstdint>
#include <filesystem>
#include <memory>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "core/layers.hpp"
#include "core/safe_file.hpp"
#include "farm/shard_plan.hpp"

namespace hfbake {

// What identifies the job a shard belongs to (checked by the merge).
struct ShardIdentity {
  std::string job_name, job_hash, version;
  ShardId id;
  int width = 0, height = 0;
  // For messages: what the file is ("shard I/N" when empty) and how to make it again ("bake it with
  // --shard I/N" when empty).
  std::string what, redo;
  // A file of one piece (a stage's state, a stage's direction block): that piece's entry, kind and block,
  // which its one part must have. part_entry -2: a shard, whose parts the merge checks against the plan.
  int part_entry = -2;
  std::string part_kind;
  int part_block = 0, part_stage = 0;
};

struct ShardPart {
  int entry = -1;                  // index into Job::bakes; -1: the reference
  std::string kind;                // "whole", "block", "rows"
  int block = 0;                   // kind "block", "stage-block"; kind "stage": the stage
  int stage = 0;                   // kind "stage-block": the stage the block is of
  int row_begin = 0, row_end = 0;  // kind "rows"
  double seconds = 0, cpu_seconds = 0;
  nlohmann::json layers = nlohmann::json::array();  // header: per layer name, channels, offset, checksum
  std::vector<std::pair<std::string, std::string>> attributes;
  int width = 0, height = 0;
};

class ShardWriter {
 public:
  // Opens a temporary file of its own beside `final_path` (creating its folder), named
  // <final>.tmp-<owner>-XXXXXX (default owner: <pid>@<host>); std::runtime_error if impossible.
  ShardWriter(std::filesystem::path final_path, ShardIdentity identity, std::string owner = "");
  ~ShardWriter();  // removes the temporary file unless committed
  ShardWriter(const ShardWriter&) = delete;
  ShardWriter& operator=(const ShardWriter&) = delete;
  // Appends a part's layers (written now; `part` gives everything but the layers).
  void add(ShardPart part, const LayerSet& layers);
  // Writes the header and the trailer and renames the file into place.
  void commit();

 private:
  std::filesystem::path final_;
  ShardIdentity identity_;
  std::unique_ptr<TempFile> out_;
  bool ok_ = true;  // every write so far succeeded
  std::uint64_t offset_ = 0;
  std::vector<ShardPart> parts_;
};

class ShardReader {
 public:
  // Reads the header. Throws InputError naming the file: missing, truncated or damaged, of another job
  // (job hash or name), another hfbake version, or another shard than `expected`.
  ShardReader(const std::filesystem::path& file, const ShardIdentity& expected);
  ~ShardReader();
  ShardReader(ShardReader&& other) noexcept;
  ShardReader& operator=(ShardReader&&) = delete;
  ShardReader(const ShardReader&) = delete;
  const std::vector<ShardPart>& parts() const { return parts_; }
  // Loads part i's layers and attributes; InputError naming the file when a checksum fails, with the advice
  // that makes the file again (ShardIdentity::redo).
  LayerSet load(std::size_t i);
  const std::filesystem::path& file() const { return file_; }

 private:
  void read_header(const ShardIdentity& expected);  // opens file_ into fd_ and reads the parts
  std::filesystem::path file_;
  int fd_ = -1;
  std::vector<ShardPart> parts_;
  std::string which_, redo_;  // what the file is and what makes it again, as the errors say them
};

// Whether `file` is a complete shard of `expected` (the check a re-run does to skip a finished shard).
bool shard_is_complete(const std::filesystem::path& file, const ShardIdentity& expected);

}  // namespace hfbake
