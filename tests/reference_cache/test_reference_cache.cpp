// The reference cache: an entry comes back bit for bit; any damage (a flipped byte, a truncated file, a
// wrong header) is detected and the entry removed; the key follows exactly what determines a reference.
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <functional>
#include <random>

#include "cli/reference_cache.hpp"
#include "methods/method_table.hpp"

namespace hfbake {
namespace {
namespace fs = std::filesystem;

class Cache : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("hfbake_test_refcache_" + std::to_string(std::random_device{}()));
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }

  static LayerSet sample(int w, int h) {
    LayerSet s;
    s.width = w;
    s.height = h;
    Layer& ao = s.add("ao", mono_channels());
    std::mt19937 rng(3);
    std::uniform_real_distribution<float> u(0.0f, 1.0f);
    for (float& v : ao.data) v = u(rng);
    Layer& direct = s.add("direct", rgb_channels());
    for (float& v : direct.data) v = u(rng) * 3.0f;
    direct.data[5] = -0.0f;
    direct.data[7] = 1e-40f;  // a denormal survives too
    s.attributes.emplace_back("hfbake:reference_samples", "64");
    return s;
  }

  Job job(const nlohmann::json& doc) {
    Job j;
    j.file = dir_ / "j.json";
    j.base_dir = dir_;
    j.doc = doc;
    j.name = doc.value("name", "t");
    // Its entries resolved by their methods' readers, as resolve_job does (a 64² field).
    MethodContext context;
    context.field.width = context.field.height = 64;
    context.field.texel_size = 1;
    for (std::size_t b = 0; b < doc["bake"].size(); ++b) {
      BakeEntry e;
      e.method = doc["bake"][b]["method"];
      e.pointer = "/bake/" + std::to_string(b);
      e.params = doc["bake"][b];
      e.config = std::make_shared<const MethodConfig>(resolve_method(e.params, context, "j.json", e.pointer));
      j.bakes.push_back(std::move(e));
    }
    return j;
  }

  static nlohmann::json base_doc() {
    return {{"version", 1},
            {"name", "t"},
            {"height", {{"procedural", {{"kind", "fractal"}, {"size", {64, 64}}, {"seed", 3}}}}},
            {"environment", {{"sky", nlohmann::json::object()}}},
            {"bake", {{{"method", "p1"}, {"directions", 16}}}},
            {"reference", {{"samples", 64}, {"seed", 1}}}};
  }

  fs::path dir_;
};

TEST_F(Cache, RoundTripIsBitExact) {
  const ReferenceCache cache(dir_ / "c");
  const LayerSet s = sample(7, 5);
  EXPECT_EQ(cache.store("0123456789abcdef", s, 12.5), "");
  ReferenceCache::Entry e;
  ASSERT_EQ(cache.load("0123456789abcdef", e), CacheLookup::hit);
  EXPECT_EQ(e.seconds, 12.5);
  ASSERT_EQ(e.layers.width, 7);
  ASSERT_EQ(e.layers.height, 5);
  ASSERT_EQ(e.layers.layers.size(), 2u);
  for (std::size_t i = 0; i < 2; ++i) {
    EXPECT_EQ(e.layers.layers[i].name, s.layers[i].name);
    EXPECT_EQ(e.layers.layers[i].channels, s.layers[i].channels);
    ASSERT_EQ(e.layers.layers[i].data.size(), s.layers[i].data.size());
    EXPECT_EQ(std::memcmp(e.layers.layers[i].data.data(), s.layers[i].data.data(),
                          s.layers[i].data.size() * sizeof(float)),
              0);
  }
  EXPECT_EQ(e.layers.attributes, s.attributes);
  // Nothing but the entry is left in the folder (the temporary was renamed).
  int files = 0;
  for (const auto& f : fs::directory_iterator(dir_ / "c")) {
    ++files;
    EXPECT_EQ(f.path().extension(), ".hfref");
  }
  EXPECT_EQ(files, 1);
}

TEST_F(Cache, UnknownKeyMisses) {
  const ReferenceCache cache(dir_ / "nowhere");
  ReferenceCache::Entry e;
  EXPECT_EQ(cache.load("0000000000000000", e), CacheLookup::miss);
}

TEST_F(Cache, FlippedPayloadByteIsDetectedAndRemoved) {
  const ReferenceCache cache(dir_);
  ASSERT_EQ(cache.store("k", sample(16, 16), 1.0), "");
  const fs::path f = cache.entry_path("k");
  {
    std::fstream io(f, std::ios::in | std::ios::out | std::ios::binary);
    io.seekp(-100, std::ios::end);
    char c = 0;
    io.read(&c, 1);
    io.seekp(-100, std::ios::end);
    c ^= 0x10;
    io.write(&c, 1);
  }
  ReferenceCache::Entry e;
  EXPECT_EQ(cache.load("k", e), CacheLookup::corrupt);
  EXPECT_FALSE(fs::exists(f));
  EXPECT_EQ(cache.load("k", e), CacheLookup::miss);
  // Rebuilt: a new store is read back.
  ASSERT_EQ(cache.store("k", sample(16, 16), 1.0), "");
  EXPECT_EQ(cache.load("k", e), CacheLookup::hit);
}

TEST_F(Cache, TruncatedExtendedOrForeignEntriesAreCorrupt) {
  const ReferenceCache cache(dir_);
  ReferenceCache::Entry e;
  ASSERT_EQ(cache.store("a", sample(16, 16), 1.0), "");
  fs::resize_file(cache.entry_path("a"), fs::file_size(cache.entry_path("a")) - 4);
  EXPECT_EQ(cache.load("a", e), CacheLookup::corrupt);

  ASSERT_EQ(cache.store("b", sample(16, 16), 1.0), "");
  std::ofstream(cache.entry_path("b"), std::ios::app | std::ios::binary) << "xx";
  EXPECT_EQ(cache.load("b", e), CacheLookup::corrupt);

  // An entry stored under another key (a renamed file) is not trusted.
  ASSERT_EQ(cache.store("c", sample(16, 16), 1.0), "");
  fs::rename(cache.entry_path("c"), cache.entry_path("d"));
  EXPECT_EQ(cache.load("d", e), CacheLookup::corrupt);

  std::ofstream(cache.entry_path("g")) << "hfbake reference cache 1\n{not json\n";
  EXPECT_EQ(cache.load("g", e), CacheLookup::corrupt);
  std::ofstream(cache.entry_path("h")) << "";
  EXPECT_EQ(cache.load("h", e), CacheLookup::corrupt);
}

// The peak resident memory of this process so far (VmHWM), in bytes.
std::size_t peak_resident_bytes() {
  std::ifstream status("/proc/self/status");
  for (std::string line; std::getline(status, line);)
    if (line.rfind("VmHWM:", 0) == 0) return std::stoull(line.substr(6)) * 1024;
  return 0;
}

// Runs `load` in a child process (a hang is killed after 60 s by SIGALRM, so a blocking open fails the test
// instead of hanging it): its CacheLookup and how far it raised the child's peak resident memory.
struct ChildLoad {
  bool finished = false;
  int lookup = -1;
  std::size_t grew_bytes = 0;
};
ChildLoad load_in_child(const std::function<CacheLookup()>& load) {
  int fds[2];
  if (pipe(fds) != 0) return {};
  const pid_t pid = fork();
  if (pid == 0) {
    close(fds[0]);
    alarm(60);
    const std::size_t before = peak_resident_bytes();
    const long long result[2] = {int(load()), (long long)(peak_resident_bytes() - before)};
    const bool ok = write(fds[1], result, sizeof result) == ssize_t(sizeof result);
    _exit(ok ? 0 : 1);
  }
  close(fds[1]);
  long long result[2] = {-1, 0};
  const bool got = read(fds[0], result, sizeof result) == ssize_t(sizeof result);
  close(fds[0]);
  int status = 0;
  waitpid(pid, &status, 0);
  ChildLoad r;
  r.finished = got && WIFEXITED(status) && WEXITSTATUS(status) == 0;
  r.lookup = int(result[0]);
  r.grew_bytes = std::size_t(std::max(0ll, result[1]));
  return r;
}

// Rewrites the header's width and height (the checksum and payload stay): what a damaged or hostile entry
// claims.
void claim_size(const fs::path& file, int width, int height) {
  std::ifstream in(file, std::ios::binary);
  std::string magic, header, payload;
  std::getline(in, magic);
  std::getline(in, header);
  payload.assign(std::istreambuf_iterator<char>(in), {});
  in.close();
  nlohmann::json h = nlohmann::json::parse(header);
  h["width"] = width;
  h["height"] = height;
  std::ofstream(file, std::ios::binary | std::ios::trunc) << magic << "\n" << h.dump() << "\n" << payload;
}

TEST_F(Cache, AHeaderClaimingMoreThanTheFileHoldsIsRefusedBeforeAllocating) {
  const ReferenceCache cache(dir_);
  ASSERT_EQ(cache.store("big", sample(16, 16), 1.0), "");
  // 20000 x 20000 x 4 channels would be 6.4 GB of floats; the file holds 4 KiB of them.
  claim_size(cache.entry_path("big"), 20000, 20000);
  const ChildLoad r = load_in_child([&] {
    ReferenceCache::Entry e;
    return cache.load("big", e);
  });
  ASSERT_TRUE(r.finished);
  EXPECT_EQ(r.lookup, int(CacheLookup::corrupt));
  EXPECT_LT(r.grew_bytes, std::size_t(64) << 20) << "the header's size was allocated before it was checked";
  EXPECT_FALSE(fs::exists(cache.entry_path("big")));  // removed: the next bake rebuilds it

  // Absurd and negative sides, and an entry of another field size than the job's.
  for (const auto& [w, h] : std::vector<std::pair<long long, long long>>{
           {60000, 60000}, {-16, -16}, {1ll << 40, 1}, {16, 1ll << 62}}) {
    ASSERT_EQ(cache.store("odd", sample(16, 16), 1.0), "");
    claim_size(cache.entry_path("odd"), int(std::clamp<long long>(w, -(1ll << 31), (1ll << 31) - 1)),
               int(std::clamp<long long>(h, -(1ll << 31), (1ll << 31) - 1)));
    ReferenceCache::Entry e;
    EXPECT_EQ(cache.load("odd", e), CacheLookup::corrupt) << w << "x" << h;
  }
  ASSERT_EQ(cache.store("other", sample(16, 16), 1.0), "");
  ReferenceCache::Entry e;
  EXPECT_EQ(cache.load("other", e, 16, 17), CacheLookup::corrupt);
  // A header that gives a key twice is damage, whichever value a lenient parser would keep.
  ASSERT_EQ(cache.store("twice", sample(16, 16), 1.0), "");
  {
    std::ifstream in(cache.entry_path("twice"), std::ios::binary);
    std::string text((std::istreambuf_iterator<char>(in)), {});
    in.close();
    const std::size_t brace = text.find('{');
    ASSERT_NE(brace, std::string::npos);
    text.insert(brace + 1, "\"seconds\":5,");
    std::ofstream(cache.entry_path("twice"), std::ios::binary | std::ios::trunc) << text;
  }
  EXPECT_EQ(cache.load("twice", e), CacheLookup::corrupt);
  ASSERT_EQ(cache.store("same", sample(16, 16), 1.0), "");
  EXPECT_EQ(cache.load("same", e, 16, 16), CacheLookup::hit);
}

TEST_F(Cache, AFifoOrAFolderInAnEntrysPlaceDoesNotHang) {
  const ReferenceCache cache(dir_);
  ASSERT_EQ(mkfifo(cache.entry_path("fifo").c_str(), 0600), 0);
  const ChildLoad r = load_in_child([&] {
    ReferenceCache::Entry e;
    return cache.load("fifo", e);
  });
  ASSERT_TRUE(r.finished) << "opening a FIFO entry hung";
  EXPECT_EQ(r.lookup, int(CacheLookup::corrupt));
  EXPECT_FALSE(fs::exists(cache.entry_path("fifo")));
  // Rebuilt in its place.
  ASSERT_EQ(cache.store("fifo", sample(4, 4), 1.0), "");
  ReferenceCache::Entry e;
  EXPECT_EQ(cache.load("fifo", e), CacheLookup::hit);

  fs::create_directories(cache.entry_path("dir"));
  EXPECT_EQ(cache.load("dir", e), CacheLookup::corrupt);
  // A header line without an end (1 MiB and more) is damage too.
  std::ofstream(cache.entry_path("long"), std::ios::binary) << "hfbake reference cache 1\n"
                                                            << std::string(std::size_t(2) << 20, '{');
  EXPECT_EQ(cache.load("long", e), CacheLookup::corrupt);
}

TEST_F(Cache, KeyFollowsWhatDeterminesTheReference) {
  const std::string k0 = reference_cache_key(job(base_doc()));
  EXPECT_EQ(k0.size(), 16u);
  EXPECT_EQ(reference_cache_key(job(base_doc())), k0);

  auto changed = [&](const std::string& pointer, const nlohmann::json& value) {
    nlohmann::json d = base_doc();
    d[nlohmann::json::json_pointer(pointer)] = value;
    return reference_cache_key(job(d));
  };
  // Not part of the reference: name, output, report, description.
  EXPECT_EQ(changed("/name", "other"), k0);
  EXPECT_EQ(changed("/output", {{"dir", "elsewhere"}}), k0);
  EXPECT_EQ(changed("/report", {{"thresholds", {{"p1.ao.rmse", 0.1}}}}), k0);
  EXPECT_EQ(changed("/description", "x"), k0);
  EXPECT_EQ(changed("/bake/0/directions", 64), k0);  // the reference does not read method parameters
  EXPECT_EQ(changed("/bake/1", {{"method", "p2"}}), k0);
  // ... except an obscurance falloff and radius.
  EXPECT_NE(changed("/bake/1", {{"method", "hbao"}, {"radius", 8}, {"falloff", "step"}}), k0);
  {
    nlohmann::json d = base_doc();
    d["bake"][1] = {{"method", "hbao"}, {"radius", 8}, {"falloff", "step"}};
    const std::string k8 = reference_cache_key(job(d));
    d["bake"][1]["radius"] = 9;
    EXPECT_NE(reference_cache_key(job(d)), k8);
    d["bake"][1]["radius"] = 8;
    d["bake"][1]["directions"] = 32;
    EXPECT_EQ(reference_cache_key(job(d)), k8);
    // Only the first obscurance entry's falloff reaches the reference: more obscurance entries (other
    // methods, other radii, as a frontier or budget job adds them) do not re-trace it.
    d["bake"].push_back({{"method", "farfield"}, {"radius", 32}, {"falloff", "linear"}});
    d["bake"].push_back({{"method", "lsao"}, {"radius", 4}});
    EXPECT_EQ(reference_cache_key(job(d)), k8);
    // The reference's own falloff wins over every entry's.
    d["reference"]["radius"] = 8;
    d["reference"]["falloff"] = "step";
    const std::string kr = reference_cache_key(job(d));
    d["bake"][1]["radius"] = 12;
    EXPECT_EQ(reference_cache_key(job(d)), kr);
  }
  // Part of it.
  EXPECT_NE(changed("/reference/samples", 65), k0);
  EXPECT_NE(changed("/reference/seed", 2), k0);
  EXPECT_NE(changed("/height/procedural/seed", 4), k0);
  EXPECT_NE(changed("/height/texel_size", 2.0), k0);
  EXPECT_NE(changed("/surface", {{"albedo", 0.3}}), k0);
  EXPECT_NE(changed("/environment", {{"uniform", 1.0}}), k0);
  EXPECT_NE(changed("/bounces", 2), k0);
  EXPECT_NE(changed("/lights", nlohmann::json::array()), k0);
}

TEST_F(Cache, KeyFollowsInputFileBytes) {
  std::ofstream(dir_ / "h.pgm") << "P2 2 2 255 0 1 2 3\n";
  std::ofstream(dir_ / "glow.pgm") << "P2 2 2 255 0 0 0 0\n";
  nlohmann::json d = base_doc();
  d["height"] = {{"image", "h.pgm"}};
  d["surface"] = {{"emission", {{"image", "glow.pgm"}}}};
  const std::string k0 = reference_cache_key(job(d));
  std::ofstream(dir_ / "glow.pgm") << "P2 2 2 255 0 0 0 1\n";
  const std::string k1 = reference_cache_key(job(d));
  EXPECT_NE(k1, k0);
  std::ofstream(dir_ / "h.pgm") << "P2 2 2 255 0 1 2 4\n";
  EXPECT_NE(reference_cache_key(job(d)), k1);
}

TEST(CacheDir, FollowsXdgCacheHomeThenHome) {
  const char* old_xdg = std::getenv("XDG_CACHE_HOME");
  const char* old_home = std::getenv("HOME");
  const std::string saved = old_xdg ? old_xdg : "", saved_home = old_home ? old_home : "";
  setenv("XDG_CACHE_HOME", "/tmp/xdg", 1);
  EXPECT_EQ(default_reference_cache_dir(), fs::path("/tmp/xdg/hfbake/references"));
  setenv("XDG_CACHE_HOME", "relative/ignored", 1);  // the XDG spec: relative paths are invalid
  setenv("HOME", "/home/someone", 1);
  EXPECT_EQ(default_reference_cache_dir(), fs::path("/home/someone/.cache/hfbake/references"));
  if (old_xdg)
    setenv("XDG_CACHE_HOME", saved.c_str(), 1);
  else
    unsetenv("XDG_CACHE_HOME");
  if (old_home) setenv("HOME", saved_home.c_str(), 1);
}

}  // namespace
}  // namespace hfbake
