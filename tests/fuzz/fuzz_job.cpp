// libFuzzer harness: a job file's text through everything `hfbake validate` does before it looks at the
// inputs' bytes: the bounded JSON parser (depth, duplicate keys, number ranges), parameter sweeps, the job
// schema and each method's schema, and the checks the schema cannot express. A bad job must be a one-line
// error naming the file; anything else (a crash, an uncaught exception, UB, a leak, a multi-line message) is
// a finding. (The methods' parameter readers are not linked here: building every method with the fuzzer's
// instrumentation would multiply the CI build; tests/methods/test_method_table.cpp walks their rules.)
#include <cstdint>
#include <string>

#include "core/error.hpp"
#include "fuzz_support.hpp"
#include "job/manifest.hpp"

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
  if (load.job) (void)job_input_files(load.job->doc);
  return 0;
}
