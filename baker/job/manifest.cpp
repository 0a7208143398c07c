#include "job/manifest.hpp"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <fstream>
#include <map>
#include <set>
#include <sstream>

#include "core/error.hpp"
#include "job/embedded_schemas.hpp"
#include "job/parameter_sweep.hpp"
#include "job/schema_validation.hpp"

namespace hfbake {
namespace fs = std::filesystem;

namespace {

std::string line_column(const std::string& text, std::size_t byte) {
  std::size_t line = 1, column = 1;
  for (std::size_t i = 0; i < text.size() && i + 1 < byte; ++i) {
    if (text[i] == '\n') {
      ++line;
      column = 1;
    } else {
      ++column;
    }
  }
  return "line " + std::to_string(line) + ", column " + std::to_string(column);
}

// The common hand-written mistake behind a parse error at `byte` (nlohmann's position: 1-based, the byte
// it stopped at), as a hint; "" when none is recognised: a comment (JSON has none) or a comma after the last
// item of an object or array.
std::string json_mistake(const std::string& text, std::size_t byte) {
  const std::size_t at = std::min(byte > 0 ? byte - 1 : 0, text.size());
  const std::size_t from = at >= 2 ? at - 2 : 0;
  const std::string near = text.substr(from, 4);
  if (near.find("//") != std::string::npos || near.find("/*") != std::string::npos)
    return " (a comment: job files are JSON, which has none)";
  if (at < text.size() && (text[at] == '}' || text[at] == ']')) {
    std::size_t k = at;
    while (k > 0 && std::isspace(static_cast<unsigned char>(text[k - 1]))) --k;
    if (k > 0 && text[k - 1] == ',')
      return std::string(" (a comma after the last item: JSON takes none before ") + text[at] + ")";
  }
  if (text.find('\\') != std::string::npos && near.find('\\') != std::string::npos)
    return " (a backslash: in JSON it starts an escape; write paths with /)";
  return "";
}

// JSON pointers in document order: token by token, array indices as numbers.
bool pointer_less(const std::string& a, const std::string& b) {
  std::size_t i = 0, j = 0;
  while (i < a.size() && j < b.size()) {
    const std::size_t ie = std::min(a.find('/', i + 1), a.size()),
                      je = std::min(b.find('/', j + 1), b.size());
    const std::string ta = a.substr(i, ie - i), tb = b.substr(j, je - j);
    if (ta != tb) {
      const bool na = ta.size() > 1 && std::all_of(ta.begin() + 1, ta.end(), ::isdigit);
      const bool nb = tb.size() > 1 && std::all_of(tb.begin() + 1, tb.end(), ::isdigit);
      if (na && nb) return std::stoull(ta.substr(1)) < std::stoull(tb.substr(1));
      return ta < tb;
    }
    i = ie, j = je;
  }
  return a.size() - i < b.size() - j;
}

}  // namespace

std::vector<std::string> method_schema_names() {
  std::vector<std::string> names;
  const std::string prefix = "methods/", suffix = ".schema.json";
  for (const EmbeddedSchema& s : embedded_schemas()) {
    const std::string path(s.path);
    if (path.rfind(prefix, 0) != 0 || path.size() <= prefix.size() + suffix.size()) continue;
    const std::string name = path.substr(prefix.size(), path.size() - prefix.size() - suffix.size());
    if (name.find('/') == std::string::npos && name.find('_') == std::string::npos) names.push_back(name);
  }
  std::sort(names.begin(), names.end());
  return names;
}

std::vector<std::pair<std::string, std::string>> job_input_files(const nlohmann::json& doc) {
  std::vector<std::pair<std::string, std::string>> files;
  auto add = [&](const std::string& ptr) {
    const nlohmann::json::json_pointer p(ptr);
    if (doc.contains(p) && doc.at(p).is_string()) files.emplace_back(ptr, doc.at(p).get<std::string>());
  };
  add("/height/image");
  add("/surface/albedo/image");
  add("/surface/emission/image");
  add("/environment/cross");
  add("/environment/latlong");
  if (doc.contains("environment") && doc["environment"].contains("cubemap"))
    for (std::size_t i = 0; i < doc["environment"]["cubemap"].size(); ++i)
      add("/environment/cubemap/" + std::to_string(i));
  return files;
}

std::string nul_in_path(const std::string& path) {
  if (path.find('\0') == std::string::npos) return "";
  return "\"" + path + "\" holds a NUL character (\\u0000), which no path can hold";
}

nlohmann::json parse_json_text(const std::string& text, const std::string& file, const JsonBounds& bounds) {
  // Nesting first: a deep document would exhaust the stack of whatever walks it (the parser's callers,
  // the schema validator, the destructor).
  {
    int depth = 0;
    bool in_string = false, escape = false;
    for (std::size_t i = 0; i < text.size(); ++i) {
      const char c = text[i];
      if (in_string) {
        if (escape)
          escape = false;
        else if (c == '\\')
          escape = true;
        else if (c == '"')
          in_string = false;
      } else if (c == '"') {
        in_string = true;
      } else if (c == '[' || c == '{') {
        if (++depth > bounds.depth)
          throw InputError(file, line_column(text, i + 1),
                           "nested deeper than " + std::to_string(bounds.depth) + " levels");
      } else if (c == ']' || c == '}') {
        --depth;
      }
    }
  }
  // Duplicate keys: nlohmann keeps the last silently; a typo that repeats a key must not be ignored.
  struct Frame {
    bool array = false;
    long index = -1;  // arrays: the element being read
    std::string key;  // objects: the key being read
    std::set<std::string> keys;
  };
  std::vector<Frame> frames;
  std::string duplicate;
  auto pointer = [&](std::size_t upto) {
    std::string p;
    for (std::size_t k = 0; k < upto; ++k) {
      p.push_back('/');
      p.append(frames[k].array ? std::to_string(frames[k].index) : frames[k].key);
    }
    return p;
  };
  auto element = [&] {
    if (!frames.empty() && frames.back().array && std::size_t(++frames.back().index) >= bounds.array_items)
      throw InputError(file, pointer(frames.size() - 1),
                       "an array of more than " + std::to_string(bounds.array_items) +
                           " items; hfbake's JSON files hold at most " + std::to_string(bounds.array_items));
  };
  auto bounded_string = [&](const std::string& s, const std::string& where) {
    if (s.size() > bounds.string_bytes)
      throw InputError(file, where,
                       "a string of " + std::to_string(s.size()) +
                           " bytes; hfbake's JSON files hold at most " + std::to_string(bounds.string_bytes));
  };
  using Event = nlohmann::json::parse_event_t;
  const nlohmann::json::parser_callback_t callback = [&](int, Event event, nlohmann::json& parsed) {
    switch (event) {
      case Event::object_start:
        element();
        frames.push_back({});
        break;
      case Event::array_start:
        element();
        frames.push_back({true, -1, "", {}});
        break;
      case Event::object_end:
      case Event::array_end:
        if (!frames.empty()) frames.pop_back();
        break;
      case Event::key:
        if (!frames.empty()) {
          Frame& f = frames.back();
          f.key = parsed.get<std::string>();
          bounded_string(f.key, pointer(frames.size() - 1));
          if (!f.keys.insert(f.key).second && duplicate.empty())
            duplicate = pointer(frames.size() - 1) + "/" + f.key;
        }
        break;
      case Event::value:
        element();
        if (parsed.is_string()) bounded_string(parsed.get_ref<const std::string&>(), pointer(frames.size()));
        break;
    }
    return true;
  };
  nlohmann::json doc;
  try {
    doc = nlohmann::json::parse(text, callback);
  } catch (const nlohmann::json::parse_error& e) {
    std::string what = e.what();
    // nlohmann: "[json.exception.parse_error.101] parse error at line 3, column 5: syntax error while ..."
    const auto colon = what.find(": ");
    if (colon != std::string::npos) what = what.substr(colon + 2);
    throw InputError(file, line_column(text, e.byte), "malformed JSON: " + what + json_mistake(text, e.byte));
  } catch (const nlohmann::json::exception& e) {
    // out_of_range: a number beyond double's range ("1e309").
    std::string what = e.what();
    const auto bracket = what.find("] ");
    if (bracket != std::string::npos) what = what.substr(bracket + 2);
    throw InputError(file, "", "malformed JSON: " + what);
  }
  if (!duplicate.empty())
    throw InputError(file, duplicate, "duplicate key (the last value would silently replace the first)");
  return doc;
}

nlohmann::json read_json_file(const fs::path& file) {
  const std::string name = file.string();
  std::error_code ec;
  const fs::file_status st = fs::status(file, ec);
  if (ec) throw InputError(name, "", ec.message());
  if (!fs::is_regular_file(st)) throw InputError(name, "", "not a regular file");
  const std::uintmax_t size = fs::file_size(file, ec);
  if (ec) throw InputError(name, "", ec.message());
  if (size > kMaxJsonFileBytes)
    throw InputError(name, "",
                     "the file is " + std::to_string(size) +
                         " bytes; a JSON file of hfbake's may be at most " +
                         std::to_string(kMaxJsonFileBytes));
  std::ifstream in(file, std::ios::binary);
  if (!in) throw InputError(name, "", std::error_code(errno, std::generic_category()).message());
  std::string text(std::size_t(size), '\0');
  in.read(text.data(), std::streamsize(size));
  text.resize(std::size_t(in.gcount()));
  return parse_json_text(text, name);
}

JobLoad load_job(const fs::path& file, const std::optional<fs::path>& out_override,
                 const std::string& out_key) {
  JobLoad result;
  try {
    return load_job_document(read_json_file(file), file, out_override, out_key);
  } catch (const InputError& e) {
    result.errors.push_back(e.line());
  } catch (const std::bad_alloc&) {
    result.errors.push_back(printable(file.string() + ": not enough memory to read the job"));
  } catch (const std::exception& e) {
    result.errors.push_back(printable(file.string() + ": cannot read the job: " + e.what()));
  }
  return result;
}

JobLoad load_job_document(nlohmann::json doc, const fs::path& file,
                          const std::optional<fs::path>& out_override, const std::string& out_key) {
  JobLoad result;
  const std::string fname = file.string();
  auto fail = [&](const std::string& where, const std::string& what) {
    result.errors.push_back(printable(fname + ": " + (where.empty() ? "" : where + ": ") + what));
  };

  // A numeric parameter given as a list expands into one bake entry per value (a sweep).
  SweepExpansion sweep = expand_parameter_sweeps(doc);
  for (const std::string& e : sweep.errors) result.errors.push_back(printable(fname + ": " + e));
  if (sweep.too_many) return result;
  doc = std::move(sweep.doc);
  // The document against job.schema.json, and each bake entry against its method's own schema
  // (schemas/methods/<method>.schema.json: adding a method adds a schema file, not a line here or in
  // job.schema.json); all violations in document order.
  std::vector<SchemaViolation> violations = validate_against_schema(doc, "job.schema.json");
  const std::vector<std::string> methods = method_schema_names();
  for (std::size_t i = 0; doc.contains("bake") && doc["bake"].is_array() && i < doc["bake"].size(); ++i) {
    const nlohmann::json& entry = doc["bake"][i];
    if (!entry.is_object() || !entry.contains("method") || !entry["method"].is_string()) continue;
    if (std::find(sweep.refused.begin(), sweep.refused.end(), i) != sweep.refused.end()) continue;
    const std::string method = entry["method"].get<std::string>();
    const std::string at = "/bake/" + std::to_string(i);
    if (std::find(methods.begin(), methods.end(), method) == methods.end()) {
      std::string list;
      for (std::size_t k = 0; k < methods.size(); ++k) list += (k ? ", \"" : "\"") + methods[k] + "\"";
      violations.push_back({at + "/method", "unknown method \"" + method + "\" (one of " + list + ")"});
      continue;
    }
    for (SchemaViolation& v : validate_against_schema(entry, "methods/" + method + ".schema.json"))
      violations.push_back({at + v.pointer, std::move(v.message)});
  }
  std::stable_sort(
      violations.begin(), violations.end(),
      [](const SchemaViolation& a, const SchemaViolation& b) { return pointer_less(a.pointer, b.pointer); });
  for (const SchemaViolation& v : violations)
    fail(v.pointer.empty() ? "/" : original_pointer(v.pointer, sweep.origins), v.message);
  if (!result.errors.empty()) return result;

  Job job;
  job.file = file;
  job.base_dir = fs::absolute(file).parent_path();
  job.doc = doc;
  job.name = doc["name"].get<std::string>();

  // Checks the schema cannot express.
  if (doc.contains("environment")) {
    int kinds = 0;
    for (const char* k : {"uniform", "cubemap", "cross", "latlong", "sky"})
      kinds += doc["environment"].contains(k);
    if (kinds != 1)
      fail("/environment", "needs exactly one of uniform, cubemap, cross, latlong, sky (found " +
                               std::to_string(kinds) + ")");
    // A colour space is the images': given with a uniform or built-in sky it would say nothing.
    const nlohmann::json& env = doc["environment"];
    if (kinds == 1 && env.contains("colorspace") && !env.contains("latlong") && !env.contains("cubemap") &&
        !env.contains("cross"))
      fail("/environment/colorspace",
           "applies to an environment image (latlong, cubemap, cross), not to " +
               std::string(env.contains("uniform") ? "uniform" : "the built-in sky"));
  }
  if (doc.contains("lights")) {
    for (std::size_t i = 0; i < doc["lights"].size(); ++i) {
      const auto& d = doc["lights"][i]["directional"]["direction"];
      if (!(std::hypot(d[0].get<double>(), d[1].get<double>(), d[2].get<double>()) >= 1e-6))
        fail("/lights/" + std::to_string(i) + "/directional/direction",
             "must have a length of at least 1e-6 (it is normalised; a shorter one has no direction)");
    }
  }
  // Every path the job names, with the reason when it holds a NUL (nul_in_path).
  std::vector<std::pair<std::string, std::string>> paths = job_input_files(doc);
  for (const char* ptr : {"/report/baseline", "/output/dir"})
    if ((!out_override || std::string_view(ptr) != "/output/dir") &&
        doc.contains(nlohmann::json::json_pointer(ptr)) &&
        doc.at(nlohmann::json::json_pointer(ptr)).is_string())
      paths.emplace_back(ptr, doc.at(nlohmann::json::json_pointer(ptr)).get<std::string>());
  for (const auto& [ptr, path] : paths)
    if (const std::string why = nul_in_path(path); !why.empty()) fail(ptr, why);
  if (!result.errors.empty()) return result;
  for (const auto& [ptr, rel] : job_input_files(doc)) {
    const fs::path p = job.resolve(rel);
    std::error_code ec;
    if (fs::is_regular_file(p, ec)) continue;
    if (fs::is_directory(p, ec))
      fail(ptr, p.string() + " is a folder, not a file");
    else if (fs::exists(p, ec))
      fail(ptr, p.string() + " is not a regular file (a device, a pipe or a socket)");
    else if (fs::is_symlink(fs::symlink_status(p, ec))) {
      std::error_code why;
      (void)fs::status(p, why);
      fail(ptr, p.string() + (why == std::errc::too_many_symbolic_link_levels
                                  ? " is a link that leads back to itself (a loop)"
                                  : " is a link to nothing"));
    } else
      fail(ptr,
           "no such file: " + p.string() +
               (rel.find('\\') != std::string::npos ? " (a backslash: hfbake's paths take / between folders)"
                                                    : ""));
  }
  // The baseline is read after the bake; a missing one must not cost the bake. (Not an input of the
  // content hash: the baseline changes what is compared, not what is baked.)
  if (doc.contains("report") && doc["report"].contains("baseline")) {
    const fs::path p = job.resolve(doc["report"]["baseline"].get<std::string>());
    std::error_code ec;
    if (!fs::is_regular_file(p, ec))
      fail("/report/baseline",
           "no such file: " + p.string() +
               " (to make the first one, bake without report.baseline, then: hfbake compare OUT_DIR " +
               p.string() + " --update-baseline)");
  }

  const auto& bake = doc["bake"];
  std::map<std::string, int> count;  // entries per method in the file (a sweep counts once)
  for (std::size_t i = 0; i < bake.size(); ++i)
    if (i == 0 || sweep.origins[i].entry != sweep.origins[i - 1].entry)
      ++count[bake[i]["method"].get<std::string>()];
  for (std::size_t i = 0; i < bake.size(); ++i) {
    const SweepOrigin& origin = sweep.origins[i];
    BakeEntry entry;
    entry.method = bake[i]["method"].get<std::string>();
    entry.stem = count[entry.method] > 1 ? entry.method + "-" + std::to_string(origin.entry) : entry.method;
    entry.pointer = "/bake/" + std::to_string(origin.entry);
    entry.params = bake[i];
    if (!origin.parameter.empty()) {
      entry.stem += "-" + sweep_stem_suffix(origin.parameter, origin.value);
      entry.sweep_parameter = origin.parameter;
      entry.sweep_value = origin.value;
      entry.sweep_group = int(origin.entry);
    }
    job.bakes.push_back(std::move(entry));
  }
  job.has_reference = doc.contains("reference");
  if (job.bakes.empty() && !job.has_reference) fail("/bake", "nothing to bake: no method and no reference");

  const nlohmann::json output = doc.value("output", nlohmann::json::object());
  if (out_override) {
    job.output.dir = fs::absolute(*out_override);
    job.output.dir_key = out_key;
  } else if (output.contains("dir"))
    job.output.dir = job.resolve(output["dir"].get<std::string>());
  else
    job.output.dir = job.base_dir / "out" / job.name;
  job.output.dir = job.output.dir.lexically_normal();
  // The reports (report.json, a summary, a suite's) name the job file and its output folder in JSON, whose
  // text is UTF-8: a path in another encoding is refused here, before anything is baked.
  if (const fs::path abs = fs::absolute(file); !is_utf8(abs.string()))
    fail("",
         "the job file's path " + abs.string() +
             " is not UTF-8 text: the reports, written in JSON, cannot name it; rename its folder or file");
  else if (!is_utf8(job.output.dir.string()))
    fail(job.output.dir_key, "the output folder " + job.output.dir.string() +
                                 " is not UTF-8 text: the reports, written in JSON, cannot name it");
  job.output.float_pixels = output.value("pixel_type", "half") == "float";
  job.output.compression = output.value("compression", "");  // "": by the file's layers
  job.output.previews = output.value("previews", false);
  job.output.geotiff = output.value("geotiff", false);
  job.output.preview_display = output.value("preview_display", "");
  job.output.preview_view = output.value("preview_view", "");

  if (result.errors.empty()) result.job = std::move(job);
  return result;
}

}  // namespace hfbake
