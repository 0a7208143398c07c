#include "cli/outputs.hpp"

#include <unistd.h>

#include <fstream>

#include "core/error.hpp"
#include "io/exr_output.hpp"
#include "io/preview.hpp"

namespace hfbake {
namespace fs = std::filesystem;

OutputStage::OutputStage(const Job& job) : job_(job) {
  std::error_code ec;
  fs::create_directories(job.output.dir, ec);
  if (ec || !fs::is_directory(job.output.dir))
    throw InputError(job.file.string(), "/output/dir",
                     "cannot create " + job.output.dir.string() + ": " +
                         (ec ? ec.message() : std::string("not a folder")));
  // Hidden, per process and job: concurrent jobs and concurrent hfbake processes never share a stage.
  stage_ = job.output.dir / (".hfbake-staging-" + job.name + "-" + std::to_string(getpid()));
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
  write_exr(stage_ / exr, layers, options);
  staged_.push_back(exr);
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
    fs::rename(stage_ / name, target, ec);  // same folder tree: an atomic replace
    if (ec) throw InputError(target.string(), "", "cannot move into place: " + ec.message());
    final_paths.push_back(target);
  }
  staged_.clear();
  return final_paths;
}

}  // namespace hfbake
