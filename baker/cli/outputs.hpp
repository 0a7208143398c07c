// A job's output files: staged in a private folder inside the output folder and moved into place only
// when the whole job has succeeded, so a failure or an interrupt never leaves a partial output behind.
#pragma once

#include <filesystem>
#include <string>
#include <vector>

#include "core/layers.hpp"
#include "job/manifest.hpp"

namespace hfbake {

class OutputStage {
 public:
  // Creates the output folder and the staging folder in it; InputError naming /output/dir if impossible.
  explicit OutputStage(const Job& job);
  ~OutputStage();  // removes the staging folder and anything left in it
  OutputStage(const OutputStage&) = delete;
  OutputStage& operator=(const OutputStage&) = delete;

  // Writes <name>.<stem>.exr (and previews when the job asks for them) into the stage.
  void write_layers(const std::string& stem, const LayerSet& layers);
  // Writes a text file (report.json, ...) into the stage.
  void write_text(const std::string& filename, const std::string& text);
  // Moves every staged file to its final place (each rename is atomic) and returns the final paths.
  std::vector<std::filesystem::path> commit();

 private:
  const Job& job_;
  std::filesystem::path stage_;
  std::vector<std::filesystem::path> staged_;  // file names relative to the stage
};

}  // namespace hfbake
