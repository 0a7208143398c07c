// Files and names hfbake does not own, against the hfbake binary: the farm's shard files with forged claims
// or a FIFO in their place; links planted at the temporary names and staging folders hfbake uses; two
// processes writing one job name into one folder; a suite waiting for another's suite lock. Each must end in
// one error line (or a documented behaviour: docs/output_folders.md), with nothing written outside the folder
// asked for and nothing lost.
#include <fcntl.h>
#include <grp.h>
#include <gtest/gtest.h>
#include <poll.h>
#include <signal.h>
#include <sys/file.h>
#include <sys/inotify.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <OpenImageIO/imageio.h>
#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <nlohmann/json.hpp>
#include <random>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include "child_process.hpp"

namespace {
namespace fs = std::filesystem;
using nlohmann::json;

struct Outcome {
  int exit_code = 0;
  std::string err;
  std::vector<std::string> error_lines() const {
    std::vector<std::string> lines;
    std::istringstream in(err);
    for (std::string l; std::getline(in, l);)
      if (l.rfind("hfbake: error: ", 0) == 0) lines.push_back(l.substr(15));
    return lines;
  }
};

// In a child about to exec hfbake: the preload library that holds chosen renames (slow_rename.cpp). Under
// AddressSanitizer its runtime must come first, so the link-order check is turned off, added to the options
// the suite runs with (which it keeps).
void preload_slow_rename() {
  setenv("LD_PRELOAD", HFBAKE_SLOW_RENAME, 1);
  const char* asan = std::getenv("ASAN_OPTIONS");
  const std::string options =
      (asan && *asan ? std::string(asan) + ":" : std::string()) + "verify_asan_link_order=0";
  setenv("ASAN_OPTIONS", options.c_str(), 1);
}

std::string read_text(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

// The job file an owner record names: its first line (the outputs it lists follow).
std::string record_owner(const fs::path& p) {
  const std::string text = read_text(p);
  return text.substr(0, text.find('\n'));
}

// The job hash an EXR output records ("" when it cannot be read).
std::string exr_job_hash(const fs::path& exr) {
  auto in = OIIO::ImageInput::open(exr.string());
  return in ? std::string(in->spec().get_string_attribute("hfbake:job_hash")) : std::string();
}

// Starts `hfbake args` in `dir` (stderr to err_name); `in_child` runs in the child before exec (it knows
// the process id hfbake will have). A hang is killed by SIGALRM after 120 s.
pid_t start(const fs::path& dir, const std::vector<std::string>& args, const std::string& err_name,
            const std::function<void()>& in_child = {}) {
  return hfbake_test::start_hfbake(args, dir / err_name, dir, 120, in_child);
}

Outcome finish(pid_t pid, const fs::path& dir, const std::string& err_name) {
  int status = 0;
  waitpid(pid, &status, 0);
  Outcome r;
  r.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -WTERMSIG(status);
  r.err = read_text(dir / err_name);
  return r;
}

Outcome hfbake(const fs::path& dir, const std::vector<std::string>& args,
               const std::function<void()>& in_child = {}) {
  return finish(start(dir, args, "stderr.txt", in_child), dir, "stderr.txt");
}

// Two bakes of job files ja and jb started together in `dir`: exactly one must bake (exit 0) and the other be
// refused (exit 2) in one error line. Returns the winner's pid and job file, and the loser's error line.
struct Race {
  pid_t winner_pid = 0;
  std::string winner, lost_line;
};
Race race(const fs::path& dir, const std::string& ja, const std::string& jb) {
  const pid_t pa = start(dir, {"bake", ja, "--no-cache", "--quiet"}, "a.txt");
  const pid_t pb = start(dir, {"bake", jb, "--no-cache", "--quiet"}, "b.txt");
  const Outcome ra = finish(pa, dir, "a.txt"), rb = finish(pb, dir, "b.txt");
  Race r;
  EXPECT_TRUE((ra.exit_code == 0 && rb.exit_code == 2) || (ra.exit_code == 2 && rb.exit_code == 0))
      << ra.err << rb.err;
  const Outcome& lost = ra.exit_code == 2 ? ra : rb;
  r.winner = ra.exit_code == 0 ? ja : jb;
  r.winner_pid = ra.exit_code == 0 ? pa : pb;
  const auto lines = lost.error_lines();
  EXPECT_EQ(lines.size(), 1u) << lost.err;
  if (!lines.empty()) r.lost_line = lines[0];
  return r;
}

json base_job(const std::string& out = "out") {
  return {{"version", 1},
          {"name", "t"},
          {"height", {{"procedural", {{"kind", "fractal"}, {"size", {16, 16}}}}}},
          {"bake", {{{"method", "p1"}, {"directions", 4}}}},
          {"output", {{"dir", out}}}};
}

std::string write_job(const fs::path& dir, const json& j, const std::string& name = "job.json") {
  std::ofstream(dir / name) << j.dump(2);
  return (dir / name).string();
}

class Untrusted : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("hfbake_untrusted_" + std::to_string(std::random_device{}()));
    fs::create_directories(dir_ / "outside");
    std::ofstream(dir_ / "outside" / "victim") << "keep";
  }
  void TearDown() override { fs::remove_all(dir_); }
  // The folder outside the outputs is as the test made it.
  void expect_outside_untouched() {
    EXPECT_EQ(read_text(dir_ / "outside" / "victim"), "keep");
    int n = 0;
    for (const auto& e : fs::recursive_directory_iterator(dir_ / "outside")) n += e.is_regular_file();
    EXPECT_EQ(n, outside_files_);
  }
  // Two job files of one name (t) baking into dir_/out, a/t.json and b/t.json (another seed): their paths.
  std::pair<std::string, std::string> two_job_files_of_one_name() {
    json a = base_job("../out"), b = base_job("../out");
    b["height"]["procedural"]["seed"] = 5;
    fs::create_directories(dir_ / "a");
    fs::create_directories(dir_ / "b");
    return {write_job(dir_ / "a", a), write_job(dir_ / "b", b)};
  }
  fs::path dir_;
  int outside_files_ = 1;
};

// --- the farm's files -----------------------------------------------------------------------------------

// A shard's header line (farm/shard_file.hpp: the JSON line, then its checksum's line, then the 24-byte
// trailer) and where it starts.
std::string shard_header_line(const std::string& bytes, std::uint64_t& at) {
  at = 0;
  for (int b = 0; b < 8; ++b)
    at |= std::uint64_t(static_cast<unsigned char>(bytes[bytes.size() - 8 + b])) << (8 * b);
  const std::string text = bytes.substr(at, bytes.size() - 24 - at);
  return text.substr(0, text.rfind('\n', text.size() - 2) + 1);
}

json shard_header(const std::string& bytes, std::uint64_t& at) {
  return json::parse(shard_header_line(bytes, at));
}

// The shard's bytes with `line` (a header line ending in a newline) in place of its header, sealed with the
// line's FNV-1a checksum as the writer seals it: the forged claims are what the merge reads.
std::string with_sealed_header(const std::string& bytes, std::uint64_t at, const std::string& line) {
  std::uint64_t h = 0xcbf29ce484222325ull;
  for (const unsigned char c : line) h = (h ^ c) * 0x100000001b3ull;
  char hex[17];
  std::snprintf(hex, sizeof hex, "%016llx", static_cast<unsigned long long>(h));
  return bytes.substr(0, at) + line + hex + "\n" + bytes.substr(bytes.size() - 24);
}

void forge_part_size(const fs::path& shard, long long width, long long height) {
  std::string bytes = read_text(shard);
  std::uint64_t at = 0;
  json h = shard_header(bytes, at);
  for (json& p : h["parts"]) {
    p["width"] = width, p["height"] = height;
    for (json& l : p["layers"]) l["floats"] = width * height * (long long)l["channels"].size();
  }
  bytes = with_sealed_header(bytes, at, h.dump() + "\n");
  std::ofstream(shard, std::ios::binary | std::ios::trunc) << bytes;
}

// The seconds a shard's parts claim are summed into the report: a value no part could have taken (each is in
// [0, 1e9), docs/cluster.md) is refused by the merge in one line naming the shard, and nothing is written.
TEST_F(Untrusted, ShardSecondsOutsideTheirRangeAreRefusedByTheMerge) {
  json j = base_job();
  j["reference"] = {{"samples", 4}};
  const std::string job = write_job(dir_, j);
  ASSERT_EQ(hfbake(dir_, {"bake", job, "--shard", "0/1", "--no-cache", "--quiet"}).exit_code, 0);
  const fs::path shard = dir_ / "out" / "shards" / "t.shard-0-of-1.hfshard";
  const std::string genuine = read_text(shard);
  for (const double seconds : {1e308, -5.0}) {
    SCOPED_TRACE(seconds);
    std::uint64_t at = 0;
    json h = shard_header(genuine, at);
    for (json& p : h["parts"]) p["seconds"] = seconds;
    std::ofstream(shard, std::ios::binary | std::ios::trunc)
        << with_sealed_header(genuine, at, h.dump() + "\n");
    const Outcome r = hfbake(dir_, {"merge", job, "--no-cache", "--quiet"});
    EXPECT_EQ(r.exit_code, 2);
    ASSERT_EQ(r.error_lines().size(), 1u) << r.err;
    EXPECT_NE(r.error_lines()[0].find(shard.string()), std::string::npos) << r.err;
    EXPECT_NE(r.error_lines()[0].find("seconds"), std::string::npos) << r.err;
    EXPECT_FALSE(fs::exists(dir_ / "out" / "report.json"));
  }
  std::ofstream(shard, std::ios::binary | std::ios::trunc) << genuine;
  ASSERT_EQ(hfbake(dir_, {"merge", job, "--no-cache", "--quiet"}).exit_code, 0);
  const json report = json::parse(read_text(dir_ / "out" / "report.json"));
  EXPECT_TRUE(report["methods"]["p1"]["seconds"].is_number()) << report["methods"]["p1"];
}

TEST_F(Untrusted, ShardPartsClaimingAnotherSizeAreRefusedByTheMerge) {
  const std::string job = write_job(dir_, base_job());
  ASSERT_EQ(hfbake(dir_, {"bake", job, "--shard", "0/1", "--no-cache", "--quiet"}).exit_code, 0);
  const fs::path shard = dir_ / "out" / "shards" / "t.shard-0-of-1.hfshard";
  ASSERT_TRUE(fs::is_regular_file(shard));
  const std::string genuine = read_text(shard);
  // 1x1 made the merge read past its buffers (SIGSEGV); 100000 x 100000 allocate 40 GB a layer.
  for (const auto& [w, h] : std::vector<std::pair<long long, long long>>{{1, 1}, {100000, 100000}, {16, 1}}) {
    SCOPED_TRACE(std::to_string(w) + "x" + std::to_string(h));
    std::ofstream(shard, std::ios::binary | std::ios::trunc) << genuine;
    forge_part_size(shard, w, h);
    const Outcome r = hfbake(dir_, {"merge", job, "--no-cache", "--quiet"});
    EXPECT_EQ(r.exit_code, 2) << r.err;
    const auto lines = r.error_lines();
    ASSERT_EQ(lines.size(), 1u) << r.err;
    EXPECT_EQ(lines[0].rfind(shard.string() + ": ", 0), 0u) << lines[0];
    EXPECT_NE(lines[0].find("of another size than the field's 16x16"), std::string::npos) << lines[0];
    EXPECT_FALSE(fs::exists(dir_ / "out" / "t.p1.exr"));
  }
  std::ofstream(shard, std::ios::binary | std::ios::trunc) << genuine;
  const Outcome r = hfbake(dir_, {"merge", job, "--no-cache", "--quiet"});
  EXPECT_EQ(r.exit_code, 0) << r.err;
}

// The shard's bytes with its header text replaced by edit(header text), sealed again; the header stays where
// it was.
std::string with_header_text(const std::string& bytes, const std::function<std::string(std::string)>& edit) {
  std::uint64_t at = 0;
  const std::string text = shard_header_line(bytes, at);
  return with_sealed_header(bytes, at, edit(text));
}

// A shard's header is read by the parser of every JSON file hfbake reads: a key given twice, at the top or in
// a part, is refused in one line naming the shard and the key, never resolved by its last value.
TEST_F(Untrusted, ShardHeaderKeysGivenTwiceAreRefusedByTheMerge) {
  const std::string job = write_job(dir_, base_job());
  ASSERT_EQ(hfbake(dir_, {"bake", job, "--shard", "0/1", "--no-cache", "--quiet"}).exit_code, 0);
  const fs::path shard = dir_ / "out" / "shards" / "t.shard-0-of-1.hfshard";
  const std::string genuine = read_text(shard);
  const std::vector<std::pair<std::string, std::string>> forgeries = {
      {"/job", "{\"job\":\"zzz\","}, {"/parts/0/entry", "\"parts\":[{\"entry\":5,"}};
  for (const auto& [key, insert] : forgeries) {
    SCOPED_TRACE(key);
    std::ofstream(shard, std::ios::binary | std::ios::trunc) << with_header_text(genuine, [&](std::string t) {
      const std::string head = insert.substr(0, insert.find('{') + 1);
      const std::size_t at = t.find(head);
      EXPECT_NE(at, std::string::npos) << t;
      return t.replace(at, head.size(), insert);
    });
    const Outcome r = hfbake(dir_, {"merge", job, "--no-cache", "--quiet"});
    EXPECT_EQ(r.exit_code, 2) << r.err;
    const auto lines = r.error_lines();
    ASSERT_EQ(lines.size(), 1u) << r.err;
    EXPECT_EQ(lines[0].rfind(shard.string() + ": ", 0), 0u) << lines[0];
    EXPECT_NE(lines[0].find(key + ": duplicate key"), std::string::npos) << lines[0];
    EXPECT_FALSE(fs::exists(dir_ / "out" / "t.p1.exr"));
  }
  std::ofstream(shard, std::ios::binary | std::ios::trunc) << genuine;
  EXPECT_EQ(hfbake(dir_, {"merge", job, "--no-cache", "--quiet"}).exit_code, 0);
}

// A p2 stage's direction block moved into the next stage (its header's stage rewritten and sealed again):
// its checksums hold, but its sums are another stage's (the last bounce sends no facet light). The merge
// refuses it in one line naming a block file of the stage and the stage to bake again.
TEST_F(Untrusted, AStageBlockMovedToAnotherStageIsRefusedNamingTheFiles) {
  json j = base_job();
  j["bounces"] = 2;
  j["bake"] = {{{"method", "p2"}, {"directions", 8}}};
  const std::string job = write_job(dir_, j);
  const fs::path shards = dir_ / "out" / "shards";
  for (int stage = 0; stage <= 2; ++stage) {
    ASSERT_EQ(hfbake(dir_, {"bake", job, "--shard", "0/1", "--stage", std::to_string(stage), "--no-cache",
                            "--quiet"})
                  .exit_code,
              0);
    if (stage == 1) fs::copy_file(shards / "t.p2.stage-1.block-0.hfshard", dir_ / "stage1_block0");
  }
  const fs::path target = shards / "t.p2.stage-2.block-0.hfshard";
  ASSERT_TRUE(fs::exists(target));
  std::string bytes = read_text(dir_ / "stage1_block0");
  std::uint64_t at = 0;
  json h = shard_header(bytes, at);
  ASSERT_EQ(h["parts"][0]["stage"], 1) << h.dump();
  h["parts"][0]["stage"] = 2;
  std::ofstream(target, std::ios::binary | std::ios::trunc) << with_sealed_header(bytes, at, h.dump() + "\n");
  const Outcome r = hfbake(dir_, {"merge", job, "--no-cache", "--quiet"});
  EXPECT_EQ(r.exit_code, 2) << r.err;
  const auto lines = r.error_lines();
  ASSERT_EQ(lines.size(), 1u) << r.err;
  EXPECT_EQ(lines[0].rfind(shards.string() + "/t.p2.stage-2.block-", 0), 0u) << lines[0];
  EXPECT_NE(lines[0].find("--stage 2"), std::string::npos) << lines[0];
  EXPECT_FALSE(fs::exists(dir_ / "out" / "t.p2.exr"));
}

// A link to nothing where a shard goes is a missing shard: refused with the advice that makes it, and the
// bake that makes it replaces the link.
TEST_F(Untrusted, ADanglingLinkAtAShardsNameIsAMissingShard) {
  const std::string job = write_job(dir_, base_job());
  for (const char* s : {"0/2", "1/2"})
    ASSERT_EQ(hfbake(dir_, {"bake", job, "--shard", s, "--no-cache", "--quiet"}).exit_code, 0);
  const fs::path shard = dir_ / "out" / "shards" / "t.shard-1-of-2.hfshard";
  ASSERT_TRUE(fs::exists(shard));
  fs::remove(shard);
  fs::create_symlink(dir_ / "nowhere", shard);
  const Outcome r = hfbake(dir_, {"merge", job, "--no-cache", "--quiet"});
  EXPECT_EQ(r.exit_code, 2) << r.err;
  const auto lines = r.error_lines();
  ASSERT_EQ(lines.size(), 1u) << r.err;
  EXPECT_EQ(lines[0].rfind(shard.string() + ": ", 0), 0u) << lines[0];
  EXPECT_NE(lines[0].find("is missing (a link to nothing stands there; bake it with --shard 1/2)"),
            std::string::npos)
      << lines[0];
  ASSERT_EQ(hfbake(dir_, {"bake", job, "--shard", "1/2", "--no-cache", "--quiet"}).exit_code, 0);
  EXPECT_FALSE(fs::is_symlink(shard));
  EXPECT_EQ(hfbake(dir_, {"merge", job, "--no-cache", "--quiet"}).exit_code, 0);
}

// A header field missing or of the wrong kind is refused in one line naming the shard and the field's JSON
// pointer, with no parser library's text.
TEST_F(Untrusted, ShardHeaderFieldsOfTheWrongKindAreRefusedNamingTheField) {
  const std::string job = write_job(dir_, base_job());
  ASSERT_EQ(hfbake(dir_, {"bake", job, "--shard", "0/1", "--no-cache", "--quiet"}).exit_code, 0);
  const fs::path shard = dir_ / "out" / "shards" / "t.shard-0-of-1.hfshard";
  const std::string genuine = read_text(shard);
  const std::vector<std::pair<std::string, std::function<void(json&)>>> forgeries = {
      {"/parts/0/attributes is not an array", [](json& h) { h["parts"][0]["attributes"] = json::object(); }},
      {"/parts/0/attributes/0 is not a pair of strings",
       [](json& h) {
         h["parts"][0]["attributes"] = {{1, 2}};
       }},
      {"/parts/0/kind is not a string", [](json& h) { h["parts"][0]["kind"] = 3; }},
      {"/parts/0/layers/0/channels is not an array",
       [](json& h) { h["parts"][0]["layers"][0]["channels"] = "Y"; }},
      {"/parts/0/layers/0 is not an object", [](json& h) { h["parts"][0]["layers"][0] = 1; }},
      {"/parts/0 is not an object", [](json& h) { h["parts"][0] = "p"; }},
      {"/parts is not an array", [](json& h) { h["parts"] = 5; }},
      {"/job is not a string", [](json& h) { h["job"] = 7; }},
      {"no header field /job_hash", [](json& h) { h.erase("job_hash"); }},
      {"a header that is no JSON object", [](json& h) { h = json::array(); }}};
  for (const auto& [what, edit] : forgeries) {
    SCOPED_TRACE(what);
    std::ofstream(shard, std::ios::binary | std::ios::trunc)
        << with_header_text(genuine, [&](const std::string& t) {
             json h = json::parse(t);
             edit(h);
             return h.dump() + "\n";
           });
    const Outcome r = hfbake(dir_, {"merge", job, "--no-cache", "--quiet"});
    EXPECT_EQ(r.exit_code, 2) << r.err;
    const auto lines = r.error_lines();
    ASSERT_EQ(lines.size(), 1u) << r.err;
    EXPECT_EQ(lines[0].rfind(shard.string() + ": ", 0), 0u) << lines[0];
    EXPECT_NE(lines[0].find(what), std::string::npos) << lines[0];
    EXPECT_EQ(lines[0].find("json.exception"), std::string::npos) << lines[0];
    EXPECT_FALSE(fs::exists(dir_ / "out" / "t.p1.exr"));
  }
  std::ofstream(shard, std::ios::binary | std::ios::trunc) << genuine;
  EXPECT_EQ(hfbake(dir_, {"merge", job, "--no-cache", "--quiet"}).exit_code, 0);
}

// Rewrites every part's layer list in the header, sealed again: the layers' checksums cover their data, not
// their names.
void forge_layers(const fs::path& shard, const std::function<void(json&)>& edit) {
  std::string bytes = read_text(shard);
  std::uint64_t at = 0;
  json h = shard_header(bytes, at);
  for (json& p : h["parts"]) edit(p["layers"]);
  bytes = with_sealed_header(bytes, at, h.dump() + "\n");
  std::ofstream(shard, std::ios::binary | std::ios::trunc) << bytes;
}

// Layers renamed, dropped or duplicated in a shard's header: a whole entry's (nlp) must be its resolved
// layers, a direction block's (p1, hbao: the raw sums its finish reads by name) must be there with their
// sizes. Each made the merge read through a missing layer (SIGSEGV) or write the renamed layers.
TEST_F(Untrusted, ShardLayersOtherThanThePlanAreRefusedByTheMerge) {
  const std::vector<std::pair<std::string, std::function<void(json&)>>> forgeries = {
      {"renamed", [](json& l) { l[0]["name"] = "bogus"; }},
      {"dropped", [](json& l) { l.erase(l.size() - 1); }},
      {"duplicated", [](json& l) { l[l.size() - 1]["name"] = l[0]["name"]; }}};
  for (const std::string method : {"nlp", "p1", "hbao"}) {
    json j = base_job();
    j["bake"] = {{{"method", method}}};
    const std::string job = write_job(dir_, j);
    fs::remove_all(dir_ / "out");
    ASSERT_EQ(hfbake(dir_, {"bake", job, "--shard", "0/1", "--no-cache", "--quiet"}).exit_code, 0);
    const fs::path shard = dir_ / "out" / "shards" / "t.shard-0-of-1.hfshard";
    const std::string genuine = read_text(shard);
    for (const auto& [what, edit] : forgeries) {
      SCOPED_TRACE(method + ", " + what);
      std::ofstream(shard, std::ios::binary | std::ios::trunc) << genuine;
      forge_layers(shard, edit);
      const Outcome r = hfbake(dir_, {"merge", job, "--no-cache", "--quiet"});
      EXPECT_EQ(r.exit_code, 2) << r.err;
      const auto lines = r.error_lines();
      ASSERT_EQ(lines.size(), 1u) << r.err;
      EXPECT_EQ(lines[0].rfind((dir_ / "out" / "shards").string(), 0), 0u) << lines[0];
      EXPECT_NE(lines[0].find("/bake/0"), std::string::npos) << lines[0];
      EXPECT_NE(lines[0].find("bake "), std::string::npos) << lines[0];  // what to do
      EXPECT_FALSE(fs::exists(dir_ / "out" / ("t." + method + ".exr")));
    }
    std::ofstream(shard, std::ios::binary | std::ios::trunc) << genuine;
    EXPECT_EQ(hfbake(dir_, {"merge", job, "--no-cache", "--quiet"}).exit_code, 0) << method;
  }
}

TEST_F(Untrusted, AFifoWhereAShardBelongsNeverBlocks) {
  const std::string job = write_job(dir_, base_job());
  fs::create_directories(dir_ / "out" / "shards");
  const fs::path shard = dir_ / "out" / "shards" / "t.shard-0-of-1.hfshard";
  ASSERT_EQ(mkfifo(shard.c_str(), 0600), 0);
  const Outcome merge = hfbake(dir_, {"merge", job, "--no-cache", "--quiet"});
  EXPECT_EQ(merge.exit_code, 2) << merge.err;
  const auto lines = merge.error_lines();
  ASSERT_EQ(lines.size(), 1u) << merge.err;
  EXPECT_NE(lines[0].find(shard.string() + ": cannot read shard 0/1: not a regular file (a FIFO)"),
            std::string::npos)
      << lines[0];
  // bake --shard takes the FIFO for an incomplete shard and puts its file in its place.
  const Outcome bake = hfbake(dir_, {"bake", job, "--shard", "0/1", "--no-cache", "--quiet"});
  EXPECT_EQ(bake.exit_code, 0) << bake.err;
  EXPECT_TRUE(fs::is_regular_file(fs::symlink_status(shard)));
}

// --- temporary names and staging folders ------------------------------------------------------------------

// Links at every name hfbake used to derive from its process id: --summary's, the suite's suite.json's, the
// reference cache entry's and compare --update-baseline's temporaries. hfbake's own temporaries are new
// files; the links are left alone and never written through.
TEST_F(Untrusted, LinksAtPredictableTemporaryNamesAreNotFollowed) {
  json j = base_job();
  j["reference"] = {{"samples", 4}, {"seed", 1}};
  fs::create_directories(dir_ / "jobs");
  write_job(dir_ / "jobs", j);
  const json suite = {
      {"version", 1}, {"suite", "s"}, {"jobs", {"jobs/job.json"}}, {"output", {{"dir", "suite_out"}}}};
  const std::string suite_file = write_job(dir_, suite, "suite.json");
  fs::create_directories(dir_ / "suite_out");
  fs::create_directories(dir_ / "cache");
  const fs::path victim = dir_ / "outside" / "victim";
  const std::vector<std::string> args = {"bake",
                                         suite_file,
                                         "--cache",
                                         (dir_ / "cache").string(),
                                         "--quiet",
                                         "--summary",
                                         (dir_ / "summary.json").string()};
  // A first bake names the reference's cache entry; it is removed so that the second writes it again.
  ASSERT_EQ(hfbake(dir_, args).exit_code, 0);
  std::string entry;
  for (const auto& e : fs::recursive_directory_iterator(dir_ / "cache"))
    if (e.path().extension() == ".hfref") entry = e.path().string();
  ASSERT_FALSE(entry.empty());
  fs::remove(entry);
  auto plant = [&, victim, entry] {
    const std::string pid = std::to_string(getpid());
    fs::create_symlink(victim, dir_ / ("summary.json.tmp-" + pid));
    fs::create_symlink(victim, dir_ / "suite_out" / ("suite.json.tmp-" + pid));
    for (int k = 0; k < 4; ++k) fs::create_symlink(victim, entry + ".tmp-" + pid + "-" + std::to_string(k));
  };
  const Outcome r = hfbake(dir_, args, plant);
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_TRUE(json::parse(read_text(dir_ / "summary.json")).is_object());
  EXPECT_TRUE(fs::is_regular_file(fs::symlink_status(entry)));
  EXPECT_TRUE(fs::is_regular_file(fs::symlink_status(dir_ / "suite_out" / "suite.json")));
  expect_outside_untouched();

  // compare --update-baseline: the baseline's temporary.
  fs::create_directories(dir_ / "base");
  const fs::path report = dir_ / "suite_out" / "job" / "report.json";
  ASSERT_TRUE(fs::exists(report));
  fs::copy_file(report, dir_ / "base" / "report.json");
  const Outcome c = hfbake(
      dir_,
      {"compare", report.string(), (dir_ / "base" / "report.json").string(), "--update-baseline", "--quiet"},
      [&, victim] {
        fs::create_symlink(victim, dir_ / "base" / ("report.json.tmp-" + std::to_string(getpid())));
      });
  EXPECT_EQ(c.exit_code, 0) << c.err;
  EXPECT_TRUE(fs::is_regular_file(fs::symlink_status(dir_ / "base" / "report.json")));
  expect_outside_untouched();
}

// A process id that no longer runs (reaped).
pid_t dead_pid() {
  const pid_t pid = fork();
  if (pid == 0) _exit(0);
  waitpid(pid, nullptr, 0);
  return pid;
}

std::string host() {
  char h[256] = {};
  gethostname(h, sizeof h - 1);
  return h;
}

// A dead owner's staging folder that is a link, or whose checkpoint folder is: the next bake took every
// *.hfckpt out of the link's target and deleted it with the stage. Now the links are removed, their targets
// untouched.
TEST_F(Untrusted, StagingFoldersThatAreLinksAreRemovedNotFollowed) {
  fs::create_directories(dir_ / "outside" / "reference-checkpoint");
  std::ofstream(dir_ / "outside" / "reference-checkpoint" / "band-0.hfckpt") << "someone's data";
  std::ofstream(dir_ / "outside" / "band-1.hfckpt") << "someone else's";
  outside_files_ = 3;
  fs::create_directories(dir_ / "out");
  const std::string pid = std::to_string(dead_pid());
  const fs::path stage_link = dir_ / "out" / (".hfbake-staging-t-" + pid + "+1@" + host());
  fs::create_symlink(dir_ / "outside", stage_link);
  const fs::path stage = dir_ / "out" / (".hfbake-staging-t-" + pid + "+2@" + host());
  fs::create_directories(stage);
  fs::create_directory_symlink(dir_ / "outside", stage / "reference-checkpoint");
  json j = base_job();
  j["reference"] = {{"samples", 4}, {"seed", 1}};
  const Outcome r = hfbake(dir_, {"bake", write_job(dir_, j), "--no-cache", "--quiet"});
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_FALSE(fs::exists(fs::symlink_status(stage_link)));
  EXPECT_FALSE(fs::exists(fs::symlink_status(stage)));
  expect_outside_untouched();
}

// A dead process's stage whose commit list names textures/keep.txt, with textures/ in the stage a link to
// a folder outside: the next bake completes no move through it (the file stays where it is).
TEST_F(Untrusted, AKilledStagesMovesNeverGoThroughALinkInTheStage) {
  fs::create_directories(dir_ / "outside");
  std::ofstream(dir_ / "outside" / "keep.txt") << "someone's data";
  outside_files_ = 2;
  fs::create_directories(dir_ / "out" / "textures");
  const fs::path stage = dir_ / "out" / (".hfbake-staging-t-" + std::to_string(dead_pid()) + "+1@" + host());
  fs::create_directories(stage);
  fs::create_directory_symlink(dir_ / "outside", stage / "textures");
  std::ofstream(stage / "commit-list") << "textures/keep.txt\n";
  const Outcome r = hfbake(dir_, {"bake", write_job(dir_, base_job()), "--no-cache", "--quiet"});
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_FALSE(fs::exists(dir_ / "out" / "textures" / "keep.txt"));
  expect_outside_untouched();
}

// A baseline folder whose report.json is a link: compared as its own folder's report (not as its target's,
// which would count the report new and the target missing), and --update-baseline replaces the link by the
// new report, leaving its target as it was. A metric of another type than a number is a damaged report, not
// a new metric.
TEST_F(Untrusted, ABaselineReportThatIsALinkIsComparedAndReplacedInItsFolder) {
  json j = base_job();
  j["reference"] = {{"samples", 4}, {"seed", 1}};
  ASSERT_EQ(hfbake(dir_, {"bake", write_job(dir_, j), "--no-cache", "--quiet"}).exit_code, 0);
  const std::string report = read_text(dir_ / "out" / "report.json");
  fs::create_directories(dir_ / "U" / "j1");
  fs::create_directories(dir_ / "V" / "j1");
  fs::create_directories(dir_ / "V" / "store");
  std::ofstream(dir_ / "U" / "j1" / "report.json") << report;
  std::ofstream(dir_ / "V" / "store" / "x.json") << report;
  fs::create_symlink("../store/x.json", dir_ / "V" / "j1" / "report.json");
  Outcome r = hfbake(dir_, {"compare", (dir_ / "U").string(), (dir_ / "V").string()});
  EXPECT_EQ(r.exit_code, 0) << r.err;
  r = hfbake(dir_, {"compare", (dir_ / "U").string(), (dir_ / "V").string(), "--update-baseline", "--quiet"});
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_TRUE(fs::is_regular_file(fs::symlink_status(dir_ / "V" / "j1" / "report.json")));
  EXPECT_EQ(read_text(dir_ / "V" / "j1" / "report.json"), report);
  EXPECT_EQ(read_text(dir_ / "V" / "store" / "x.json"), report);

  json damaged = json::parse(report);
  bool changed = false;
  for (auto& [stem, m] : damaged["methods"].items())
    for (auto& [layer, metrics] : m["layers"].items())
      if (!changed && metrics.contains("mae")) metrics["mae"] = "x", changed = true;
  ASSERT_TRUE(changed);
  std::ofstream(dir_ / "V" / "j1" / "report.json") << damaged.dump();
  r = hfbake(dir_, {"compare", (dir_ / "U").string(), (dir_ / "V").string()});
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_NE(r.err.find("/mae: must be a number (it is a string)"), std::string::npos) << r.err;
  expect_outside_untouched();
}

// compare --json never replaces what the comparison reads or --update-baseline writes (the new report, the
// baseline, a link to either, the baseline folder's report-to-be), refused in one line before anything is
// compared; into folders that do not exist yet it is written, the folders made.
TEST_F(Untrusted, CompareJsonNeverReplacesAReportAndMakesItsFolders) {
  json j = base_job();
  j["reference"] = {{"samples", 4}, {"seed", 1}};
  ASSERT_EQ(hfbake(dir_, {"bake", write_job(dir_, j), "--no-cache", "--quiet"}).exit_code, 0);
  const std::string report = read_text(dir_ / "out" / "report.json");
  fs::create_directories(dir_ / "U" / "j1"), fs::create_directories(dir_ / "U" / "j2");
  fs::create_directories(dir_ / "V" / "j1");
  for (const char* f : {"U/j1/report.json", "U/j2/report.json", "V/j1/report.json", "a.json", "b.json"})
    std::ofstream(dir_ / f) << report;
  fs::create_symlink("b.json", dir_ / "link.json");
  const std::string a = (dir_ / "a.json").string(), b = (dir_ / "b.json").string();
  const std::string U = (dir_ / "U").string(), V = (dir_ / "V").string();
  const std::vector<std::vector<std::string>> refused{
      {"compare", a, b, "--json", b},
      {"compare", a, b, "--json", a},
      {"compare", a, b, "--json", (dir_ / "link.json").string()},
      {"compare", a, (dir_ / "c.json").string(), "--update-baseline", "--json", (dir_ / "c.json").string()},
      {"compare", U, V, "--json", (dir_ / "V" / "j1" / "report.json").string()},
      {"compare", U, V, "--update-baseline", "--json", (dir_ / "V" / "j2" / "report.json").string()},
      {"compare", a, b, "--json", (dir_ / "a.json" / "x.json").string()}};
  for (const auto& args : refused) {
    const Outcome r = hfbake(dir_, args);
    EXPECT_EQ(r.exit_code, 2) << args.back() << ": " << r.err;
    EXPECT_EQ(r.err.rfind("hfbake: error: " + args.back() + ": --json: ", 0), 0u) << r.err;
    EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
  }
  for (const char* f : {"U/j1/report.json", "U/j2/report.json", "V/j1/report.json", "a.json", "b.json"})
    EXPECT_EQ(read_text(dir_ / f), report) << f;
  EXPECT_FALSE(fs::exists(dir_ / "c.json"));
  EXPECT_FALSE(fs::exists(dir_ / "V" / "j2"));

  const fs::path deep = dir_ / "results" / "night" / "cmp.json";
  const Outcome r = hfbake(dir_, {"compare", a, b, "--json", deep.string()});
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_FALSE(json::parse(read_text(deep))["regression"].get<bool>());
  expect_outside_untouched();
}

// A report whose values break schemas/report.schema.json (a negative error, a missing metric, a key hfbake
// never writes) is refused by compare, and as a job's report.baseline by validate, before anything is baked:
// one line naming the file and the field. A forged baseline would otherwise decide what counts as a
// regression.
TEST_F(Untrusted, ADamagedReportIsRefusedByCompareAndAsABaselineByValidate) {
  json j = base_job();
  j["reference"] = {{"samples", 4}, {"seed", 1}};
  ASSERT_EQ(hfbake(dir_, {"bake", write_job(dir_, j), "--no-cache", "--quiet"}).exit_code, 0);
  const json report = json::parse(read_text(dir_ / "out" / "report.json"));
  const std::string stem = report["methods"].begin().key();
  const std::string layer = report["methods"][stem]["layers"].begin().key();
  const std::string metrics = "/methods/" + stem + "/layers/" + layer;
  struct Damage {
    std::string pointer, what;
    std::function<void(json&)> apply;
  };
  const std::vector<Damage> damages = {
      {metrics + "/mae", "must be >= 0", [&](json& d) { d["methods"][stem]["layers"][layer]["mae"] = -1.0; }},
      {metrics, "missing required key \"rmse\"",
       [&](json& d) { d["methods"][stem]["layers"][layer].erase("rmse"); }},
      {"/job/forged", "unknown key", [&](json& d) { d["job"]["forged"] = 1; }},
      {metrics + "/rmse", "must be at most 6.80565e+38 in magnitude",
       [&](json& d) { d["methods"][stem]["layers"][layer]["rmse"] = 1e308; }},
  };
  fs::create_directories(dir_ / "base");
  for (const Damage& damage : damages) {
    json d = report;
    damage.apply(d);
    std::ofstream(dir_ / "base" / "report.json") << d.dump();
    const std::string base = (dir_ / "base" / "report.json").string();
    Outcome r = hfbake(dir_, {"compare", (dir_ / "out" / "report.json").string(), base});
    EXPECT_EQ(r.exit_code, 2) << r.err;
    EXPECT_NE(r.err.find(base + ": " + damage.pointer + ": " + damage.what), std::string::npos) << r.err;

    json with_baseline = j;
    with_baseline["output"]["dir"] = "out2";
    with_baseline["report"] = {{"baseline", "base/report.json"}};
    const std::string job = write_job(dir_, with_baseline, "b.json");
    for (const std::string command : {"validate", "bake"}) {
      r = hfbake(dir_, command == "bake" ? std::vector<std::string>{"bake", job, "--no-cache", "--quiet"}
                                         : std::vector<std::string>{"validate", job, "--quiet"});
      EXPECT_EQ(r.exit_code, 2) << command << ": " << r.err;
      EXPECT_NE(r.err.find(job + ": /report/baseline: " + base + ": " + damage.pointer + ": " + damage.what),
                std::string::npos)
          << command << ": " << r.err;
    }
    EXPECT_FALSE(fs::exists(dir_ / "out2"));
  }
  expect_outside_untouched();
}

// out/textures as a link: the textures would land in its target.
TEST_F(Untrusted, ATexturesFolderThatIsALinkIsRefused) {
  fs::create_directories(dir_ / "out");
  fs::create_directory_symlink(dir_ / "outside", dir_ / "out" / "textures");
  json j = base_job();
  j["output"]["textures"] = {{{"layers", {"ao"}}}};
  const Outcome r = hfbake(dir_, {"bake", write_job(dir_, j), "--no-cache", "--quiet"});
  EXPECT_EQ(r.exit_code, 2) << r.err;
  const auto lines = r.error_lines();
  ASSERT_EQ(lines.size(), 1u) << r.err;
  // Refused before anything is baked, naming the job file and the key (validate says the same).
  EXPECT_NE(lines[0].find("job.json: /output/textures: " + (dir_ / "out" / "textures").string() +
                          " is not a folder (a link)"),
            std::string::npos)
      << lines[0];
  expect_outside_untouched();
}

// A textures folder this process cannot write into: validate and bake refuse it at /output/textures, saying
// that it cannot be written, before anything is baked. Run as root, the commands run as nobody (uid 65534),
// whom permissions bind.
TEST_F(Untrusted, ATexturesFolderThatCannotBeWrittenIsRefused) {
  const fs::path textures = dir_ / "out" / "textures";
  fs::create_directories(textures);
  const fs::perms read_only = fs::perms::owner_read | fs::perms::owner_exec | fs::perms::group_read |
                              fs::perms::group_exec | fs::perms::others_read | fs::perms::others_exec;
  fs::permissions(dir_, read_only | fs::perms::owner_write);
  fs::permissions(dir_ / "out", fs::perms::all);
  fs::permissions(textures, read_only);
  json j = base_job();
  j["bake"][0]["layers"] = {"ao"};
  j["output"]["textures"] = json::array({{{"layers", {"ao"}}}});
  const std::string job = write_job(dir_, j);
  fs::permissions(job, read_only);
  const auto as_nobody = [] {
    if (geteuid() == 0 && (setgroups(0, nullptr) != 0 || setgid(65534) != 0 || setuid(65534) != 0))
      _exit(126);
  };
  for (const std::string command : {"validate", "bake"}) {
    const Outcome r =
        hfbake(dir_,
               command == "bake" ? std::vector<std::string>{"bake", job, "--no-cache", "--quiet"}
                                 : std::vector<std::string>{"validate", job, "--quiet"},
               as_nobody);
    EXPECT_EQ(r.exit_code, 2) << command << ": " << r.err;
    const auto lines = r.error_lines();
    ASSERT_EQ(lines.size(), 1u) << command << ": " << r.err;
    EXPECT_EQ(lines[0],
              job + ": /output/textures: cannot write into " + textures.string() + ": Permission denied")
        << command;
    EXPECT_TRUE(fs::is_empty(textures)) << command;
    std::vector<fs::path> out;
    for (const auto& e : fs::directory_iterator(dir_ / "out")) out.push_back(e.path());
    EXPECT_EQ(out, std::vector<fs::path>{textures}) << command;
  }
  fs::permissions(textures, fs::perms::owner_all);
}

// out/shards and out/slurm as links: a shard task, and the scripts and logs of `hfbake slurm`, would land
// in their targets (and the shard task's clean-up of stale temporaries would run there).
TEST_F(Untrusted, ShardAndSlurmFoldersThatAreLinksAreRefused) {
  fs::create_directories(dir_ / "out");
  fs::create_directory_symlink(dir_ / "outside", dir_ / "out" / "shards");
  const std::string job = write_job(dir_, base_job());
  Outcome r = hfbake(dir_, {"bake", job, "--shard", "0/2", "--no-cache", "--quiet"});
  EXPECT_EQ(r.exit_code, 2) << r.err;
  auto lines = r.error_lines();
  ASSERT_EQ(lines.size(), 1u) << r.err;
  EXPECT_NE(lines[0].find(job + ": /output/dir: " + (dir_ / "out" / "shards").string() +
                          " is not a folder (a link)"),
            std::string::npos)
      << lines[0];
  expect_outside_untouched();

  fs::remove(dir_ / "out" / "shards");
  fs::create_directory_symlink(dir_ / "outside", dir_ / "out" / "slurm");
  // No sbatch on PATH: nothing could be submitted, and the scripts are refused before it is looked for.
  r = hfbake(dir_, {"slurm", job, "--shards", "2", "--no-cache"}, [] { setenv("PATH", "/nonexistent", 1); });
  EXPECT_EQ(r.exit_code, 2) << r.err;
  lines = r.error_lines();
  ASSERT_EQ(lines.size(), 1u) << r.err;
  EXPECT_NE(lines[0].find("slurm: not a folder (a link?)"), std::string::npos) << lines[0];
  expect_outside_untouched();
}

// A hard link planted at a job's lock file: opening it without following links still opens the file it
// shares, which the lock would truncate and write its owner into. Refused in one line, the file untouched.
TEST_F(Untrusted, AHardLinkAtTheLockFileIsNeverWritten) {
  fs::create_directories(dir_ / "out");
  fs::create_hard_link(dir_ / "outside" / "victim", dir_ / "out" / ".hfbake-t.lock");
  const std::string job = write_job(dir_, base_job());
  for (const char* command : {"validate", "bake"}) {  // validate finds it before any bake starts
    SCOPED_TRACE(command);
    const Outcome r = hfbake(dir_, {command, job, "--quiet"});
    EXPECT_EQ(r.exit_code, 2) << r.err;
    const auto lines = r.error_lines();
    ASSERT_EQ(lines.size(), 1u) << r.err;
    EXPECT_NE(lines[0].find("is no lock file of hfbake's (a file with another name elsewhere (a hard link))"),
              std::string::npos)
        << lines[0];
  }
  expect_outside_untouched();
}

// A folder where an output goes: the bake fails before any output moves, so the previous bake's outputs
// stay whole (not half old, half new).
TEST_F(Untrusted, AFolderAtAnOutputNameMovesNothing) {
  json j = base_job();
  const std::string job = write_job(dir_, j);
  ASSERT_EQ(hfbake(dir_, {"bake", job, "--no-cache", "--quiet"}).exit_code, 0);
  std::vector<std::pair<fs::path, std::string>> before;
  for (const auto& e : fs::directory_iterator(dir_ / "out"))
    if (e.is_regular_file() && e.path().extension() != ".lock")
      before.push_back({e.path(), read_text(e.path())});
  ASSERT_GE(before.size(), 2u);
  // The owner record: renamed after every output, so a late failure would have replaced them all.
  const fs::path taken = dir_ / "out" / ".hfbake-t.job";
  ASSERT_TRUE(fs::is_regular_file(taken));
  fs::remove(taken);
  fs::create_directory(taken);
  std::erase_if(before, [&](const auto& b) { return b.first == taken; });
  j["height"]["procedural"]["seed"] = 9;  // other heights: every output would change
  const Outcome r = hfbake(dir_, {"bake", write_job(dir_, j), "--no-cache", "--quiet", "--overwrite"});
  EXPECT_EQ(r.exit_code, 2) << r.err;
  const auto lines = r.error_lines();
  ASSERT_EQ(lines.size(), 1u) << r.err;
  EXPECT_NE(lines[0].find("job.json: /output/dir: " + taken.string() + " is a folder where an output goes"),
            std::string::npos)
      << lines[0];
  for (const auto& [file, text] : before) EXPECT_EQ(read_text(file), text) << file;
}

// A folder at the name of a file the bake moves into place (a GeoTIFF, a texture) is refused by validate,
// and by bake before anything is baked, in one line naming the job file and the key; nothing is written. A
// folder at a name the job does not write (a GeoTIFF's, previews off) is left alone.
TEST_F(Untrusted, AFolderAtAnOutputNameIsRefusedBeforeBaking) {
  json j = base_job();
  j["bake"][0]["layers"] = {"ao"};
  j["output"]["geotiff"] = true;
  j["output"]["textures"] = json::array({{{"layers", {"ao"}}}});
  const std::string job = write_job(dir_, j);
  const fs::path tif = dir_ / "out" / "t.p1.ao.tif", png = dir_ / "out" / "textures" / "t.p1.ao.png";
  const fs::path other = dir_ / "out" / "t.p1.ao.preview.png";
  for (const fs::path& folder : {tif, png, other}) fs::create_directories(folder / "sub");
  const auto listing = [&] {
    std::set<std::string> names;
    for (const auto& e : fs::recursive_directory_iterator(dir_ / "out")) names.insert(e.path().string());
    return names;
  };
  for (const auto& [folder, key] : {std::pair<fs::path, std::string>{tif, "/output/dir"},
                                    std::pair<fs::path, std::string>{png, "/output/textures"}}) {
    const std::set<std::string> made = listing();
    for (const std::string command : {"validate", "bake"}) {
      const Outcome r =
          hfbake(dir_, command == "bake" ? std::vector<std::string>{"bake", job, "--no-cache", "--quiet"}
                                         : std::vector<std::string>{"validate", job, "--quiet"});
      EXPECT_EQ(r.exit_code, 2) << command << ": " << r.err;
      const auto lines = r.error_lines();
      ASSERT_EQ(lines.size(), 1u) << command << ": " << r.err;
      EXPECT_EQ(lines[0],
                job + ": " + key + ": " + folder.string() + " is a folder where an output goes: remove it")
          << command;
      EXPECT_EQ(listing(), made) << command;
    }
    fs::remove_all(folder);
  }
  const Outcome r = hfbake(dir_, {"bake", job, "--no-cache", "--quiet"});
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_TRUE(fs::is_regular_file(tif));
  EXPECT_TRUE(fs::is_regular_file(png));
  EXPECT_TRUE(fs::is_directory(other / "sub"));
}

// --- one folder, one owner ----------------------------------------------------------------------------

// A copy of a job file, the same job name and folder: validate refuses it as bake does, before anything is
// baked, naming the file that owns the outputs; with --overwrite both accept it. A textures/ folder the bake
// would have made is not left behind when the bake is refused for a folder at an output's name.
TEST_F(Untrusted, ValidateRefusesAnotherJobFilesOutputsAsBakeDoes) {
  json j = base_job();
  const std::string first = write_job(dir_, j), copy = write_job(dir_, j, "copy.json");
  ASSERT_EQ(hfbake(dir_, {"bake", first, "--no-cache", "--quiet"}).exit_code, 0);
  const Outcome v = hfbake(dir_, {"validate", copy, "--quiet"});
  EXPECT_EQ(v.exit_code, 2) << v.err;
  const auto lines = v.error_lines();
  ASSERT_EQ(lines.size(), 1u) << v.err;
  EXPECT_NE(lines[0].find("copy.json: /name: the outputs of job t in "), std::string::npos) << lines[0];
  EXPECT_NE(lines[0].find(" were baked from " + fs::weakly_canonical(first).string()), std::string::npos)
      << lines[0];
  EXPECT_EQ(hfbake(dir_, {"validate", first, "--quiet"}).exit_code, 0);
  EXPECT_EQ(hfbake(dir_, {"validate", copy, "--quiet", "--overwrite"}).exit_code, 0);

  j["output"]["textures"] = json::array({{{"layers", {"ao"}}}});
  j["bake"][0]["layers"] = {"ao"};
  const std::string textured = write_job(dir_, j);
  fs::remove(dir_ / "out" / "t.p1.exr");
  fs::create_directory(dir_ / "out" / "t.p1.exr");  // where an output goes
  const Outcome r = hfbake(dir_, {"bake", textured, "--no-cache", "--quiet"});
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_FALSE(fs::exists(dir_ / "out" / "textures"));
}

// An owner record that hfbake did not write (a link, even to this job's own record; an empty file) is no
// record of this job file: validate, bake and merge refuse the folder without --overwrite, follow no link,
// and with it replace the link by a record.
TEST_F(Untrusted, ALinkOrAnEmptyFileAtAnOwnerRecordIsNoLicenceToReplaceTheOutputs) {
  const json j = base_job();
  const std::string job = write_job(dir_, j);
  ASSERT_EQ(hfbake(dir_, {"bake", job, "--no-cache", "--quiet"}).exit_code, 0);
  const fs::path record = dir_ / "out" / ".hfbake-t.job", kept = dir_ / "kept.job";
  fs::rename(record, kept);
  const std::string kept_text = read_text(kept);
  fs::create_symlink(kept, record);
  Outcome r = hfbake(dir_, {"validate", job, "--quiet"});
  EXPECT_EQ(r.exit_code, 2) << r.err;
  ASSERT_EQ(r.error_lines().size(), 1u) << r.err;
  EXPECT_NE(r.error_lines()[0].find("were baked from a record that is not hfbake's (" + record.string() +
                                    ", a link): give this job "
                                    "another name or output folder, or give --overwrite"),
            std::string::npos)
      << r.err;
  EXPECT_EQ(hfbake(dir_, {"bake", job, "--no-cache", "--quiet"}).exit_code, 2);
  r = hfbake(dir_, {"bake", job, "--no-cache", "--quiet", "--overwrite"});
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_FALSE(fs::is_symlink(fs::symlink_status(record)));
  EXPECT_EQ(read_text(kept), kept_text);
  std::ofstream(record, std::ios::trunc).close();  // empty
  r = hfbake(dir_, {"validate", job, "--quiet"});
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_NE(r.err.find("were baked from a record that is not hfbake's (" + record.string() + "): give"),
            std::string::npos)
      << r.err;
}

// A job file whose path holds a tab and a newline, or runs past 1024 bytes: its owner record (the path, a
// control character escaped) is its own on the next bake, which replaces the outputs without --overwrite; a
// job file of the same name at another such path is still refused, naming the first one's escaped path.
TEST_F(Untrusted, AJobFileAtAnUnusualPathOwnsItsOutputsAgain) {
  const fs::path odd = dir_ / "tab\there" / "new\nline";
  fs::path deep = dir_;
  for (int i = 0; i < 12; ++i) deep /= std::string(100, char('a' + i));
  for (const fs::path& folder : {odd, deep}) {
    SCOPED_TRACE(folder.string().size());
    fs::create_directories(folder);
    json j = base_job();
    j["output"]["dir"] = (dir_ / "out").string();
    const std::string job = write_job(folder, j);
    for (int run = 0; run < 2; ++run) {
      const Outcome r = hfbake(dir_, {"bake", job, "--no-cache", "--quiet"});
      EXPECT_EQ(r.exit_code, 0) << "run " << run << ": " << r.err;
    }
    fs::create_directories(folder / "second");
    const Outcome other = hfbake(dir_, {"validate", write_job(folder / "second", j), "--quiet"});
    EXPECT_EQ(other.exit_code, 2) << other.err;
    ASSERT_EQ(other.error_lines().size(), 1u) << other.err;
    const std::string line = other.error_lines()[0];
    EXPECT_NE(line.find("were baked from "), std::string::npos) << line;
    EXPECT_NE(
        line.find(folder == odd ? "tab\\x09here/new\\x0aline/job.json" : std::string(100, 'l') + "/job.json"),
        std::string::npos)
        << line;
    fs::remove_all(dir_ / "out");
  }
}

// A shard task of another job file with the same name, into a folder holding the first's outputs: refused in
// one line naming the first file (its merge would refuse the mix), the first's shards kept.
TEST_F(Untrusted, AShardOfAnotherJobFileOverAJobsOutputsIsRefused) {
  const auto [ja, jb] = two_job_files_of_one_name();
  for (const char* shard : {"0/2", "1/2"})
    ASSERT_EQ(hfbake(dir_, {"bake", ja, "--shard", shard, "--no-cache", "--quiet"}).exit_code, 0);
  ASSERT_EQ(hfbake(dir_, {"merge", ja, "--no-cache", "--quiet"}).exit_code, 0);
  const fs::path shard0 = dir_ / "out" / "shards" / "t.shard-0-of-2.hfshard";
  const std::string before = read_text(shard0);
  const Outcome r = hfbake(dir_, {"bake", jb, "--shard", "0/2", "--no-cache", "--quiet"});
  EXPECT_EQ(r.exit_code, 2) << r.err;
  ASSERT_EQ(r.error_lines().size(), 1u) << r.err;
  EXPECT_NE(r.error_lines()[0].find("were baked from " + fs::weakly_canonical(ja).string()),
            std::string::npos)
      << r.err;
  EXPECT_EQ(read_text(shard0), before);
  EXPECT_EQ(hfbake(dir_, {"bake", jb, "--shard", "0/2", "--no-cache", "--quiet", "--overwrite"}).exit_code,
            0);
}

// A job file lying in shards/ under a name a shard task of the job writes (a shard or stage file, the
// shards lock or owner record): validate and bake --shard refuse it in one line naming it, and it is kept.
TEST_F(Untrusted, AnInputWhereAShardTaskWritesIsRefused) {
  const fs::path shards = dir_ / "out" / "shards";
  fs::create_directories(shards);
  for (const std::string name :
       {"t.shard-0-of-2.hfshard", "t.shard-1-of-3.hfshard", "t.p2.stage-0.hfshard",
        "t.p2.stage-1.block-2.hfshard", ".hfbake-t+shards.job", ".hfbake-t+shards.lock"}) {
    SCOPED_TRACE(name);
    json j = base_job("..");
    j["bake"] = {{{"method", "p2"}, {"directions", 4}}};
    const std::string job = write_job(shards, j, name);
    const std::string text = read_text(job);
    for (const std::vector<std::string>& command :
         {std::vector<std::string>{"validate", job, "--quiet"},
          std::vector<std::string>{"bake", job, "--shard", "0/2", "--no-cache", "--quiet"}}) {
      SCOPED_TRACE(command[0]);
      const Outcome r = hfbake(dir_, command);
      EXPECT_EQ(r.exit_code, 2) << r.err;
      const auto lines = r.error_lines();
      ASSERT_EQ(lines.size(), 1u) << r.err;
      EXPECT_NE(lines[0].find(job + " is where this job writes an output"), std::string::npos) << r.err;
      EXPECT_EQ(read_text(job), text);
    }
    fs::remove(job);
  }
}

// The job's name in shards/ has one owner, as in tiles/ (docs/output_folders.md): a shard task of another
// job file with the same name and folder is refused before it bakes, while the first job's shards wait for
// their merge, and so is its merge; the first's shards are kept. Started at the same moment, one job file's
// task bakes and the other's is refused. --overwrite takes the name over.
TEST_F(Untrusted, OneJobNameInShardsHasOneJobFile) {
  const auto [ja, jb] = two_job_files_of_one_name();
  const fs::path shards = dir_ / "out" / "shards";
  const std::string owned_by_a = "/name: the shards of job t in " + fs::weakly_canonical(shards).string() +
                                 " were baked from " + fs::weakly_canonical(ja).string();
  ASSERT_EQ(hfbake(dir_, {"bake", ja, "--shard", "0/2", "--no-cache", "--quiet"}).exit_code, 0);
  const fs::path shard0 = shards / "t.shard-0-of-2.hfshard";
  const std::string before = read_text(shard0);
  for (const std::vector<std::string>& command :
       {std::vector<std::string>{"bake", jb, "--shard", "0/2", "--no-cache", "--quiet"},
        std::vector<std::string>{"bake", jb, "--shard", "1/2", "--no-cache", "--quiet"},
        std::vector<std::string>{"merge", jb, "--no-cache", "--quiet"},
        std::vector<std::string>{"slurm", jb, "--shards", "2", "--dry-run"}}) {
    SCOPED_TRACE(command[0] + " " + command[2]);
    const Outcome r = hfbake(dir_, command);
    EXPECT_EQ(r.exit_code, 2) << r.err;
    const auto lines = r.error_lines();
    ASSERT_EQ(lines.size(), 1u) << r.err;
    EXPECT_NE(lines[0].find(jb + ": " + owned_by_a), std::string::npos) << lines[0];
  }
  EXPECT_EQ(read_text(shard0), before);
  EXPECT_FALSE(fs::exists(shards / "t.shard-1-of-2.hfshard"));
  ASSERT_EQ(hfbake(dir_, {"bake", ja, "--shard", "1/2", "--no-cache", "--quiet"}).exit_code, 0);
  ASSERT_EQ(hfbake(dir_, {"merge", ja, "--no-cache", "--quiet"}).exit_code, 0);

  for (int run = 0; run < 5; ++run) {
    SCOPED_TRACE(run);
    fs::remove_all(dir_ / "out");
    const pid_t pa = start(dir_, {"bake", ja, "--shard", "0/2", "--no-cache", "--quiet"}, "a.txt");
    const pid_t pb = start(dir_, {"bake", jb, "--shard", "1/2", "--no-cache", "--quiet"}, "b.txt");
    const Outcome ra = finish(pa, dir_, "a.txt"), rb = finish(pb, dir_, "b.txt");
    ASSERT_TRUE((ra.exit_code == 0 && rb.exit_code == 2) || (ra.exit_code == 2 && rb.exit_code == 0))
        << ra.err << rb.err;
    const bool a_won = ra.exit_code == 0;
    EXPECT_EQ(read_text(shards / ".hfbake-t+shards.job"), fs::weakly_canonical(a_won ? ja : jb).string());
    EXPECT_NE((a_won ? rb : ra).err.find("were baked from " + fs::weakly_canonical(a_won ? ja : jb).string()),
              std::string::npos)
        << (a_won ? rb : ra).err;
    EXPECT_EQ(fs::exists(shards / "t.shard-0-of-2.hfshard"), a_won);
    EXPECT_EQ(fs::exists(shards / "t.shard-1-of-2.hfshard"), !a_won);
  }
  const Outcome taken = hfbake(dir_, {"bake", jb, "--shard", "0/2", "--no-cache", "--quiet", "--overwrite"});
  EXPECT_EQ(taken.exit_code, 0) << taken.err;
  EXPECT_EQ(read_text(shards / ".hfbake-t+shards.job"), fs::weakly_canonical(jb).string());
}

// Two processes bake different job files with the same name into one folder, 20 times: one bakes (exit
// 0), the other is refused with one line (exit 2: the folder is locked by the first, or holds the first's
// outputs); the winner's outputs are never replaced. --overwrite lets a job take the name over.
TEST_F(Untrusted, TwoJobsOfOneNameInOneFolderNeverReplaceEachOther) {
  const auto [ja, jb] = two_job_files_of_one_name();
  for (int run = 0; run < 20; ++run) {
    SCOPED_TRACE(run);
    fs::remove_all(dir_ / "out");
    const Race r = race(dir_, ja, jb);
    ASSERT_FALSE(r.lost_line.empty());
    // The loser names the folder and who owns it: the running holder (<pid>@<host>), or the job file whose
    // finished outputs are there.
    const std::string folder = fs::weakly_canonical(dir_ / "out").string();
    const std::string& line = r.lost_line;
    EXPECT_NE(line.find(" into " + folder + " now") == std::string::npos
                  ? line.find(" in " + folder + " were baked from " + fs::weakly_canonical(r.winner).string())
                  : line.find("another hfbake process (" + std::to_string(r.winner_pid) + "@" + host() + ")"),
              std::string::npos)
        << line;
    EXPECT_EQ(record_owner(dir_ / "out" / ".hfbake-t.job"), fs::weakly_canonical(r.winner).string());
    auto in = OIIO::ImageInput::open((dir_ / "out" / "t.p1.exr").string());
    ASSERT_TRUE(in);
    for (const auto& e : fs::directory_iterator(dir_ / "out"))
      EXPECT_EQ(e.path().filename().string().rfind(".hfbake-staging-", 0), std::string::npos) << e.path();
  }
  // The same job again replaces its own outputs; the other only with --overwrite.
  const std::string owner = record_owner(dir_ / "out" / ".hfbake-t.job");
  const std::string other = owner == fs::weakly_canonical(ja).string() ? jb : ja;
  EXPECT_EQ(hfbake(dir_, {"bake", owner, "--no-cache", "--quiet"}).exit_code, 0);
  EXPECT_EQ(hfbake(dir_, {"bake", other, "--no-cache", "--quiet"}).exit_code, 2);
  EXPECT_EQ(hfbake(dir_, {"bake", other, "--no-cache", "--quiet", "--overwrite"}).exit_code, 0);
  EXPECT_EQ(record_owner(dir_ / "out" / ".hfbake-t.job"), fs::weakly_canonical(other).string());
}

// report.json and report.html carry no job name: of two jobs of different names, each with a reference,
// started together into one folder, one bakes and the other is refused in one line naming the folder
// (docs/output_folders.md), whichever moment the second reaches its outputs; the report is the winner's.
TEST_F(Untrusted, TwoJobsWithAReferenceInOneFolderNeverReplaceEachOthersReport) {
  json a = base_job("out"), b = base_job("out");
  a["name"] = "a", b["name"] = "b";
  a["reference"] = b["reference"] = {{"samples", 4}};
  const std::string ja = write_job(dir_, a, "a.json"), jb = write_job(dir_, b, "b.json");
  const std::string folder = fs::weakly_canonical(dir_ / "out").string();
  for (int run = 0; run < 10; ++run) {
    SCOPED_TRACE(run);
    fs::remove_all(dir_ / "out");
    const Race r = race(dir_, ja, jb);
    ASSERT_FALSE(r.lost_line.empty());
    EXPECT_NE(r.lost_line.find(folder), std::string::npos) << r.lost_line;
    const json report = json::parse(read_text(dir_ / "out" / "report.json"));
    EXPECT_EQ(report["job"]["name"], r.winner == ja ? "a" : "b");
    for (const auto& e : fs::directory_iterator(dir_ / "out"))
      EXPECT_FALSE(hfbake_test::is_stage(e.path())) << e.path();
  }
}

// One folder under different spellings (a "." part, a trailing "/", a link to it) is one folder: the lock is
// the file in it, whatever path reached it. Of two processes baking different job files named t into it,
// one bakes and the other is refused, 5 times per spelling.
TEST_F(Untrusted, OneFolderUnderAnotherSpellingIsLockedAsOne) {
  fs::create_directories(dir_ / "out");
  fs::create_directory_symlink(dir_ / "out", dir_ / "link");
  json a = base_job("out");
  const std::string ja = write_job(dir_, a, "a.json");
  for (const std::string spelling : {"out/./", "./out/", "link", "link/../out"}) {
    SCOPED_TRACE(spelling);
    json b = base_job(spelling);
    b["height"]["procedural"]["seed"] = 5;
    const std::string jb = write_job(dir_, b, "b.json");
    for (int run = 0; run < 5; ++run) {
      SCOPED_TRACE(run);
      for (const auto& e : fs::directory_iterator(dir_ / "out")) fs::remove_all(e.path());
      const Race r = race(dir_, ja, jb);
      EXPECT_EQ(record_owner(dir_ / "out" / ".hfbake-t.job"), fs::weakly_canonical(r.winner).string());
      EXPECT_EQ(hfbake_test::stages_in(dir_ / "out"), 0);
    }
  }
}

// A folder inside another job's output folder is a folder of its own: two job files named t, baking with
// previews and GeoTIFFs into out and out/sub at once, 5 times, both bake, and each folder holds its own job's
// outputs and record, and no stage.
TEST_F(Untrusted, ANestedOutputFolderIsAFolderOfItsOwn) {
  json a = base_job("out"), b = base_job("out/sub");
  b["height"]["procedural"]["seed"] = 5;
  for (json* j : {&a, &b}) (*j)["output"]["previews"] = (*j)["output"]["geotiff"] = true;
  const std::string ja = write_job(dir_, a, "a.json"), jb = write_job(dir_, b, "b.json");
  for (int run = 0; run < 5; ++run) {
    SCOPED_TRACE(run);
    fs::remove_all(dir_ / "out");
    const pid_t pa = start(dir_, {"bake", ja, "--no-cache", "--quiet"}, "a.txt");
    const pid_t pb = start(dir_, {"bake", jb, "--no-cache", "--quiet"}, "b.txt");
    const Outcome ra = finish(pa, dir_, "a.txt"), rb = finish(pb, dir_, "b.txt");
    EXPECT_EQ(ra.exit_code, 0) << ra.err;
    EXPECT_EQ(rb.exit_code, 0) << rb.err;
    for (const auto& [folder, job] : {std::pair(dir_ / "out", ja), std::pair(dir_ / "out" / "sub", jb)}) {
      EXPECT_EQ(record_owner(folder / ".hfbake-t.job"), fs::weakly_canonical(job).string());
      EXPECT_NE(exr_job_hash(folder / "t.p1.exr"), "");
      EXPECT_TRUE(fs::is_regular_file(folder / "t.p1.ao.tif"));
      EXPECT_EQ(hfbake_test::stages_in(folder), 0);
    }
    EXPECT_NE(exr_job_hash(dir_ / "out" / "t.p1.exr"), exr_job_hash(dir_ / "out" / "sub" / "t.p1.exr"));
  }
}

// A job's output folder inside another's is harmless (their names are in different folders), except the
// textures folder, where a job that writes textures and a job that bakes into it under the same name would
// write the same files (textures/t.p1.ao.tif: a texture of the first, a GeoTIFF of the second). Started
// together, 10 times, one bakes and the other is refused in one line naming the textures folder; one after
// the other, the second is refused naming the first's job file, unless --overwrite.
TEST_F(Untrusted, AJobBakingIntoAnotherJobsTexturesFolderNeverReplacesItsTextures) {
  json a = base_job("out"), b = base_job("out/textures");
  a["output"]["textures"] = {{{"layers", {"ao"}}, {"format", "tif"}}};
  b["output"]["geotiff"] = true;
  b["height"]["procedural"]["seed"] = 5;
  const std::string ja = write_job(dir_, a, "a.json"), jb = write_job(dir_, b, "b.json");
  const fs::path textures = dir_ / "out" / "textures";
  for (int run = 0; run < 10; ++run) {
    SCOPED_TRACE(run);
    fs::remove_all(dir_ / "out");
    const Race r = race(dir_, ja, jb);
    EXPECT_NE(r.lost_line.find(fs::weakly_canonical(textures).string()), std::string::npos) << r.lost_line;
    EXPECT_EQ(record_owner(textures / ".hfbake-t.job"), fs::weakly_canonical(r.winner).string());
    EXPECT_TRUE(fs::is_regular_file(textures / "t.p1.ao.tif"));
  }
  for (const auto& [first, second] : {std::pair(ja, jb), std::pair(jb, ja)}) {
    fs::remove_all(dir_ / "out");
    ASSERT_EQ(hfbake(dir_, {"bake", first, "--no-cache", "--quiet"}).exit_code, 0);
    const std::string tif = read_text(textures / "t.p1.ao.tif");
    const Outcome r = hfbake(dir_, {"bake", second, "--no-cache", "--quiet"});
    EXPECT_EQ(r.exit_code, 2) << r.err;
    ASSERT_EQ(r.error_lines().size(), 1u) << r.err;
    EXPECT_NE(r.error_lines()[0].find("the outputs of job t in " + textures.string() + " were baked from " +
                                      fs::weakly_canonical(first).string()),
              std::string::npos)
        << r.err;
    EXPECT_EQ(read_text(textures / "t.p1.ao.tif"), tif);
    EXPECT_EQ(hfbake(dir_, {"bake", second, "--no-cache", "--quiet", "--overwrite"}).exit_code, 0);
    EXPECT_NE(read_text(textures / "t.p1.ao.tif"), tif);
    EXPECT_EQ(record_owner(textures / ".hfbake-t.job"), fs::weakly_canonical(second).string());
  }
}

// Two suites of different jobs with one output folder, finishing together, 5 times: each one's replacement of
// history.json is held 0.4 s by the preload library, so that the second reads the history while the first
// still writes it unless the suite lock (docs/output_folders.md) orders them. Both bake (exit 0), both runs
// are in history.json, and suite.json, index.html and junit.xml are each one suite's.
TEST_F(Untrusted, TwoSuitesIntoOneFolderBothKeepTheirRunInTheHistory) {
  for (const std::string s : {"a", "b"}) {
    json j = base_job();
    j["name"] = s;
    write_job(dir_, j, s + ".json");
    std::ofstream(dir_ / ("suite_" + s + ".json"))
        << json{{"version", 1}, {"suite", "s" + s}, {"jobs", {s + ".json"}}, {"output", {{"dir", "out"}}}};
  }
  const auto slow_history = [] {
    preload_slow_rename();
    setenv("HFBAKE_TEST_SLOW_RENAME", "/out/history.json", 1);
    setenv("HFBAKE_TEST_SLOW_RENAME_MS", "400", 1);
  };
  const fs::path out = dir_ / "out";
  for (int run = 0; run < 5; ++run) {
    SCOPED_TRACE(run);
    fs::remove_all(out);
    const pid_t pa = start(dir_, {"bake", "suite_a.json", "--no-cache", "--quiet"}, "a.txt", slow_history);
    const pid_t pb = start(dir_, {"bake", "suite_b.json", "--no-cache", "--quiet"}, "b.txt", slow_history);
    const Outcome ra = finish(pa, dir_, "a.txt"), rb = finish(pb, dir_, "b.txt");
    EXPECT_EQ(ra.exit_code, 0) << ra.err;
    EXPECT_EQ(rb.exit_code, 0) << rb.err;
    const json history = json::parse(read_text(out / "history.json"));
    ASSERT_EQ(history["runs"].size(), 2u) << history.dump();
    std::set<std::string> jobs;
    for (const json& r : history["runs"])
      for (const auto& [stem, outcome] : r["jobs"].items()) jobs.insert(stem);
    EXPECT_EQ(jobs, (std::set<std::string>{"a", "b"})) << history.dump();
    // The last suite to finish wrote all four reports.
    const json suite = json::parse(read_text(out / "suite.json"));
    const std::string name = suite["suite"];
    ASSERT_EQ(suite["jobs"].size(), 1u);
    EXPECT_EQ(fs::path(suite["jobs"][0]["file"].get<std::string>()).stem(), name.substr(1));
    EXPECT_NE(read_text(out / "index.html").find("<h1>Suite " + name + "</h1>"), std::string::npos);
    EXPECT_NE(read_text(out / "junit.xml").find("<testsuite name=\"" + name + "\""), std::string::npos);
    for (const auto& e : fs::directory_iterator(out))
      EXPECT_EQ(e.path().filename().string().find(".tmp-"), std::string::npos) << e.path();
    EXPECT_FALSE(fs::exists(fs::symlink_status(out / ".hfbake+suite.lock")));
  }
}

// The suite lock held as hfbake holds it (flock(2), "<pid>@<host>" in the file) by this test, standing for
// another process writing its suite reports.
class HeldSuiteLock {
 public:
  explicit HeldSuiteLock(const fs::path& file) : file_(file) {
    fs::create_directories(file.parent_path());
    fd_ = open(file.c_str(), O_RDWR | O_CREAT | O_CLOEXEC, 0644);  // O_CLOEXEC: no hfbake child keeps it
    EXPECT_GE(fd_, 0);
    EXPECT_EQ(flock(fd_, LOCK_EX | LOCK_NB), 0);
    const std::string holder = "4242@node7";
    EXPECT_EQ(write(fd_, holder.data(), holder.size()), ssize_t(holder.size()));
  }
  ~HeldSuiteLock() { release(); }
  HeldSuiteLock(const HeldSuiteLock&) = delete;
  HeldSuiteLock& operator=(const HeldSuiteLock&) = delete;
  // Given up as hfbake gives it up: the file removed while held, then closed.
  void release() {
    if (fd_ < 0) return;
    unlink(file_.c_str());
    close(fd_);
    fd_ = -1;
  }

 private:
  fs::path file_;
  int fd_ = -1;
};

// A suite of one job into out/.
void write_one_job_suite(const fs::path& dir) {
  json j = base_job();
  j["name"] = "a";
  write_job(dir, j, "a.json");
  std::ofstream(dir / "suite.json") << json{
      {"version", 1}, {"suite", "s"}, {"jobs", {"a.json"}}, {"output", {{"dir", "out"}}}};
}

// The suite lock held for longer than the suite waits (HFBAKE_TEST_SUITE_LOCK_WAIT=1, a test switch: one
// second instead of a minute): the suite's job bakes, and the suite ends with exit 2 and one line naming the
// suite file, the folder, the holder and the wait; none of its four reports is written, and the lock is still
// the holder's.
TEST_F(Untrusted, ASuiteGivesUpOnALockHeldLongerThanItWaits) {
  write_one_job_suite(dir_);
  const fs::path out = dir_ / "out", lock = out / ".hfbake+suite.lock";
  HeldSuiteLock held(lock);
  const Outcome r = hfbake(dir_, {"bake", "suite.json", "--no-cache", "--quiet"},
                           [] { setenv("HFBAKE_TEST_SUITE_LOCK_WAIT", "1", 1); });
  EXPECT_EQ(r.exit_code, 2) << r.err;
  ASSERT_EQ(r.error_lines().size(), 1u) << r.err;
  EXPECT_EQ(r.error_lines()[0],
            "suite.json: cannot write the suite reports: another hfbake process (4242@node7) "
            "has been writing suite reports into " +
                out.string() + " for 1 s: wait for it to finish, then bake the suite again")
      << r.err;
  EXPECT_TRUE(fs::exists(out / "a" / "a.p1.exr")) << "the suite's job did not bake";
  for (const char* report : {"suite.json", "history.json", "index.html", "junit.xml"})
    EXPECT_FALSE(fs::exists(out / report)) << report;
  EXPECT_EQ(read_text(lock), "4242@node7");
}

// A suite that finds the lock held waits for it (its wait as shipped: a minute), and writes its reports once
// the holder gives the lock up. The holder gives it up when it sees the suite open the lock's file (inotify),
// which a suite does only to try the lock: the suite has found it held by then.
TEST_F(Untrusted, ASuiteWaitsForTheLocksHolderThenWritesItsReports) {
  write_one_job_suite(dir_);
  const fs::path out = dir_ / "out", lock = out / ".hfbake+suite.lock";
  HeldSuiteLock held(lock);
  const int watch = inotify_init1(IN_CLOEXEC);
  ASSERT_GE(watch, 0);
  ASSERT_GE(inotify_add_watch(watch, lock.c_str(), IN_OPEN), 0);
  const pid_t pid = start(dir_, {"bake", "suite.json", "--no-cache", "--quiet"}, "suite.txt");
  // The suite's first try of the lock, or its end (start's SIGALRM ends a hung suite).
  bool tried = false;
  for (int status = 0; !tried;) {
    pollfd p{watch, POLLIN, 0};
    if (poll(&p, 1, 100) > 0) {
      char events[4096];
      tried = read(watch, events, sizeof events) > 0;
    } else if (waitpid(pid, &status, WNOHANG) == pid) {
      close(watch);
      FAIL() << "the suite ended without trying the lock: " << read_text(dir_ / "suite.txt");
    }
  }
  close(watch);
  held.release();
  const Outcome r = finish(pid, dir_, "suite.txt");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const json history = json::parse(read_text(out / "history.json"));
  EXPECT_EQ(history["runs"].size(), 1u) << history.dump();
  for (const char* report : {"suite.json", "index.html", "junit.xml"})
    EXPECT_TRUE(fs::exists(out / report)) << report;
  EXPECT_FALSE(fs::exists(fs::symlink_status(lock)));
}

// A link planted at the suite's lock name: validate and bake refuse the suite with one line naming the suite
// file and the lock, before any of its jobs bakes, and the link's target is untouched.
TEST_F(Untrusted, ALinkAtTheSuitesLockIsRefusedBeforeAnyJobBakes) {
  json j = base_job();
  j["name"] = "a";
  write_job(dir_, j, "a.json");
  std::ofstream(dir_ / "suite.json") << json{
      {"version", 1}, {"suite", "s"}, {"jobs", {"a.json"}}, {"output", {{"dir", "out"}}}};
  const fs::path out = dir_ / "out", target = dir_ / "target.txt";
  fs::create_directories(out);
  std::ofstream(target) << "kept";
  fs::create_symlink(target, out / ".hfbake+suite.lock");
  for (const bool bake : {false, true}) {
    SCOPED_TRACE(bake ? "bake" : "validate");
    const Outcome r = bake ? hfbake(dir_, {"bake", "suite.json", "--no-cache", "--quiet"})
                           : hfbake(dir_, {"validate", "suite.json", "--quiet"});
    EXPECT_EQ(r.exit_code, 2) << r.err;
    ASSERT_EQ(r.error_lines().size(), 1u) << r.err;
    EXPECT_NE(r.error_lines()[0].find("suite.json: /output/dir: " + (out / ".hfbake+suite.lock").string() +
                                      " is no lock file of hfbake's (a link)"),
              std::string::npos)
        << r.err;
    EXPECT_FALSE(fs::exists(out / "a")) << "a job of the suite baked";
    EXPECT_EQ(read_text(target), "kept");
  }
}

// --- stopped while the outputs move into place (docs/output_folders.md#moving-the-outputs-into-place) ------

class Moves : public Untrusted {
 protected:
  void SetUp() override {
    Untrusted::SetUp();
    for (const int seed : {5, 6}) {
      json j = base_job("out");
      j["height"]["procedural"]["seed"] = seed;
      j["bake"].push_back({{"method", "hbao"}, {"directions", 4}, {"radius", 4}});
      jobs_.push_back(write_job(dir_, j, "seed" + std::to_string(seed) + ".json"));
    }
  }
  // Bakes jobs_[1] over jobs_[0]'s outputs with --overwrite, its move of t.hbao.exr (after t.p1.exr's) held
  // 3 s by the preload library; sends `sig` `times` times once that move has begun. Returns the exit code.
  // Starts that bake and returns its process once its held move has begun.
  pid_t start_the_moves() {
    EXPECT_EQ(hfbake(dir_, {"bake", jobs_[0], "--no-cache", "--quiet"}).exit_code, 0);
    old_hash_ = exr_job_hash(dir_ / "out" / "t.p1.exr");
    const fs::path flag = dir_ / "moving";
    const pid_t pid = start(dir_, {"bake", jobs_[1], "--no-cache", "--quiet", "--overwrite"}, "err.txt", [&] {
      preload_slow_rename();
      setenv("HFBAKE_TEST_SLOW_RENAME", "/t.hbao.exr", 1);
      setenv("HFBAKE_TEST_SLOW_RENAME_FLAG", flag.c_str(), 1);
    });
    for (int wait = 0; wait < 6000 && !fs::exists(flag); ++wait) usleep(10000);
    EXPECT_TRUE(fs::exists(flag)) << "the moves never began";
    return pid;
  }
  int stop_during_the_moves(int sig, int times) {
    const pid_t pid = start_the_moves();
    for (int i = 0; i < times; ++i) {
      kill(pid, sig);
      usleep(100000);
    }
    return finish(pid, dir_, "err.txt").exit_code;
  }
  std::vector<std::string> jobs_;
  std::string old_hash_;
};

// The staging folder renamed and a link to a folder outside planted at its name while the outputs move: the
// bake moves the rest from the folder it made (held, core/safe_file.hpp HeldFolder), and nothing is written
// or moved through the link.
TEST_F(Moves, ALinkPlantedAtTheStageDuringTheMovesIsNotFollowed) {
  const pid_t pid = start_the_moves();
  fs::path stage;
  for (const auto& e : fs::directory_iterator(dir_ / "out"))
    if (e.path().filename().string().rfind(".hfbake-staging-", 0) == 0) stage = e.path();
  ASSERT_FALSE(stage.empty());
  fs::rename(stage, dir_ / "out" / "moved-stage");
  fs::create_directory_symlink(dir_ / "outside", stage);
  const Outcome r = finish(pid, dir_, "err.txt");
  EXPECT_EQ(r.exit_code, 0) << r.err;
  const std::string p1 = exr_job_hash(dir_ / "out" / "t.p1.exr");
  EXPECT_NE(p1, old_hash_);
  EXPECT_EQ(exr_job_hash(dir_ / "out" / "t.hbao.exr"), p1);
  EXPECT_EQ(record_owner(dir_ / "out" / ".hfbake-t.job"), fs::weakly_canonical(jobs_[1]).string());
  expect_outside_untouched();
}

// A bake killed during its moves whose parent has not yet collected it (a zombie: `timeout -s KILL` leaves
// one) is gone: the next bake of the job name completes its moves, says so, and removes its stage.
TEST_F(Moves, AKilledBakeNotYetCollectedIsGone) {
  const pid_t pid = start_the_moves();
  kill(pid, SIGKILL);
  for (int wait = 0; wait < 500; ++wait) {  // until it is a zombie (this test does not collect it yet)
    std::ifstream in("/proc/" + std::to_string(pid) + "/stat");
    std::string stat;
    std::getline(in, stat);
    if (stat.find(") Z ") != std::string::npos) break;
    usleep(10000);
  }
  const Outcome next = hfbake(dir_, {"bake", jobs_[1], "--no-cache"});
  EXPECT_EQ(next.exit_code, 0) << next.err;
  EXPECT_NE(next.err.find("t: completed the moves of " + (dir_ / "out").string() + "/.hfbake-staging-"),
            std::string::npos)
      << next.err;
  for (const auto& e : fs::directory_iterator(dir_ / "out"))
    EXPECT_EQ(e.path().filename().string().find(".hfbake-staging-"), std::string::npos) << e.path();
  EXPECT_EQ(finish(pid, dir_, "err.txt").exit_code, -SIGKILL);
}

TEST_F(Moves, ASecondSignalDuringTheMovesLetsThemFinish) {
  // The job finished: its exit status, not the signal's (docs/contract.md).
  EXPECT_EQ(stop_during_the_moves(SIGTERM, 2), 0);
  const std::string p1 = exr_job_hash(dir_ / "out" / "t.p1.exr"),
                    hbao = exr_job_hash(dir_ / "out" / "t.hbao.exr");
  EXPECT_NE(p1, old_hash_);
  EXPECT_EQ(hbao, p1);
  EXPECT_EQ(record_owner(dir_ / "out" / ".hfbake-t.job"), fs::weakly_canonical(jobs_[1]).string());
}

TEST_F(Moves, MovesAKilledProcessBeganAreCompletedByTheNextBakeOfTheJobName) {
  EXPECT_EQ(stop_during_the_moves(SIGKILL, 1), -SIGKILL);
  const fs::path out = dir_ / "out";
  const std::string p1 = exr_job_hash(out / "t.p1.exr");
  ASSERT_NE(p1, old_hash_);
  ASSERT_EQ(exr_job_hash(out / "t.hbao.exr"), old_hash_) << "killed before the moves began";
  // Another job name's bake into the folder keeps the killed stage.
  json other = base_job("out");
  other["name"] = "u";
  ASSERT_EQ(hfbake(dir_, {"bake", write_job(dir_, other, "u.json"), "--no-cache", "--quiet"}).exit_code, 0);
  // The first job file again, without --overwrite: the killed moves are completed first, and their record
  // names the second job file, so it is refused naming that file.
  const Outcome again = hfbake(dir_, {"bake", jobs_[0], "--no-cache", "--quiet"});
  EXPECT_EQ(again.exit_code, 2) << again.err;
  ASSERT_EQ(again.error_lines().size(), 1u) << again.err;
  EXPECT_NE(again.error_lines()[0].find(fs::weakly_canonical(jobs_[1]).string()), std::string::npos)
      << again.err;
  EXPECT_EQ(exr_job_hash(out / "t.p1.exr"), p1);
  EXPECT_EQ(exr_job_hash(out / "t.hbao.exr"), p1);
  EXPECT_EQ(record_owner(out / ".hfbake-t.job"), fs::weakly_canonical(jobs_[1]).string());
  // With --overwrite it bakes, and leaves no stage.
  EXPECT_EQ(hfbake(dir_, {"bake", jobs_[0], "--no-cache", "--quiet", "--overwrite"}).exit_code, 0);
  EXPECT_EQ(exr_job_hash(out / "t.hbao.exr"), old_hash_);
  EXPECT_EQ(hfbake_test::stages_in(out), 0);
}

// --summary where a job writes: refused before anything is baked, the output and the record kept.
TEST_F(Untrusted, ASummaryWhereAJobWritesIsRefusedBeforeBaking) {
  const std::string job = write_job(dir_, base_job("out"));
  ASSERT_EQ(hfbake(dir_, {"bake", job, "--no-cache", "--quiet"}).exit_code, 0);
  const fs::path out = dir_ / "out";
  const std::string exr = read_text(out / "t.p1.exr"), record = read_text(out / ".hfbake-t.job");
  for (const std::string name : {"t.p1.exr", ".hfbake-t.job", "t.p1.ao.preview.png", "report.json"}) {
    SCOPED_TRACE(name);
    const Outcome r = hfbake(dir_, {"bake", job, "--no-cache", "--quiet", "--summary", "out/" + name});
    EXPECT_EQ(r.exit_code, 2);
    ASSERT_EQ(r.error_lines().size(), 1u) << r.err;
    EXPECT_NE(r.error_lines()[0].find("--summary"), std::string::npos) << r.err;
    EXPECT_EQ(read_text(out / "t.p1.exr"), exr);
    EXPECT_EQ(read_text(out / ".hfbake-t.job"), record);
    EXPECT_FALSE(fs::exists(out / name) && name != "t.p1.exr" && name != ".hfbake-t.job");
  }
  // A name beside them that is no output of the job is written.
  EXPECT_EQ(hfbake(dir_, {"bake", job, "--no-cache", "--quiet", "--summary", "out/summary.json"}).exit_code,
            0);
  EXPECT_TRUE(fs::is_regular_file(out / "summary.json"));
}

}  // namespace

namespace {

// A job baked again with fewer outputs leaves none of its previous bake's behind (its owner record lists
// them, docs/output_folders.md): no EXR of an entry it dropped, no preview, no texture of another format,
// no report.json of a reference it no longer traces. What it never wrote stays: a file beside the outputs,
// a link at an output's name, and names a forged record lists outside the job's own (another job's output,
// a path out of the folder).
TEST_F(Untrusted, ABakeWithFewerOutputsRemovesThePreviousBakesOthersOnly) {
  json j = base_job();
  j["bake"] = {{{"method", "p1"}, {"directions", 4}, {"layers", {"ao", "vsky"}}},
               {{"method", "hbao"}, {"directions", 4}}};
  j["reference"] = {{"samples", 4}};
  j["output"]["previews"] = true;
  j["output"]["textures"] = {{{"layers", {"ao"}}}, {{"layers", {"vsky"}}, {"format", "tga"}}};
  const std::string job = write_job(dir_, j);
  ASSERT_EQ(hfbake(dir_, {"bake", job, "--no-cache", "--quiet"}).exit_code, 0);
  const fs::path out = dir_ / "out";
  for (const char* name : {"t.hbao.exr", "t.reference.exr", "report.json", "report.html",
                           "textures/t.p1.vsky.tga", "t.p1.ao.preview.png"})
    ASSERT_TRUE(fs::is_regular_file(out / name)) << name;
  std::ofstream(out / "t.notes.txt") << "mine";
  std::ofstream(out / "u.p1.exr") << "another job's";
  fs::remove(out / "t.p1.vsky.preview.png");
  fs::create_symlink(dir_ / "outside" / "victim", out / "t.p1.vsky.preview.png");
  // The record, forged to list names beyond the job's.
  std::string record = read_text(out / ".hfbake-t.job");
  record += "\nt.notes.txt\nu.p1.exr\n../outside/victim\n" + (dir_ / "outside" / "victim").string();
  std::ofstream(out / ".hfbake-t.job", std::ios::trunc) << record;

  j["bake"] = {{{"method", "p1"}, {"directions", 4}, {"layers", {"ao"}}}};
  j.erase("reference");
  j["output"]["previews"] = false;
  j["output"]["textures"] = {{{"layers", {"ao"}}}};
  write_job(dir_, j);
  const Outcome r = hfbake(dir_, {"bake", job, "--no-cache"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  for (const char* name : {"t.hbao.exr", "t.reference.exr", "report.json", "report.html",
                           "textures/t.p1.vsky.tga", "t.p1.ao.preview.png"}) {
    EXPECT_FALSE(fs::exists(out / name)) << name;
    EXPECT_NE(r.err.find("removed " + (out / name).string()), std::string::npos) << name << "\n" << r.err;
  }
  EXPECT_TRUE(fs::is_regular_file(out / "t.p1.exr"));
  EXPECT_TRUE(fs::is_regular_file(out / "textures" / "t.p1.ao.png"));
  EXPECT_EQ(read_text(out / "t.notes.txt"), "mine");
  EXPECT_EQ(read_text(out / "u.p1.exr"), "another job's");
  EXPECT_TRUE(fs::is_symlink(out / "t.p1.vsky.preview.png"));
  expect_outside_untouched();
  // The record lists this bake's outputs now: a bake of the same outputs removes nothing.
  const Outcome again = hfbake(dir_, {"bake", job, "--no-cache"});
  ASSERT_EQ(again.err.find("removed"), std::string::npos) << again.err;
  ASSERT_EQ(again.exit_code, 0) << again.err;
  // textures/ is a folder other jobs bake into: a bake that writes no texture now removes its previous ones
  // while textures/'s record names its job file, and leaves them when another job file took the name there
  // over (its outputs, whatever their names).
  j["output"].erase("textures");
  write_job(dir_, j);
  const std::string record_there = read_text(out / "textures" / ".hfbake-t.job");
  std::ofstream(out / "textures" / ".hfbake-t.job", std::ios::trunc) << "/elsewhere/other.json";
  ASSERT_EQ(hfbake(dir_, {"bake", job, "--no-cache", "--quiet"}).exit_code, 0);
  EXPECT_TRUE(fs::is_regular_file(out / "textures" / "t.p1.ao.png"));
  // (The bake above wrote no texture, so the record it left lists none: the texture is listed again.)
  j["output"]["textures"] = {{{"layers", {"ao"}}}};
  write_job(dir_, j);
  std::ofstream(out / "textures" / ".hfbake-t.job", std::ios::trunc) << record_there;
  ASSERT_EQ(hfbake(dir_, {"bake", job, "--no-cache", "--quiet"}).exit_code, 0);
  j["output"].erase("textures");
  write_job(dir_, j);
  const Outcome dropped = hfbake(dir_, {"bake", job, "--no-cache"});
  ASSERT_EQ(dropped.exit_code, 0) << dropped.err;
  EXPECT_FALSE(fs::exists(out / "textures" / "t.p1.ao.png")) << dropped.err;
  EXPECT_NE(dropped.err.find("removed " + (out / "textures" / "t.p1.ao.png").string()), std::string::npos)
      << dropped.err;
}

}  // namespace
