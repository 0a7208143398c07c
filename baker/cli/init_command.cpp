#include "cli/init_command.hpp"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <nlohmann/json.hpp>
#include <optional>
#include <system_error>
#include <vector>

#include "cli/method_dispatch.hpp"
#include "cli/scene_loader.hpp"
#include "cli/shell_words.hpp"
#include "core/error.hpp"
#include "core/safe_file.hpp"
#include "io/georaster_input.hpp"
#include "job/embedded_schemas.hpp"
#include "job/manifest.hpp"
#include "methods/method_table.hpp"

namespace hfbake {
namespace fs = std::filesystem;
using nlohmann::json;
using ordered = nlohmann::ordered_json;

namespace {

constexpr InitPreset kPresets[] = {
    {"game-ao",
     "a tiling game texture: p1's ao as a 16-bit PNG and its bent normals as an 8-bit normal map (tangent "
     "space, OpenGL)"},
    {"gis-relief",
     "a DEM: relief's sky-view factor and openness and p1's ao as GeoTIFFs georeferenced like the input"},
    {"reference-check", "p1 against the path-traced reference: report.html and an excess-error threshold"},
};

// Four significant digits, as a number a person edits.
double round4(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.4g", v);
  return std::strtod(buf, nullptr);
}

// A file's stem as a job name (the schema's pattern: ASCII letters, digits, _ . -, not starting with . or
// -): every other character one _ (a UTF-8 character of several bytes too: "hé" is "h_").
std::string job_name(const fs::path& file) {
  std::string name;
  for (const char c : file.stem().string()) {
    const auto u = static_cast<unsigned char>(c);
    if ((u & 0xC0) == 0x80) continue;  // a UTF-8 continuation byte: its character has its _ already
    name += u < 0x80 && (std::isalnum(u) || c == '_' || c == '.' || c == '-') ? c : '_';
  }
  if (name.empty() || name[0] == '.' || name[0] == '-') name.insert(name.begin(), '_');
  if (name.size() > 128) name.resize(128);
  return name;
}

// Problems with the input found by the job loader, as its lines.
struct InitRefused {
  std::vector<std::string> lines;
};

// What the presets need to know of the heights.
struct HeightsFound {
  Scene scene;
  bool georeferenced = false;  // the file's geotransform gives the texel size
  bool holes = false;          // NaN or NoData texels (filled)
};

// The height file read as a bake reads it: through a job that names only it.
HeightsFound read_heights(const std::string& image, const fs::path& job_file) {
  const json probe = {{"version", 1},
                      {"name", "init"},
                      {"height", {{"image", image}, {"nodata", "fill"}}},
                      {"bake", {{{"method", "p1"}}}}};
  JobLoad load = load_job_document(probe, job_file, std::nullopt);
  if (!load.job) throw InitRefused{load.errors};
  HeightsFound found;
  found.scene = load_scene(*load.job);
  found.georeferenced = found.scene.georeference.from_file;
  found.holes = !found.scene.georeference.holes.empty();
  return found;
}

// World units per stored unit for an image without georeferencing whose stored relief r is implausible for
// the field's extent E at 1 unit per stored unit (under 1 % of E or over 4 E, describe_heights' rule): the
// scale that makes the relief E / 10; else 1. A georeferenced raster's heights are data: kept.
double suggested_height_scale(const HeightsFound& h) {
  const HeightSource& s = h.scene.height_source;
  const double relief = s.stored_max - s.stored_min;
  const double extent = std::max(h.scene.field.width, h.scene.field.height) * h.scene.field.texel_size;
  // An integer image's stored units are levels, not world units (an 8-bit map's 0..255 over 64 texels would
  // be cliffs four times the field's side); a float image's may be world units when plausible.
  if (h.georeferenced || relief <= 0 || (!s.integer && relief >= 0.01 * extent && relief <= 4 * extent))
    return 1;
  return round4(0.1 * extent / relief);
}

// A georeferenced band's heights as stored x scale + offset in the pixels' unit: what the band declares
// (GDAL's scale and offset, and a unit of its heights other than the pixels', metres_per), which a job
// applies only through height_scale and height_offset (docs/heights.md). `why` says which, for the job's
// notes; empty for a band that declares neither.
struct DeclaredHeights {
  double scale = 1, offset = 0;
  std::string why;
};
DeclaredHeights declared_heights(const HeightSource& s) {
  DeclaredHeights d;
  if (s.file_scale != 1 || s.file_offset != 0) {
    d.scale = s.file_scale, d.offset = s.file_offset;
    d.why = "the file's declared scale " + json(s.file_scale).dump() + " and offset " +
            json(s.file_offset).dump();
  }
  const double ratio = height_unit_ratio(s.height_unit, s.pixel_unit_metres);
  if (ratio != 1) {
    d.scale *= ratio, d.offset *= ratio;
    d.why += (d.why.empty() ? "" : ", then ") + std::string("the band's heights in ") + s.height_unit +
             " converted into the pixels' " + (s.pixel_unit.empty() ? "metres" : s.pixel_unit);
  }
  return d;
}

// The job in the order a person reads it: version, name, description, height, bake, the rest.
ordered preset_job(const std::string& preset, const std::string& name, const std::string& image,
                   const HeightsFound& h, double scale, const DeclaredHeights& declared) {
  const HeightField& f = h.scene.field;
  ordered height = {{"image", image}};
  std::string notes;
  if (!h.georeferenced) {
    height["texel_size"] = 1.0;
    notes += "texel_size: world units between texels (1: the map's size in texels; set the real size). ";
  } else {
    notes += "texel_size: the raster's pixel size (from the file). ";
  }
  if (!declared.why.empty()) {
    if (declared.scale != 1) height["height_scale"] = declared.scale;
    if (declared.offset != 0) height["height_offset"] = declared.offset;
    notes += "height_scale and height_offset: " + declared.why + " (docs/heights.md). ";
  } else if (scale != 1) {
    height["height_scale"] = scale;
    notes += "height_scale " + json(scale).dump() +
             " makes the relief a tenth of the field's side: set your map's real height per stored unit "
             "(docs/heights.md). ";
  } else {
    notes += "Heights are the stored values x height_scale (docs/heights.md). ";
  }
  if (h.holes) {
    height["nodata"] = "fill";
    notes += "nodata fill: the file's holes are filled from their neighbours. ";
  }
  ordered job = {{"version", 1}, {"name", name}, {"description", ""}, {"height", nullptr}};
  ordered output = {{"dir", "out/" + name}, {"previews", true}};
  if (preset == "game-ao") {
    // A georeferenced raster is a piece of the Earth, which does not tile (and a geographic one has no
    // repeating frame): clamp.
    if (!h.georeferenced) {
      height["wrap"] = "repeat";
      notes += "wrap repeat: the map tiles (set clamp if it does not). ";
    } else {
      notes += "wrap clamp: a georeferenced raster does not tile. ";
    }
    job["bake"] = {{{"method", "p1"}, {"directions", 32}, {"layers", {"ao", "bent_normal"}}}};
    output["textures"] = {
        {{"layers", {"ao"}}, {"bits", 16}, {"format", "png"}},
        {{"layers", {"bent_normal"}}, {"space", "tangent"}, {"y", "opengl"}, {"format", "png"}}};
    notes += "Textures in out/" + name + "/textures (y: directx for Unreal).";
  } else if (preset == "gis-relief") {
    const double radius = 10 * f.texel_size;
    job["bake"] = {{{"method", "relief"}, {"directions", 16}, {"search_radius", radius}},
                   {{"method", "p1"}, {"directions", 32}, {"layers", {"ao", "vsky"}}}};
    output["geotiff"] = true;
    notes += "relief search_radius: " + json(radius).dump() + " world units (10 texels). GeoTIFFs in out/" +
             name + ".";
  } else {
    job["bake"] = {{{"method", "p1"}, {"directions", 32}, {"layers", {"ao"}}}};
    job["reference"] = {{"samples", 64}, {"seed", 1}};
    job["report"] = {{"thresholds", {{"p1.ao.excess_rmse", 0.01}}}};
    notes += "The reference path-traces every texel (";
    notes +=
        std::to_string(f.width) + "x" + std::to_string(f.height) +
        "): fewer samples or a smaller field for a quick check. The threshold fails the bake (exit 1) when "
        "p1's ao error beyond the reference's noise exceeds it.";
  }
  job["description"] = "hfbake init --preset " + preset + ". " + notes;
  job["height"] = height;
  job["output"] = output;
  return job;
}

// The layers a method writes, from its schema: the enum of "layers", else the schema's description of them.
std::string method_layers(const std::string& method) {
  for (const EmbeddedSchema& s : embedded_schemas()) {
    if (s.path != "methods/" + method + ".schema.json") continue;
    const json schema = json::parse(s.text);
    const json layers = schema["properties"].value("layers", json::object());
    const json items = layers.value("items", json::object());
    if (items.contains("enum")) {
      std::string out;
      for (const json& l : items["enum"]) out += (out.empty() ? "" : ", ") + l.get<std::string>();
      return out;
    }
    std::string text = layers.value("description", std::string());
    const std::string lead = "Layers to write: ";
    if (text.rfind(lead, 0) == 0) text = text.substr(lead.size());
    // The first sentence: up to a full stop before a capital (not "indirect_b1 .. indirect_b<n>").
    for (std::size_t i = 0; i + 2 < text.size(); ++i)
      if (text[i] == '.' && text[i + 1] == ' ' && std::isupper(static_cast<unsigned char>(text[i + 2]))) {
        text.resize(i);
        break;
      }
    if (!text.empty() && text.back() == '.') text.pop_back();
    return text;
  }
  return "";
}

}  // namespace

std::span<const InitPreset> init_presets() {
  return kPresets;
}

std::string methods_and_presets_help() {
  // `name` padded to `width` columns (at least one space after it).
  auto column = [](const std::string& name, std::size_t width) {
    return name + std::string(name.size() < width ? width - name.size() : 1, ' ');
  };
  std::string out = "Methods (bake entries; the layers each writes):\n";
  for (const MethodInfo& m : method_table()) {
    out += "  " + column(m.name, 10) + m.summary + "\n";
    out += "            layers: " + method_layers(m.name) + "\n";
  }
  out += "\nPresets (hfbake init HEIGHT_FILE --preset NAME):\n";
  for (const InitPreset& p : kPresets) out += "  " + column(p.name, 17) + p.summary + "\n";
  out +=
      "\nhfbake COMMAND --help for a command's options; the manual: docs/ in the repository, installed in "
      "PREFIX/share/doc/hfbake/docs.\n";
  return out;
}

int run_init(const InitOptions& options) {
  auto refuse = [](const std::string& line) {
    std::fprintf(stderr, "hfbake: error: %s\n", line.c_str());
    return 2;
  };
  const fs::path& height = options.height_file;
  std::error_code ec;
  if (!fs::is_regular_file(height, ec))
    return refuse(height.string() + ": " + (fs::exists(height, ec) ? "not a file" : "no such file"));
  const fs::path job_file = options.out ? *options.out : fs::path(job_name(height) + ".json");
  if (fs::equivalent(job_file, height, ec) && !ec)
    return refuse(job_file.string() + ": is the height file itself: give the job another name (-o)");
  // Nor a file GDAL reads with it (a world file, a VRT's sources, an .aux.xml): --force would replace it.
  for (const fs::path& f : raster_files(height))
    if (fs::equivalent(job_file, f, ec) && !ec)
      return refuse(job_file.string() + ": is " + f.string() +
                    ", which GDAL reads for the height file: give the job another name (-o)");
  if (fs::is_directory(job_file, ec))
    return refuse(job_file.string() + ": is a folder: --out names the job file to write (e.g. " +
                  (job_file / (job_name(height) + ".json")).string() + ")");
  // A job file is a file of its own, beside which its relative paths resolve: never a stream, which a
  // rename would replace (/dev/stdout with --force).
  if (descriptor_named(job_file) >= 0 || (fs::exists(job_file, ec) && !fs::is_regular_file(job_file, ec)))
    return refuse(job_file.string() + ": is not a file: --out names the job file to write");
  if (fs::exists(job_file, ec) && !options.force)
    return refuse(job_file.string() + ": exists (--force writes over it)");
  const fs::path job_dir = fs::absolute(job_file).parent_path();
  if (!fs::is_directory(job_dir, ec)) return refuse(job_file.string() + ": its folder does not exist");
  std::string image = fs::relative(fs::absolute(height), job_dir, ec).generic_string();
  if (ec || image.empty()) image = fs::absolute(height).generic_string();

  try {
    HeightsFound found = read_heights(image, job_file);
    const DeclaredHeights declared =
        found.georeferenced ? declared_heights(found.scene.height_source) : DeclaredHeights{};
    const double scale = declared.why.empty() ? suggested_height_scale(found) : declared.scale;
    const double offset = declared.offset;
    // Named after the job file (the height file's stem unless --out names another): jobs written for one
    // height file with several presets (--out) bake into folders of their own.
    const ordered doc = preset_job(options.preset, job_name(job_file), image, found, scale, declared);
    // The job as validate checks it, before anything is written.
    JobLoad load = load_job_document(json::parse(doc.dump()), job_file, std::nullopt);
    if (load.job) load.errors = resolve_job(*load.job);
    if (!load.job || !load.errors.empty()) {
      for (const std::string& e : load.errors) std::fprintf(stderr, "hfbake: error: %s\n", e.c_str());
      return 1;  // a preset that does not validate is hfbake's fault, not the input's
    }
    // A temporary renamed into place: a link at job_file is replaced, never written through.
    try {
      write_file_atomically(job_file, doc.dump(2) + "\n");
    } catch (const std::system_error& e) {
      return refuse(job_file.string() + ": cannot write it: " + e.code().message());
    }
    HeightSource& s = found.scene.height_source;
    s.scale = scale, s.offset = offset;
    s.world_min = std::min(s.stored_min * scale, s.stored_max * scale) + offset;
    s.world_max = std::max(s.stored_min * scale, s.stored_max * scale) + offset;
    const HeightsReport heights = describe_heights(*load.job, found.scene);
    std::fprintf(stderr, "hfbake: wrote %s (preset %s)\nhfbake: %s\n", job_file.c_str(),
                 options.preset.c_str(), heights.line.c_str());
    if (!heights.warning.empty()) std::fprintf(stderr, "hfbake: warning: %s\n", heights.warning.c_str());
    // The next step as a line a shell runs: the job file one word, never taken for an option.
    const std::string word =
        shell_word(job_file.string().rfind('-', 0) == 0 ? "./" + job_file.string() : job_file.string());
    std::fprintf(stderr, "hfbake: edit it, then: hfbake validate %s && hfbake bake %s\n", word.c_str(),
                 word.c_str());
    return 0;
  } catch (const InputError& e) {
    // The job file is not written yet: what its heights refuse is the height file's.
    if (e.file() == job_file.string()) return refuse(height.string() + ": " + e.what());
    return refuse(e.line());
  } catch (const InitRefused& e) {
    for (const std::string& line : e.lines) refuse(line);
    return 2;
  }
}

}  // namespace hfbake
