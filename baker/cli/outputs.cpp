#include "cli/outputs.hpp"

#include <signal.h>
#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <fstream>
#include <string_view>

#include "cli/texture_plan.hpp"
#include "core/error.hpp"
#include "io/exr_output.hpp"
#include "io/geotiff_output.hpp"
#include "io/preview.hpp"
#include "io/texture_output.hpp"

namespace hfbake {
namespace fs = std::filesystem;

namespace {

constexpr std::string_view kStagePrefix = ".hfbake-staging-";
// The longest side of a field whose EXRs are written as scanlines (larger ones are tiled).
constexpr int kLargestScanlineExr = 2048;

std::string host_name() {
  char buf[256] = {};
  if (gethostname(buf, sizeof buf - 1) != 0) return "localhost";
  return buf;
}

}  // namespace

std::string azimuth_convention(const Georeference& geo) {
  std::string s =
      "phi (directions, horizon channel k: phi_k = 360 k / K degrees) is measured from +x (image columns, i) "
      "towards +y (image rows, j)";
  const auto& g = geo.geotransform;
  if (!geo.from_file || geo.crs_wkt.empty()) return s + "; the raster has no CRS";
  // Per unit +x the map moves east by sign(g[1]); per unit +y north by sign(g[5]) (g[5] < 0: rows go
  // south). A direction phi: east = sign(g[1]) cos phi, north = sign(g[5]) sin phi; compass azimuth A has
  // east = sin A, north = cos A.
  const bool east = g[1] > 0, north_up = g[5] < 0;
  if (east && north_up)
    return s + "; north-up raster: +x = east, +y = south, compass azimuth = (90 + phi) mod 360";
  if (east && !north_up)
    return s + "; south-up raster: +x = east, +y = north, compass azimuth = (90 - phi) mod 360";
  if (!east && north_up)
    return s +
           "; north-up, east-to-west raster: +x = west, +y = south, compass azimuth = (270 - phi) mod 360";
  return s + "; +x = west, +y = north, compass azimuth = (270 + phi) mod 360";
}

std::optional<StageOwner> parse_stage_name(const std::string& name) {
  if (name.compare(0, kStagePrefix.size(), kStagePrefix) != 0) return std::nullopt;
  StageOwner owner;
  std::string rest = name.substr(kStagePrefix.size());
  const auto at = rest.rfind('@');  // job names have no '@' (schema); older stages had no host part
  if (at != std::string::npos) {
    owner.host = rest.substr(at + 1);
    rest.resize(at);
  }
  const auto dash = rest.rfind('-');
  if (dash == std::string::npos || dash + 1 == rest.size()) return std::nullopt;
  long long pid = 0;
  for (std::size_t i = dash + 1; i < rest.size(); ++i) {
    if (rest[i] < '0' || rest[i] > '9' || pid > (1ll << 40)) return std::nullopt;
    pid = pid * 10 + (rest[i] - '0');
  }
  if (pid <= 0) return std::nullopt;
  owner.pid = pid;
  return owner;
}

std::vector<fs::path> remove_stale_stages(const fs::path& dir) {
  std::vector<fs::path> removed;
  const std::string host = host_name();
  std::error_code ec;
  for (fs::directory_iterator it(dir, ec), end; !ec && it != end; it.increment(ec)) {
    const std::optional<StageOwner> owner = parse_stage_name(it->path().filename().string());
    if (!owner || !it->is_directory(ec)) continue;
    // Another machine's process (a shared output folder) cannot be checked from here: keep its stage.
    if (!owner->host.empty() && owner->host != host) continue;
    if (owner->pid == getpid()) continue;  // this process's own (another job's) stage
    // kill(pid, 0): 0 = alive, EPERM = alive but another user's, ESRCH = no such process.
    if (kill(pid_t(owner->pid), 0) == 0 || errno != ESRCH) continue;
    std::error_code remove_ec;
    fs::remove_all(it->path(), remove_ec);
    if (!remove_ec) removed.push_back(it->path());
  }
  return removed;
}

OutputStage::OutputStage(const Job& job) : job_(job) {
  std::error_code ec;
  fs::create_directories(job.output.dir, ec);
  if (ec || !fs::is_directory(job.output.dir))
    throw InputError(job.file.string(), "/output/dir",
                     "cannot create " + job.output.dir.string() + ": " +
                         (ec ? ec.message() : std::string("not a folder")));
  // Stages that processes which no longer run left behind (killed by SIGKILL, a second signal, a crash).
  stale_removed_ = remove_stale_stages(job.output.dir);
  // Hidden, per process, host and job: concurrent jobs and concurrent hfbake processes never share a stage.
  stage_ = job.output.dir /
           (std::string(kStagePrefix) + job.name + "-" + std::to_string(getpid()) + "@" + host_name());
  fs::remove_all(stage_, ec);
  if (!fs::create_directory(stage_, ec) || ec)
    throw InputError(job.file.string(), "/output/dir",
                     "cannot write into " + job.output.dir.string() + ": " + ec.message());
}

OutputStage::~OutputStage() {
  std::error_code ec;
  fs::remove_all(stage_, ec);
}

void OutputStage::write_layers(const std::string& stem, const LayerSet& layers) {
  const std::string exr = job_.name + "." + stem + ".exr";
  ExrOptions options;
  options.float_pixels = job_.output.float_pixels;
  options.compression = job_.output.compression;
  // Tiles of 256 once a field is larger than a preview: OpenImageIO's cache (oiiotool, iv) and Nuke then read
  // what they show, not the whole file (a 512^2 crop of a 16384^2 scanline EXR: 9.6 s and 1.25 GB; tiled:
  // 0.55 s, 0.14 GB), for 0.2 % more bytes. Smaller fields stay scanline files, as before.
  options.tile_size = std::max(layers.width, layers.height) > kLargestScanlineExr ? 256 : 0;
  options.attributes.emplace_back("hfbake:azimuth_convention", azimuth_convention(georeference_));
  write_exr(stage_ / exr, layers, options);
  staged_.push_back(exr);
  if (job_.output.geotiff) write_geotiffs(stem, layers);
  write_textures(stem, layers);
  if (!job_.output.previews) return;
  PreviewOptions preview;
  preview.display = job_.output.preview_display;
  preview.view = job_.output.preview_view;
  for (const Layer& layer : layers.layers) {
    // Previews of what a person can look at: scalars and colours, not per-direction or SH stacks.
    if (layer.channel_count() != 1 && layer.channel_count() != 3) continue;
    if (layer.name.size() > 7 && layer.name.compare(layer.name.size() - 7, 7, "_stderr") == 0) continue;
    const std::string png = job_.name + "." + stem + "." + layer.name + ".png";
    write_preview(stage_ / png, layers, layer, preview);
    staged_.push_back(png);
  }
}

void OutputStage::write_geotiffs(const std::string& stem, const LayerSet& layers) {
  GeoTiffOptions options;
  for (const auto& [key, value] : layers.attributes) {
    std::string k = key;  // "hfbake:method" -> "HFBAKE_METHOD" (GDAL metadata names)
    for (char& c : k) c = c == ':' ? '_' : char(std::toupper(static_cast<unsigned char>(c)));
    options.metadata.emplace_back(k, value);
  }
  options.metadata.emplace_back("HFBAKE_AZIMUTH_CONVENTION", azimuth_convention(georeference_));
  for (const Layer& layer : layers.layers) {
    const std::string tif = job_.name + "." + stem + "." + layer.name + ".tif";
    write_geotiff(stage_ / tif, layers, layer, georeference_, options);
    staged_.push_back(tif);
  }
}

void OutputStage::write_textures(const std::string& stem, const LayerSet& layers) {
  for (PlannedTexture& t : plan_textures(job_)) {
    if (t.stem != stem) continue;
    for (std::size_t c = 0; c < t.spec.channels.size(); ++c) {  // suffix -> the layer's channel index
      TextureSource& s = t.spec.channels[c];
      if (s.layer.empty()) continue;
      const Layer* layer = layers.find(s.layer);
      const auto at = layer ? std::find(layer->channels.begin(), layer->channels.end(), t.suffixes[c])
                            : std::vector<std::string>::const_iterator();
      if (!layer || at == layer->channels.end())
        throw std::logic_error("texture " + t.file + ": " + stem + " has no channel " + s.layer + "." +
                               t.suffixes[c]);
      s.channel = int(at - layer->channels.begin());
    }
    std::filesystem::create_directories((stage_ / t.file).parent_path());
    write_texture(stage_ / t.file, layers, t.spec);
    staged_.push_back(t.file);
  }
}

void OutputStage::write_text(const std::string& filename, const std::string& text) {
  std::ofstream out(stage_ / filename, std::ios::binary);
  out << text;
  out.close();
  if (!out) throw InputError((job_.output.dir / filename).string(), "", "cannot write file");
  staged_.push_back(filename);
}

std::vector<fs::path> OutputStage::commit() {
  std::vector<fs::path> final_paths;
  for (const fs::path& name : staged_) {
    const fs::path target = job_.output.dir / name;
    std::error_code ec;
    if (name.has_parent_path()) fs::create_directories(target.parent_path(), ec);  // textures/
    fs::rename(stage_ / name, target, ec);  // same folder tree: an atomic replace
    if (ec) throw InputError(target.string(), "", "cannot move into place: " + ec.message());
    final_paths.push_back(target);
  }
  staged_.clear();
  return final_paths;
}

}  // namespace hfbake
