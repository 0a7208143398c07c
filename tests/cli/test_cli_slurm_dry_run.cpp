// hfbake slurm --dry-run: the two scripts and the sbatch commands on stdout, nothing written or submitted
// (the truth: the output folder does not exist afterwards, and no sbatch is needed to run it).
#include <gtest/gtest.h>
#include <sys/wait.h>

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <nlohmann/json.hpp>
#include <random>
#include <string>

namespace {
namespace fs = std::filesystem;

TEST(CliSlurm, DryRunPrintsTheScriptsAndWritesNothing) {
  const fs::path dir =
      fs::temp_directory_path() / ("hfbake_test_dry_run_" + std::to_string(std::random_device{}()));
  fs::create_directories(dir);
  const nlohmann::json job = {{"version", 1},
                              {"name", "dry"},
                              {"height", {{"procedural", {{"kind", "fractal"}, {"size", {32, 32}}}}}},
                              {"bake", {{{"method", "p1"}, {"directions", 8}}}}};
  std::ofstream(dir / "dry.json") << job.dump();
  const fs::path out = dir / "out";
  // PATH without sbatch: a dry run must not call it.
  const std::string cmd = "cd '" + dir.string() + "' && PATH=/nonexistent " + std::string(HFBAKE_BINARY) +
                          " slurm dry.json --shards 3 --dry-run --out '" + out.string() +
                          "' > stdout.txt 2> stderr.txt";
  const int status = std::system(cmd.c_str());
  std::ifstream in(dir / "stdout.txt"), err_in(dir / "stderr.txt");
  const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  const std::string err((std::istreambuf_iterator<char>(err_in)), std::istreambuf_iterator<char>());
  EXPECT_EQ(WEXITSTATUS(status), 0) << err;
  for (const std::string& s :
       {"# ---- " + (out / "slurm" / "bake.sbatch").string(), std::string("#SBATCH --array=0-2"),
        std::string(" bake \"${JOBS[$i]}\" --shard \"${SHARDS[$i]}/$N\""), std::string(" merge "),
        "sbatch --parsable --array=0-2 '" + (out / "slurm" / "bake.sbatch").string() + "'",
        std::string("sbatch --parsable --dependency=afterok:<stage 0 array> --kill-on-invalid-dep=yes '")})
    EXPECT_NE(text.find(s), std::string::npos) << s << "\n" << text;
  EXPECT_FALSE(fs::exists(out)) << "a dry run writes nothing";
  fs::remove_all(dir);
}

// A line break in the output folder (the job's output.dir) would end a script's comment or #SBATCH line and
// start a command of its own: refused in one line naming the job file, nothing written, the command never
// printed.
TEST(CliSlurm, ALineBreakInAPathIsRefused) {
  const fs::path dir =
      fs::temp_directory_path() / ("hfbake_test_slurm_newline_" + std::to_string(std::random_device{}()));
  fs::create_directories(dir);
  const nlohmann::json job = {{"version", 1},
                              {"name", "inj"},
                              {"height", {{"procedural", {{"kind", "fractal"}, {"size", {32, 32}}}}}},
                              {"bake", {{{"method", "p1"}, {"directions", 8}}}},
                              {"output", {{"dir", "out\ntouch " + (dir / "ran").string() + "\n#"}}}};
  std::ofstream(dir / "inj.json") << job.dump();
  const std::string cmd = "cd '" + dir.string() + "' && PATH=/nonexistent " + std::string(HFBAKE_BINARY) +
                          " slurm inj.json --shards 2 --dry-run > stdout.txt 2> stderr.txt";
  const int status = std::system(cmd.c_str());
  std::ifstream in(dir / "stdout.txt"), err_in(dir / "stderr.txt");
  const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  const std::string err((std::istreambuf_iterator<char>(err_in)), std::istreambuf_iterator<char>());
  EXPECT_EQ(WEXITSTATUS(status), 2);
  EXPECT_NE(err.find("line break"), std::string::npos) << err;
  EXPECT_EQ(std::count(err.begin(), err.end(), '\n'), 1) << err;
  EXPECT_EQ(text.find("touch"), std::string::npos) << text;
  EXPECT_FALSE(fs::exists(dir / "ran"));
  fs::remove_all(dir);
}

}  // namespace
