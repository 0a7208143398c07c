// libFuzzer harness: two report.json documents through what `hfbake compare` does with them: the bounded
// JSON parser, then the comparison (job identity, parameter changes, metric by metric) and both of its
// renderings (the table and --json). The input is the new report, a line "@@", then the baseline (without
// the separator, a report compared with itself). Not a report is std::invalid_argument (compare's one-line
// error); anything else (an uncaught exception, a crash, UB) is a finding.
#include <cstdint>
#include <stdexcept>
#include <string>

#include "core/error.hpp"
#include "fuzz_support.hpp"
#include "job/manifest.hpp"
#include "report/baseline_compare.hpp"

using namespace hfbake;

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  const auto sep = text.find("\n@@\n");
  const std::string now_text = text.substr(0, sep);
  const std::string old_text = sep == std::string::npos ? now_text : text.substr(sep + 4);
  nlohmann::json now, old;
  try {
    now = parse_json_text(now_text, "new/report.json");
    old = parse_json_text(old_text, "baseline/report.json");
  } catch (const InputError& e) {
    if (e.line().find('\n') != std::string::npos) fuzz::finding("a multi-line error: " + e.line());
    return 0;
  }
  try {
    BaselineOptions options = BaselineOptions::defaults();
    (void)parse_tolerance("max=0.1,1e-4", options);
    const BaselineComparison c = compare_to_baseline(now, old, options);
    (void)another_job_message(c.job_differences);
    (void)comparison_table(c, true);
    (void)comparison_json(c).dump();
  } catch (const std::invalid_argument& e) {
    const std::string what = e.what();
    if (what.find('\n') != std::string::npos) fuzz::finding("a multi-line error: " + what);
  }
  return 0;
}
