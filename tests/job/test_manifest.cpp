// Job loading: every kind of bad job gives one line naming the file, the JSON pointer and the rule.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <random>

#include <sys/stat.h>

#include "job/manifest.hpp"

namespace hfbake {
namespace {
namespace fs = std::filesystem;

class Manifest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("hfbake_test_job_" + std::to_string(std::random_device{}()));
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }

  fs::path write(const std::string& name, const std::string& text) {
    const fs::path p = dir_ / name;
    std::ofstream(p) << text;
    return p;
  }
  // Loads a job whose text is `text` and returns its error lines.
  std::vector<std::string> errors(const std::string& text) {
    return load_job(write("x.json", text), std::nullopt).errors;
  }
  static std::string minimal(const std::string& extra = "",
                             const std::string& bake = R"([{"method": "p1"}])") {
    return R"({"version": 1, "name": "t", "height": {"procedural": {"kind": "flat", "size": [8, 8]}}, "bake": )" +
           bake + extra + "}";
  }

  fs::path dir_;
};

TEST_F(Manifest, MinimalJobLoadsWithDefaults) {
  const JobLoad r = load_job(write("ok.json", minimal()), std::nullopt);
  ASSERT_TRUE(r.errors.empty()) << r.errors.front();
  ASSERT_TRUE(r.job);
  EXPECT_EQ(r.job->name, "t");
  ASSERT_EQ(r.job->bakes.size(), 1u);
  EXPECT_EQ(r.job->bakes[0].stem, "p1");
  EXPECT_EQ(r.job->output.dir, (dir_ / "out" / "t").lexically_normal());
  EXPECT_FALSE(r.job->output.float_pixels);
}

TEST_F(Manifest, RepeatedMethodGetsIndexedStems) {
  const JobLoad r =
      load_job(write("ok.json", minimal("", R"([{"method": "p1"}, {"method": "hbao"}, {"method": "p1"}])")),
               std::nullopt);
  ASSERT_TRUE(r.job);
  EXPECT_EQ(r.job->bakes[0].stem, "p1-0");
  EXPECT_EQ(r.job->bakes[1].stem, "hbao");
  EXPECT_EQ(r.job->bakes[2].stem, "p1-2");
}

TEST_F(Manifest, MalformedJsonNamesLineAndColumn) {
  const auto e = errors("{\n  \"version\": 1,\n  \"name\": \n}");
  ASSERT_EQ(e.size(), 1u);
  EXPECT_NE(e[0].find("x.json: line 4, column 1: malformed JSON"), std::string::npos) << e[0];
}

// The hand-written mistakes a newcomer makes get a hint after the parser's words: a comment, a comma after
// the last item, a Windows path's backslash. An error of another kind gets none.
TEST_F(Manifest, MalformedJsonNamesTheUsualMistake) {
  const std::vector<std::pair<std::string, std::string>> cases = {
      {"{\"version\": 1, // my job\n \"name\": \"a\"}", "(a comment: job files are JSON, which has none)"},
      {"{\"version\": 1, /* x */ \"name\": \"a\"}", "(a comment: job files are JSON, which has none)"},
      {"{\"version\": 1,\n \"name\": \"a\",\n}", "(a comma after the last item: JSON takes none before })"},
      {"{\"bake\": [1, 2, ]}", "(a comma after the last item: JSON takes none before ])"},
      {"{\"height\": {\"image\": \"..\\img\\x.png\"}}",
       "(a backslash: in JSON it starts an escape; write paths with /)"}};
  for (const auto& [text, hint] : cases) {
    const auto e = errors(text);
    ASSERT_EQ(e.size(), 1u) << text;
    EXPECT_NE(e[0].find("malformed JSON"), std::string::npos) << e[0];
    EXPECT_EQ(e[0].substr(e[0].size() - std::min(e[0].size(), hint.size())), hint) << e[0];
  }
  const auto e = errors("{\n  \"version\": 1,\n  \"name\": \n}");
  ASSERT_EQ(e.size(), 1u);
  EXPECT_EQ(e[0].find(" (a "), std::string::npos) << e[0];
  // A Windows path written with escaped backslashes parses, and names no file.
  const auto w = errors(R"({"version": 1, "name": "a", "height": {"image": "..\\img\\x.png"},
                            "bake": [{"method": "p1"}]})");
  ASSERT_EQ(w.size(), 1u);
  EXPECT_NE(w[0].find("no such file: "), std::string::npos) << w[0];
  EXPECT_NE(w[0].find("(a backslash: hfbake's paths take / between folders)"), std::string::npos) << w[0];
}

TEST_F(Manifest, OutOfRangeDirections) {
  const auto e = errors(minimal("", R"([{"method": "p1", "directions": 0}])"));
  ASSERT_EQ(e.size(), 1u);
  EXPECT_EQ(e[0], (dir_ / "x.json").string() + ": /bake/0/directions: must be >= 1");
}

TEST_F(Manifest, WrongType) {
  const auto e = errors(minimal(R"(, "bounces": "two")"));
  ASSERT_EQ(e.size(), 1u);
  EXPECT_EQ(e[0], (dir_ / "x.json").string() + ": /bounces: must be an integer (it is a string)");
}

// The line names what the schema expects: the types of every alternative, a constant's value; a value
// that matched one alternative's type is judged by that alternative alone.
TEST_F(Manifest, WrongTypesAndConstantsSayWhatIsExpected) {
  auto one = [&](const std::string& json) {
    const auto e = errors(json);
    return e.size() == 1 ? e[0].substr((dir_ / "x.json").string().size() + 2) : std::to_string(e.size());
  };
  EXPECT_EQ(one(minimal(R"(, "bounces": 1.5)")), "/bounces: must be an integer (it is 1.5)");
  EXPECT_EQ(one(minimal(R"(, "bounces": 2.0)")),
            "/bounces: must be an integer (it is 2.0, written with a fraction or an exponent: write 2)");
  EXPECT_EQ(one(minimal(R"(, "bounces": 2e0)")),
            "/bounces: must be an integer (it is 2.0, written with a fraction or an exponent: write 2)");
  // A scale past float's range (0 x inf made the image NaN, reported at its pixels): refused at the scale,
  // the bound said as a number is written.
  EXPECT_EQ(one(minimal(R"(, "surface": {"emission": {"image": "e.png", "scale": 1e300}})")),
            "/surface/emission/scale: must be <= 1e+30");
  // A bound valijson's six decimals would print as 0 is said as the schema writes it.
  EXPECT_EQ(one(minimal(R"(, "output": {"dir": "o", "textures": [{"layers": ["ao"], "exposure": 1e-300}]})")),
            "/output/textures/0/exposure: must be >= 1e-30");
  // A colour space that says nothing: empty, or given to a uniform environment (no image to read in it).
  EXPECT_EQ(one(minimal(R"(, "environment": {"latlong": "sky.exr", "colorspace": ""})")),
            "/environment/colorspace: must not be empty");
  EXPECT_EQ(
      one(minimal(R"(, "environment": {"uniform": 1, "colorspace": "sRGB"})")),
      "/environment/colorspace: applies to an environment image (latlong, cubemap, cross), not to uniform");
  EXPECT_EQ(one(minimal(R"(, "surface": {"albedo": "grey"})")),
            "/surface/albedo: must be a number, an array or an object (it is a string)");
  EXPECT_EQ(one(minimal(R"(, "surface": {"albedo": [0.5, "a", 0.5]})")),
            "/surface/albedo/1: must be a number (it is a string)");
  EXPECT_EQ(one(minimal(R"(, "output": {"dir": "o", "previews": "no"})")),
            "/output/previews: must be true or false (it is a string)");
  std::string v2 = minimal("");
  v2.replace(v2.find("\"version\": 1"), 12, "\"version\": 2");
  EXPECT_EQ(one(v2), "/version: must be 1");
  // A constant or a choice of integers is an integer too: 1.0 is not the version 1.
  v2.replace(v2.find("\"version\": 2"), 12, "\"version\": 1.0");
  EXPECT_EQ(one(v2),
            "/version: must be an integer (it is 1.0, written with a fraction or an exponent: write 1)");
  std::string named = minimal("");
  named.replace(named.find("\"name\": \"t\""), 11, "\"name\": \"a b\"");
  EXPECT_EQ(one(named), "/name: must match the pattern ^[A-Za-z0-9_][A-Za-z0-9_.-]*$");
  std::string both = minimal("");
  both.replace(both.find("\"height\": {"), 11, "\"height\": {\"image\": \"h.exr\", ");
  EXPECT_EQ(one(both), "/height: needs exactly one of image or procedural");
  // Neither alternative given: one line naming them, not a missing key for each branch.
  std::string neither = minimal("");
  const std::string given = R"("height": {"procedural": {"kind": "flat", "size": [8, 8]}})";
  neither.replace(neither.find(given), given.size(), R"("height": {"texel_size": 1})");
  EXPECT_EQ(one(neither), "/height: needs exactly one of image or procedural");
  EXPECT_EQ(one(minimal(R"(, "output": {"dir": "o", "textures": [{"format": "png"}]})")),
            "/output/textures/0: needs exactly one of layers or pack and channels");
  EXPECT_EQ(one(minimal(R"(, "output": {"dir": "o", "textures": [{"pack": "orm"}]})")),
            "/output/textures/0: needs exactly one of layers or pack and channels");
}

// The reports name the job file and its output folder in JSON (UTF-8): a path in another encoding is
// refused in one line at load (validate and bake alike), not after the bake as report.json is written.
TEST_F(Manifest, PathsThatAreNotUtf8AreRefusedAtLoad) {
  const fs::path latin = dir_ / "d\xe9j\xe0";
  fs::create_directories(latin);
  std::ofstream(latin / "x.json") << minimal();
  const auto e = load_job(latin / "x.json", std::nullopt).errors;
  ASSERT_EQ(e.size(), 1u);
  EXPECT_NE(e[0].find("the job file's path "), std::string::npos) << e[0];
  EXPECT_NE(e[0].find("d\\xe9j\\xe0"), std::string::npos) << e[0];  // escaped in the message
  const auto o = load_job(write("y.json", minimal()), latin / "out").errors;
  ASSERT_EQ(o.size(), 1u);
  EXPECT_NE(o[0].find("--out: the output folder "), std::string::npos) << o[0];
  // UTF-8 itself is fine.
  const fs::path accented = dir_ / "d\xc3\xa9j\xc3\xa0";
  fs::create_directories(accented);
  std::ofstream(accented / "x.json") << minimal();
  EXPECT_TRUE(load_job(accented / "x.json", std::nullopt).errors.empty());
}

TEST_F(Manifest, MissingKey) {
  const auto e = errors(R"({"version": 1, "height": {"procedural": {"kind": "flat"}}, "bake": []})");
  ASSERT_EQ(e.size(), 1u);
  EXPECT_EQ(e[0], (dir_ / "x.json").string() + ": /: missing required key \"name\"");
}

TEST_F(Manifest, UnknownKeysAreErrorsAtEveryLevel) {
  auto e = errors(minimal(R"(, "bouncess": 2)"));
  ASSERT_EQ(e.size(), 1u);
  EXPECT_EQ(e[0], (dir_ / "x.json").string() + ": /bouncess: unknown key (did you mean \"bounces\"?)");
  e = errors(minimal("", R"([{"method": "p1", "directoins": 8}])"));
  ASSERT_EQ(e.size(), 1u);
  EXPECT_EQ(e[0],
            (dir_ / "x.json").string() + ": /bake/0/directoins: unknown key (did you mean \"directions\"?)");
}

// An unknown key names the key it is closest to, among those allowed beside it (the method's for a bake
// entry), when one is within two edits and no other is as close; a key near none, or near two, names none.
TEST_F(Manifest, AnUnknownKeyNamesTheClosestKnownKey) {
  struct Case {
    const char* entry;
    const char* pointer;
    const char* suggestion;  // "" for none
  };
  const Case cases[] = {
      {R"({"method": "p1", "direction": 8})", "/bake/0/direction", "directions"},
      {R"({"method": "p1", "Directions": 8})", "/bake/0/Directions", "directions"},
      {R"({"method": "relief", "serach_radius": 8})", "/bake/0/serach_radius", "search_radius"},
      {R"({"method": "p1", "search_radius": 8})", "/bake/0/search_radius", ""},  // relief's, not p1's
      {R"({"method": "p1", "colour": 8})", "/bake/0/colour", ""},
  };
  for (const Case& c : cases) {
    SCOPED_TRACE(c.entry);
    const auto e = errors(minimal("", std::string("[") + c.entry + "]"));
    ASSERT_EQ(e.size(), 1u);
    const std::string want = (dir_ / "x.json").string() + ": " + c.pointer + ": unknown key";
    EXPECT_EQ(e[0], *c.suggestion ? want + " (did you mean \"" + c.suggestion + "\"?)" : want);
  }
  const auto e = errors(minimal(R"(, "outptu": {"dir": "o"})"));
  ASSERT_FALSE(e.empty());
  EXPECT_EQ(e[0], (dir_ / "x.json").string() + ": /outptu: unknown key (did you mean \"output\"?)");
}

TEST_F(Manifest, UnknownMethod) {
  const auto e = errors(minimal("", R"([{"method": "magic"}])"));
  ASSERT_EQ(e.size(), 1u);
  EXPECT_EQ(e[0], (dir_ / "x.json").string() +
                      ": /bake/0/method: unknown method \"magic\" (one of \"farfield\", \"hbao\", \"hsao\", "
                      "\"lsao\", \"nlp\", \"p1\", \"p2\", \"relief\", \"sun\", \"vo\")");
}

// Enum errors list the allowed values, in the job schema and in a method's own schema.
TEST_F(Manifest, EnumErrorsListTheAllowedValues) {
  auto e = errors(minimal("", R"([{"method": "hbao", "falloff": "gauss"}])"));
  ASSERT_EQ(e.size(), 1u);
  EXPECT_EQ(e[0], (dir_ / "x.json").string() +
                      ": /bake/0/falloff: must be one of \"none\", \"step\", \"linear\", \"smooth\", "
                      "\"exponential\", \"rational\"");
  e = errors(minimal("", R"([{"method": "p1", "layers": ["ao", "horizn"]}])"));
  ASSERT_EQ(e.size(), 1u);
  EXPECT_NE(e[0].find("/bake/0/layers/1: must be one of \"ao\", \"vsky\""), std::string::npos) << e[0];
  e = errors(minimal("", R"([{"method": "p2", "subdivide": 3}])"));
  ASSERT_EQ(e.size(), 1u);
  EXPECT_EQ(e[0], (dir_ / "x.json").string() + ": /bake/0/subdivide: must be one of 1, 2, 4");
}

// A missing baseline is found before the bake (it used to fail after hours of baking), and the message says
// how to make the first one.
TEST_F(Manifest, MissingBaselineIsFoundBeforeBaking) {
  const auto e = errors(
      R"({"version": 1, "name": "t", "height": {"procedural": {"kind": "fractal", "size": [8, 8]}},
          "bake": [{"method": "p1"}], "reference": {"samples": 4}, "report": {"baseline": "base/report.json"}})");
  ASSERT_EQ(e.size(), 1u);
  EXPECT_NE(e[0].find(": /report/baseline: no such file: "), std::string::npos) << e[0];
  EXPECT_NE(e[0].find("--update-baseline"), std::string::npos) << e[0];
}

TEST_F(Manifest, MissingInputFile) {
  const auto e =
      errors(R"({"version": 1, "name": "t", "height": {"image": "nope.exr"}, "bake": [{"method": "p1"}]})");
  ASSERT_EQ(e.size(), 1u);
  EXPECT_NE(e[0].find(": /height/image: no such file: "), std::string::npos) << e[0];
}

TEST_F(Manifest, EnvironmentNeedsExactlyOneKind) {
  const auto e = errors(minimal(R"(, "environment": {"uniform": 1, "latlong": "a.exr"})"));
  ASSERT_GE(e.size(), 1u);
  EXPECT_NE(e[0].find(": /environment: needs exactly one of"), std::string::npos) << e[0];
}

TEST_F(Manifest, SeveralViolationsAreAllReported) {
  const auto e = errors(minimal(R"(, "bounces": -1, "output": {"pixel_type": "double"})"));
  EXPECT_EQ(e.size(), 2u);
}

TEST_F(Manifest, UnreadableFile) {
  const JobLoad r = load_job(dir_ / "absent.json", std::nullopt);
  ASSERT_EQ(r.errors.size(), 1u);
  EXPECT_NE(r.errors[0].find("absent.json: No such file or directory"), std::string::npos) << r.errors[0];
}

}  // namespace
}  // namespace hfbake

namespace hfbake {
namespace {

// Hostile job files: each is one line naming the file (and the pointer where there is one),
// never a crash, a hang or an absurd allocation.
TEST_F(Manifest, HostileFilesAreOneLineErrors) {
  const std::string x = (dir_ / "x.json").string();
  auto one = [&](const std::string& text) {
    const auto e = errors(text);
    EXPECT_EQ(e.size(), 1u);
    return e.empty() ? std::string() : e[0];
  };
  EXPECT_EQ(one(minimal(R"(, "bounces": 1e309)")), x + ": malformed JSON: number overflow parsing '1e309'");
  EXPECT_EQ(one(R"({"version": 1, "name": "a", "name": "b"})"),
            x + ": /name: duplicate key (the last value would silently replace the first)");
  EXPECT_EQ(one(minimal("", R"([{"method": "p1"}, {"method": "hbao", "radius": 2, "radius": 3}])")),
            x + ": /bake/1/radius: duplicate key (the last value would silently replace the first)");
  EXPECT_EQ(one(minimal(
                "", R"([{"method": "p1", "layers": ["ao"]}, {"method": "p1", "x": [1, {"k": 1, "k": 2}]}])")),
            x + ": /bake/1/x/1/k: duplicate key (the last value would silently replace the first)");
  // The same key in different objects is fine.
  EXPECT_TRUE(
      errors(minimal("", R"([{"method": "p1", "directions": 8}, {"method": "p1", "directions": 16}])"))
          .empty());
  EXPECT_EQ(one(std::string(100000, '[')), x + ": line 1, column 65: nested deeper than 64 levels");
  // Brackets inside strings are not nesting.
  EXPECT_TRUE(errors(minimal(R"(, "description": ")" + std::string(200, '[') + "\"")).empty());
  // An integer beyond int64 is refused at its pointer with the key's bound, or the 64-bit one where the key
  // has none: not as a wrapped value ("must be >= 1") or as "not an integer".
  EXPECT_EQ(one(minimal("", R"([{"method": "p1", "directions": 123456789012345678901234567890}])")),
            x + ": /bake/0/directions: must be <= 4096 (it is 1.2345678901234568e+29)");
  EXPECT_EQ(one(minimal("", R"([{"method": "p1", "directions": 9223372036854775808}])")),
            x + ": /bake/0/directions: must be <= 4096 (it is 9223372036854775808)");
  const std::string seeded = R"({"version": 1, "name": "t", "bake": [{"method": "p1"}], "height": )"
                             R"({"procedural": {"kind": "fractal", "size": [8, 8], "seed": )";
  EXPECT_EQ(one(seeded + "9223372036854775808}}}"),
            x + ": /height/procedural/seed: is 9223372036854775808, beyond a 64-bit integer (at most "
                "9223372036854775807)");
  EXPECT_EQ(one(seeded + "18446744073709551616}}}"),
            x + ": /height/procedural/seed: is 1.8446744073709552e+19, beyond a 64-bit integer (at most "
                "9223372036854775807)");
  EXPECT_TRUE(errors(seeded + "9223372036854775807}}}").empty());
}

// Values a user could mistype into nonsense are refused with the key's range.
TEST_F(Manifest, RangesForValuesAUserCouldMistype) {
  auto first = [&](const std::string& text) {
    const auto e = errors(text);
    return e.empty() ? std::string("accepted") : e[0].substr((dir_ / "x.json").string().size() + 2);
  };
  const std::string h =
      R"({"version": 1, "name": "t", "bake": [{"method": "p1"}], "height": {"procedural": {"kind": "flat", "size": [8, 8]}, )";
  EXPECT_EQ(first(h + R"("texel_size": 1e308}})"), "/height/texel_size: must be <= 1000000");
  EXPECT_EQ(first(h + R"("texel_size": 1e-300}})"), "/height/texel_size: must be >= 0.000001");
  EXPECT_EQ(first(h + R"("height_scale": 1e38}})"), "/height/height_scale: must be <= 1000000");
  EXPECT_EQ(first(minimal(R"(, "surface": {"albedo": 5})")).rfind("/surface/albedo", 0), 0u);
  EXPECT_EQ(first(minimal(R"(, "surface": {"albedo": [0.5, 1.2, 0.5]})")).rfind("/surface/albedo", 0), 0u);
  EXPECT_EQ(first(minimal(R"(, "surface": {"albedo": [0.5, 1, 0.5]})")), "accepted");
  EXPECT_EQ(
      first(minimal(R"(, "lights": [{"directional": {"direction": [1e-200, 0, 1e-200], "irradiance": 1}}])")),
      "/lights/0/directional/direction: must have a length of at least 1e-6 (it is normalised; a shorter one "
      "has no direction)");
  EXPECT_EQ(first(minimal(R"(, "lights": [{"directional": {"direction": [0, 0, 1], "irradiance": 1e308}}])"))
                .rfind("/lights/0/directional/irradiance", 0),
            0u);
}

TEST_F(Manifest, OnlyRegularFilesUnderTheSizeLimitAreRead) {
  const fs::path fifo = dir_ / "fifo.json";
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
  auto e = load_job(fifo, std::nullopt).errors;  // would block forever if opened
  ASSERT_EQ(e.size(), 1u);
  EXPECT_EQ(e[0], fifo.string() + ": not a regular file");
  e = load_job("/dev/zero", std::nullopt).errors;  // would grow without end if read
  ASSERT_EQ(e.size(), 1u);
  EXPECT_EQ(e[0], "/dev/zero: not a regular file");
  e = load_job(dir_, std::nullopt).errors;
  ASSERT_EQ(e.size(), 1u);
  const fs::path big = dir_ / "big.json";
  {
    std::ofstream out(big);
    out << minimal(R"(, "description": ")" + std::string(kMaxJsonFileBytes, 'a') + "\"");
  }
  e = load_job(big, std::nullopt).errors;
  ASSERT_EQ(e.size(), 1u);
  EXPECT_NE(e[0].find("at most " + std::to_string(kMaxJsonFileBytes)), std::string::npos) << e[0];
}

}  // namespace
}  // namespace hfbake
