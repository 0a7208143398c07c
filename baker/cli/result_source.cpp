#include "cli/result_source.hpp"

#include <chrono>

#include "cli/method_dispatch.hpp"
#include "cli/progress.hpp"
#include "cli/reference_checkpoint.hpp"
#include "reference/bake_reference.hpp"

namespace hfbake {

ResultSource computed_results(const Job& job, const Scene& scene, OutputStage& stage, FieldSize size) {
  ResultSource source;
  source.method = [&job, &scene](int entry, const RunControl& rc) {
    const auto t0 = std::chrono::steady_clock::now();
    const double cpu0 = process_cpu_seconds();
    SourcedLayers out;
    out.layers = run_method(job.bakes[std::size_t(entry)], scene, rc);
    out.seconds = seconds_since(t0);
    out.cpu_seconds = process_cpu_seconds() - cpu0;
    return out;
  };
  source.reference = [&job, &scene, &stage, size](const RunControl& rc) {
    const auto t0 = std::chrono::steady_clock::now();
    const ReferenceOptions& options = job_reference_options(job);
    const ReferenceCheckpoint checkpoint(stage.checkpoint_dir(),
                                         reference_checkpoint_key(job, options, size.width, size.height));
    std::string problem;
    ReferenceResume resume = checkpoint.resume(&problem);
    SourcedLayers out;
    out.layers = bake_reference(scene, options, rc, &resume);
    out.seconds = seconds_since(t0);
    if (!problem.empty())
      out.notices.push_back("reference checkpoint: " + problem + " (a kill now loses it)");
    if (resume.bands_resumed > 0)
      out.notices.push_back("reference: resumed " + std::to_string(resume.bands_resumed) + " of " +
                            std::to_string(resume.bands_resumed + resume.bands_traced) +
                            " bands from a killed bake's checkpoints");
    out.record["bands"] = {{"resumed", resume.bands_resumed}, {"traced", resume.bands_traced}};
    return out;
  };
  return source;
}

ResultSource merged_results(MergedShards& shards, const Scene& scene) {
  ResultSource source;
  source.method = [&shards, &scene](int entry, const RunControl& rc) {
    SourcedLayers out;
    out.layers = shards.method(entry, scene, rc);
    out.seconds = shards.seconds(entry);
    out.cpu_seconds = shards.cpu_seconds(entry);
    return out;
  };
  source.reference = [&shards](const RunControl&) {
    SourcedLayers out;
    out.layers = shards.reference();
    out.seconds = shards.seconds(-1);
    return out;
  };
  return source;
}

}  // namespace hfbake
