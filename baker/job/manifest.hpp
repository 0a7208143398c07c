// A job file: parsed, validated against schemas/job.schema.json, with paths resolved and defaults applied.
#pragma once

#include <filesystem>
#include <memory>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

namespace hfbake {

struct MethodConfig;      // methods/method_table.hpp
struct ReferenceOptions;  // reference/bake_reference.hpp

struct BakeEntry {
  std::string method;     // "p1", "lsao", ...
  std::string stem;       // output stem: "p1", or "p1-2" when the method appears more than once
  std::string pointer;    // "/bake/<i>", for error messages
  nlohmann::json params;  // the bake[i] object as written (schema-validated)
  // The entry's parameters read once by its method's reader (cli/method_dispatch.hpp resolve_job), what
  // every step of the bake hands the method; null before.
  std::shared_ptr<const MethodConfig> config;
  // Parameter sweeps (job/parameter_sweep.hpp): "directions": [16, 32] is two entries sharing sweep_group
  // (the index of the entry in the file), sweep_parameter "directions" and sweep_value 16, then 32.
  std::string sweep_parameter;  // "" when the entry is not part of a sweep
  nlohmann::json sweep_value;
  int sweep_group = -1;
};

struct OutputOptions {
  std::filesystem::path dir;  // absolute
  // Where dir was given, for messages about it: the job's key, or the command line's --out.
  std::string dir_key = "/output/dir";
  bool float_pixels = false;  // half by default
  std::string compression;    // EXR compression; empty: default_exr_compression of each file's layers
  bool previews = false;
  bool geotiff = false;  // also <name>.<stem>.<layer>.tif: float32 Cloud-Optimised GeoTIFFs
  std::string preview_display, preview_view;  // empty: the OCIO config's defaults
};

struct Job {
  std::filesystem::path file;      // as given (used in messages)
  std::filesystem::path base_dir;  // absolute folder of the job file: relative paths resolve against it
  nlohmann::json doc;              // the whole document
  std::string name;
  std::vector<BakeEntry> bakes;
  bool has_reference = false;
  // The reference's options read once (resolve_job), with every default filled in; null before, or
  // without a reference.
  std::shared_ptr<const ReferenceOptions> reference_options;
  OutputOptions output;

  std::filesystem::path resolve(const std::string& relative) const { return base_dir / relative; }
  std::filesystem::path output_path(const std::string& stem, const std::string& ext) const {
    return output.dir / (name + "." + stem + ext);
  }
};

// The outcome of loading a job: the job, or every problem found, each as one line
// "<file>: <JSON pointer>: <what is wrong>".
struct JobLoad {
  std::optional<Job> job;
  std::vector<std::string> errors;
};

// Reads, parses and validates `file` (schema + checks the schema cannot express, e.g. that input files
// exist). `out_override` replaces output.dir (--out DIR; the job's name is appended when several jobs
// share one --out so they cannot overwrite each other: see the CLI).
// out_key: what gave out_override, as messages about the output folder name it ("--out").
JobLoad load_job(const std::filesystem::path& file, const std::optional<std::filesystem::path>& out_override,
                 const std::string& out_key = "--out");
// The same for a parsed document (`file` names it in messages and is where relative paths resolve).
JobLoad load_job_document(nlohmann::json doc, const std::filesystem::path& file,
                          const std::optional<std::filesystem::path>& out_override,
                          const std::string& out_key = "--out");

// The methods that have a schema, schemas/methods/<name>.schema.json (files with "_" in the name, such as
// obscurance_common, hold shared definitions), sorted. The method table must list the same names.
std::vector<std::string> method_schema_names();

// Every input file a job document names, as (JSON pointer, path as written).
std::vector<std::pair<std::string, std::string>> job_input_files(const nlohmann::json& doc);

// Limits of every JSON file hfbake reads (jobs, suites, reports): a bad or hostile file is an error, never a
// crash, a hang or an absurd allocation.
inline constexpr int kMaxJsonDepth = 64;
inline constexpr std::uintmax_t kMaxJsonFileBytes = 16u << 20;
// Every string (value or key) and every array of such a file: a schema's "pattern" is matched by a
// recursive std::regex whose stack grows with the string, and work grows with the items.
inline constexpr std::size_t kMaxJsonStringBytes = 4096;
inline constexpr std::size_t kMaxJsonArrayItems = 4096;

// What parse_json_text bounds besides the text's own size: nesting, each string's bytes, each array's items.
// The defaults are those of the JSON files people write (jobs, suites, reports).
struct JsonBounds {
  int depth = kMaxJsonDepth;
  std::size_t string_bytes = kMaxJsonStringBytes;
  std::size_t array_items = kMaxJsonArrayItems;
};

// Parses JSON text, the one parser of every JSON document hfbake reads (jobs, suites, reports, the farm's
// shard headers); errors (InputError naming `file`) as "line L, column C: <what>": malformed text, numbers
// beyond double's range, nesting deeper than `bounds.depth`; as the JSON pointer: a key given twice in one
// object (never resolved silently), a string longer than `bounds.string_bytes`, an array longer than
// `bounds.array_items`.
nlohmann::json parse_json_text(const std::string& text, const std::string& file,
                               const JsonBounds& bounds = {});

// A path from a JSON file goes to the system as a C string, which ends at a NUL, so one that holds a NUL
// would name another file (its part before the NUL): the reason such a path is refused, "" for any other.
std::string nul_in_path(const std::string& path);

// Reads and parses a JSON file: a regular file (not a FIFO, device or folder) of at most kMaxJsonFileBytes.
nlohmann::json read_json_file(const std::filesystem::path& file);

}  // namespace hfbake
