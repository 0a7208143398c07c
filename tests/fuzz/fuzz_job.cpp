// libFuzzer harness: a job file's text through everything `hfbake validate` does before it looks at the
// inputs' bytes: the bounded JSON parser (depth, duplicate keys, number ranges), parameter sweeps, the job
// schema and each method's schema, the checks the schema cannot express, then every method's parameter
// reader (the method table) on the field the job describes. A bad job must be a one-line error naming the
// file; anything else (a crash, an uncaught exception, UB, a leak, a multi-line message) is a finding.
#include <cstdint>
#include <string>

#include "core/error.hpp"
#include "fuzz_support.hpp"
#include "job/manifest.hpp"
#include "methods/method_table.hpp"

using namespace hfbake;

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  // A folder that does not exist: input files are "no such file" (their bytes are the other harnesses').
  static const std::string file = "/nonexistent-hfbake-fuzz/job.json";
  if (size > kMaxJsonFileBytes) return 0;  // read_json_file refuses these before parsing
  const std::string text(reinterpret_cast<const char*>(data), size);
  nlohmann::json doc;
  try {
    doc = parse_json_text(text, file);
  } catch (const InputError& e) {
    fuzz::check_error_line(e.line(), file);
    return 0;
  }
  JobLoad load = load_job_document(doc, file, std::nullopt);
  for (const std::string& e : load.errors) fuzz::check_error_line(e, file);
  if (!load.job) return 0;  // (a job naming input files is never whole here: they do not exist)
  // Every method's reader on the field the job describes (what resolve_job does once the size is known).
  MethodContext context;
  context.field.width = context.field.height = 64;
  const nlohmann::json& jd = load.job->doc;
  const nlohmann::json size_spec = jd["height"].value("procedural", nlohmann::json::object())
                                       .value("size", nlohmann::json::array({64, 64}));
  context.field.width = size_spec[0].get<int>();  // the schema bounds it to [2, 2^20]
  context.field.height = size_spec[1].get<int>();
  context.bounces = jd.value("bounces", 1);
  for (const BakeEntry& b : load.job->bakes) {
    try {
      const nlohmann::json r = resolve_method_params(b.params, context, file, b.pointer);
      const MethodInfo* m = find_method(b.method);
      if (m && m->working_bytes) (void)m->working_bytes(r, context);
      for (const auto& l : r.value("layers", nlohmann::json::array()))
        (void)layer_channel_count(l.get<std::string>(), r);
    } catch (const InputError& e) {
      fuzz::check_error_line(e.line(), file);
    }
  }
  return 0;
}
