#include "cli/method_dispatch.hpp"

#include "cli/scene_loader.hpp"
#include "cli/texture_plan.hpp"
#include "core/error.hpp"

namespace hfbake {

MethodContext job_method_context(const Job& job) {
  MethodContext c;
  const FieldSize size = probe_field_size(job);
  const nlohmann::json& h = job.doc["height"];
  c.field.width = size.width;
  c.field.height = size.height;
  c.field.texel_size = job_texel_size(job);
  c.field.wrap = h.value("wrap", "clamp") == "repeat" ? Wrap::repeat : Wrap::clamp;
  c.bounces = job_bounces(job);
  return c;
}

std::vector<std::string> resolve_job(Job& job) {
  std::vector<std::string> errors;
  const std::string file = job.file.string();
  MethodContext context;
  try {
    context = job_method_context(job);
  } catch (const InputError& e) {
    errors.push_back(e.line());
    return errors;
  }
  for (BakeEntry& entry : job.bakes) {
    try {
      entry.resolved = resolve_method_params(entry.params, context, file, entry.pointer);
    } catch (const InputError& e) {
      errors.push_back(e.line());
    }
  }
  if (job.has_reference && errors.empty()) {
    try {
      job.reference_resolved = read_reference_options(job.doc, context, file).resolved;
    } catch (const InputError& e) {
      errors.push_back(e.line());
    }
  }
  if (errors.empty()) {
    try {
      plan_textures(job);  // output.textures against the resolved layers
    } catch (const InputError& e) {
      errors.push_back(e.line());
    }
  }
  return errors;
}

LayerSet run_method(const BakeEntry& entry, const Scene& scene, const RunControl& rc) {
  const MethodInfo* m = find_method(entry.method);
  if (!m) throw InputError("", entry.pointer + "/method", "unknown method \"" + entry.method + "\"");
  return m->bake(scene, entry.params, rc);
}

ReferenceOptions job_reference_options(const Job& job, const Scene& scene) {
  MethodContext c;
  c.field = scene.field;
  c.bounces = scene.bounces;
  return read_reference_options(job.doc, c, job.file.string());
}

}  // namespace hfbake
