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

struct SlurmRun {
  int exit_code = -1;
  std::string out, err;
};

// `hfbake ARGS` in `dir` with no sbatch on PATH (a dry run must not call it); its exit code and output.
SlurmRun run_in(const fs::path& dir, const std::string& args) {
  const std::string cmd = "cd '" + dir.string() + "' && PATH=/nonexistent " + std::string(HFBAKE_BINARY) +
                          " " + args + " > stdout.txt 2> stderr.txt";
  const int status = std::system(cmd.c_str());
  std::ifstream in(dir / "stdout.txt"), err_in(dir / "stderr.txt");
  SlurmRun r;
  r.exit_code = WEXITSTATUS(status);
  r.out.assign(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
  r.err.assign(std::istreambuf_iterator<char>(err_in), std::istreambuf_iterator<char>());
  return r;
}

// A fresh folder for one test (under the system's temporary folder), and a small p1 job "v" baking into
// `out` there.
fs::path fresh_folder(const std::string& what) {
  const fs::path dir = fs::temp_directory_path() /
                       ("hfbake_test_slurm_" + what + "_" + std::to_string(std::random_device{}()));
  fs::create_directories(dir);
  return dir;
}
nlohmann::json small_job(const std::string& out) {
  return {{"version", 1},
          {"name", "v"},
          {"height", {{"procedural", {{"kind", "fractal"}, {"size", {32, 32}}}}}},
          {"bake", {{{"method", "p1"}, {"directions", 8}}}},
          {"output", {{"dir", out}}}};
}

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
  const SlurmRun r = run_in(dir, "slurm dry.json --shards 3 --dry-run --out '" + out.string() + "'");
  const std::string& text = r.out;
  EXPECT_EQ(r.exit_code, 0) << r.err;
  for (const std::string& s :
       {"# ---- " + (out / "slurm" / "bake.sbatch").string(), std::string("#SBATCH --array=0-2"),
        std::string(" bake \"${JOBS[$i]}\" --shard \"${SHARDS[$i]}/$N\""), std::string(" merge "),
        "sbatch --parsable --array=0-2 '" + (out / "slurm" / "bake.sbatch").string() + "'",
        std::string("sbatch --parsable --dependency=afterok:<stage 0 array> --kill-on-invalid-dep=yes '")})
    EXPECT_NE(text.find(s), std::string::npos) << s << "\n" << text;
  // The tasks and the merge take glibc's SSE2 math on every machine (docs/cluster.md): the tunable's line
  // comes before each script's command.
  const std::string tunable =
      "export GLIBC_TUNABLES=\"${GLIBC_TUNABLES:+$GLIBC_TUNABLES:}glibc.cpu.hwcaps=-FMA,-FMA4\"\n";
  const std::size_t first = text.find(tunable), second = text.find(tunable, first + 1);
  ASSERT_NE(second, std::string::npos) << text;
  EXPECT_LT(first, text.find(" bake \"${JOBS[$i]}\"")) << text;
  EXPECT_LT(second, text.find("exec ", text.find(" merge") - 60)) << text;
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
  const SlurmRun r = run_in(dir, "slurm inj.json --shards 2 --dry-run");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("line break"), std::string::npos) << r.err;
  EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
  EXPECT_EQ(r.out.find("touch"), std::string::npos) << r.out;
  EXPECT_FALSE(fs::exists(dir / "ran"));
  fs::remove_all(dir);
}

// Slurm splits an #SBATCH value at a blank, expands a % in a file name, takes quotes and backslashes out and
// ends the line at a # (the tasks would run in another folder, baking its job file): a folder with any of
// them is refused in one line, the working folder too. A job file whose
// name starts with '-' is passed as ./-name, never as an option.
TEST(CliSlurm, SbatchValuesAndJobPathsStayWhole) {
  const fs::path dir = fresh_folder("values");
  nlohmann::json job = small_job("out");
  SlurmRun r;
  for (const char* folder : {"out 50%", "out\"x\"", "out'x", "out\\x", "out#2"}) {
    job["output"]["dir"] = folder;
    std::ofstream(dir / "v.json") << job.dump();
    r = run_in(dir, "slurm v.json --shards 2 --dry-run");
    EXPECT_EQ(r.exit_code, 2) << folder;
    EXPECT_NE(r.err.find("holds a blank, a %, a #, a quote or a backslash"), std::string::npos) << r.err;
    EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
    EXPECT_TRUE(r.out.empty()) << r.out;
  }
  {
    const fs::path hash = dir / "wd#2";
    fs::create_directories(hash);
    job["output"]["dir"] = (dir / "out").string();  // the working folder alone holds the #
    std::ofstream(hash / "v.json") << job.dump();
    std::ofstream(dir / "v.json") << job.dump();
    r = run_in(hash, "slurm v.json --shards 2 --dry-run");
    EXPECT_EQ(r.exit_code, 2);
    EXPECT_NE(r.err.find("the working folder"), std::string::npos) << r.err;
    EXPECT_NE(r.err.find("a #"), std::string::npos) << r.err;
    EXPECT_TRUE(r.out.empty()) << r.out;
    r = run_in(dir, "slurm v.json --shards 2 --dry-run --partition 'main#x'");
    EXPECT_EQ(r.exit_code, 2);
    EXPECT_NE(r.err.find("--partition \"main#x\" holds a #"), std::string::npos) << r.err;
  }
  job["output"]["dir"] = "out";
  std::ofstream(dir / "-v.json") << job.dump();
  r = run_in(dir, "slurm --shards 2 --dry-run -- -v.json");
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("  './-v.json'\n"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find(" merge './-v.json'"), std::string::npos) << r.out;
  fs::remove_all(dir);
}

// An --sbatch-arg setting what the scripts set themselves (the logs, the working folder, the array, the
// chain, the threads, the memory) is refused in one line naming it; any other goes into both scripts.
TEST(CliSlurm, SbatchArgsTheScriptsOwnAreRefused) {
  const fs::path dir = fresh_folder("args");
  std::ofstream(dir / "v.json") << small_job("out").dump();
  for (const char* arg : {"--output=x.log", "-ox.log", "--job-name=x", "-J", "--chdir=/tmp", "--array=0-9",
                          "--dependency=afterok:1", "--wait", "-c4", "--cpus-per-task=4", "--mem=1G"}) {
    const SlurmRun r =
        run_in(dir, std::string("slurm v.json --shards 2 --dry-run --sbatch-arg='") + arg + "'");
    EXPECT_EQ(r.exit_code, 2) << arg;
    EXPECT_NE(r.err.find("--sbatch-arg \"" + std::string(arg) + "\": the scripts set"), std::string::npos)
        << r.err;
    EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
  }
  const SlurmRun r =
      run_in(dir, "slurm v.json --shards 2 --dry-run --sbatch-arg=--exclusive --sbatch-arg=-pdebug");
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("#SBATCH --exclusive\n"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("#SBATCH -pdebug\n"), std::string::npos) << r.out;
  fs::remove_all(dir);
}

// Before anything is submitted: shards of the job's name for another count in its shards folder (the merge
// would refuse the mix), and outputs of the job's name that another job file baked there (its tasks and
// merge run without --overwrite), are refused in one line naming them.
TEST(CliSlurm, AFolderTheMergeWouldRefuseIsRefusedBeforeSubmitting) {
  const fs::path dir = fresh_folder("folder");
  fs::create_directories(dir / "out" / "shards");
  std::ofstream(dir / "v.json") << small_job("out").dump();
  std::ofstream(dir / "out" / "shards" / "v.shard-0-of-3.hfshard") << "a shard of three";
  SlurmRun r = run_in(dir, "slurm v.json --shards 2 --dry-run");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find((dir / "out" / "shards").string() + ": holds shards of job v for 3 shards"),
            std::string::npos)
      << r.err;
  EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
  EXPECT_TRUE(r.out.empty()) << r.out;
  r = run_in(dir, "slurm v.json --shards 3 --dry-run");
  EXPECT_EQ(r.exit_code, 0) << r.err;

  std::ofstream(dir / "out" / ".hfbake-v.job") << "/elsewhere/v.json";
  r = run_in(dir, "slurm v.json --shards 3 --dry-run");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("were baked from /elsewhere/v.json"), std::string::npos) << r.err;
  EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
  fs::remove_all(dir);
}

}  // namespace
