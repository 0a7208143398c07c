// Parameter sweeps in a job: a bake entry whose numeric parameter is given as a list, e.g.
//   {"method": "p1", "directions": [16, 32, 64, 128]}
// expands into one run per value (stems p1-directions16, p1-directions32, ...). The runs share the
// job's one reference, and report.html plots each error metric against the swept parameter.
//
// A list expands only where the method's schema (schemas/methods/<method>.schema.json) declares the
// property "integer" or "number": a property that is itself an array (e.g. "layers") never expands.
// One swept parameter per bake entry; each value is then checked by the method's schema as usual.
#pragma once

#include <cstddef>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

namespace hfbake {

// Where an expanded bake entry came from.
struct SweepOrigin {
  std::size_t entry = 0;        // index of the entry in the job file's "bake" array
  std::string parameter;        // the swept property ("" when the entry is not a sweep)
  std::size_t value_index = 0;  // index of the value in the list
  nlohmann::json value;         // the value of this run
};

// The bake entries of a job once its sweeps are expanded (job.schema.json "bake" maxItems): counted before
// anything is expanded, so a small file cannot ask for unbounded work.
inline constexpr std::size_t kMaxBakeEntries = 256;

struct SweepExpansion {
  nlohmann::json doc;                // the job with every sweep expanded (unchanged when there is none)
  std::vector<SweepOrigin> origins;  // one per bake entry of `doc`
  std::vector<std::string> errors;   // "<JSON pointer>: <what is wrong>", pointers into the original file
  bool too_many = false;             // beyond kMaxBakeEntries: nothing expanded, `errors` says where
  // Entries of `doc` left as written because their sweep is refused (`errors` says why): their lists are
  // not checked against the method's schema as well.
  std::vector<std::size_t> refused;
};

// Expands every sweep of doc["bake"]. Documents that are not jobs pass through unchanged (the schema
// reports what is wrong with them).
SweepExpansion expand_parameter_sweeps(const nlohmann::json& doc);

// Maps a JSON pointer into the expanded document back onto the file the user wrote:
// "/bake/3/directions" -> "/bake/1/directions/2" when entry 3 is the third value of entry 1's sweep.
std::string original_pointer(const std::string& pointer, const std::vector<SweepOrigin>& origins);

// The output stem suffix of a run: "directions16", "radius0.5".
std::string sweep_stem_suffix(const std::string& parameter, const nlohmann::json& value);

}  // namespace hfbake
