// The Python module hfbake._hfbake: numpy heights in, numpy layers out, through the same job loader,
// method-table readers, memory estimate and scene checks as `hfbake bake`. The package hfbake
// (python/hfbake/__init__.py) wraps it in one function per method and defines the exceptions it raises.
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>
#include <tbb/task_arena.h>

#include <atomic>
#include <chrono>
#include <cmath>
#include <condition_variable>
#include <cstring>
#include <exception>
#include <filesystem>
#include <limits>
#include <map>
#include <mutex>
#include <new>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "cli/bake_command.hpp"
#include "cli/compare_command.hpp"
#include "cli/method_dispatch.hpp"
#include "cli/outputs.hpp"
#include "cli/reference_cache.hpp"
#include "cli/scene_inputs.hpp"
#include "cli/scene_loader.hpp"
#include "cli/version.hpp"
#include "core/error.hpp"
#include "core/safe_file.hpp"
#include "field/georeference.hpp"
#include "io/crs_geodesy.hpp"
#include "io/georaster_input.hpp"
#include "job/embedded_schemas.hpp"
#include "job/manifest.hpp"
#include "methods/method_table.hpp"

namespace py = pybind11;
namespace fs = std::filesystem;
using nlohmann::json;

namespace hfbake {
namespace {

// One problem of an input, as the CLI prints it: "<file>: <pointer>: <message>".
struct Problem {
  std::string file, pointer, message;
};

// Splits a line of JobLoad::errors or resolve_job ("<file>: <pointer>: <message>", `file` known).
Problem split_line(const std::string& line, const std::string& file) {
  Problem p;
  std::string rest = line;
  if (!file.empty() && rest.rfind(file + ": ", 0) == 0) {
    p.file = file;
    rest = rest.substr(file.size() + 2);
  }
  const std::size_t colon = rest.find(": ");
  if (!rest.empty() && rest[0] == '/' && colon != std::string::npos) {
    p.pointer = rest.substr(0, colon);
    p.message = rest.substr(colon + 2);
  } else {
    p.message = rest;
  }
  return p;
}

// The pointers of the job the array API builds, as the caller named them: its keyword arguments
// (/bake/0/<key> and /height/<key> are /<key>), the array itself (/height/image is /heights).
std::string array_pointer(const std::string& pointer) {
  for (const char* prefix : {"/bake/0", "/height"})
    if (pointer.rfind(prefix, 0) == 0) {
      const std::string rest = pointer.substr(std::strlen(prefix));
      if (rest.empty() || rest == "/image" || rest == "/procedural" || rest.rfind("/procedural/", 0) == 0)
        return std::string(prefix) == "/height" ? "/heights" : rest;
      return rest;
    }
  return pointer;
}

// Sets hfbake.InputError (a ValueError) as the Python error for `problems` (the first one is the exception's
// own; every line is in its `lines`).
void set_input_error(const std::vector<Problem>& problems) {
  const py::object type = py::module_::import("hfbake").attr("InputError");
  py::list lines;
  for (const Problem& p : problems) lines.append(InputError(p.file, p.pointer, p.message).line());
  const Problem& first = problems.front();
  const py::object error = type(first.message, first.pointer, first.file, lines);
  PyErr_SetObject(type.ptr(), error.ptr());
}

[[noreturn]] void raise_input_error(const std::vector<Problem>& problems) {
  set_input_error(problems);
  throw py::error_already_set();
}

[[noreturn]] void raise_lines(const std::vector<std::string>& lines, const std::string& file,
                              bool array_api) {
  std::vector<Problem> problems;
  for (const std::string& l : lines) {
    Problem p = split_line(l, file);
    if (array_api) p.file.clear(), p.pointer = array_pointer(p.pointer);
    problems.push_back(std::move(p));
  }
  raise_input_error(problems);
}

// Python text as UTF-8: a str holding a lone surrogate (from a file name decoded with surrogateescape)
// has none.
std::string utf8_of(py::handle text, const std::string& pointer) {
  try {
    return py::str(text).cast<std::string>();
  } catch (const std::exception&) {
    PyErr_Clear();
    throw InputError("", pointer, "is not UTF-8 text (a lone surrogate: bytes of another encoding?)");
  }
}

// A keyword argument's value as JSON (what a job file would hold); numpy scalars by their item(), numpy
// arrays as lists. Nested at most as deep as a job file may be (kMaxJsonDepth): a dict or list that holds
// itself is refused, not followed until the stack overflows.
json to_json(py::handle value, const std::string& pointer, int depth = 0) {
  if (depth > kMaxJsonDepth)
    throw InputError("", pointer,
                     "nested deeper than " + std::to_string(kMaxJsonDepth) +
                         " levels (a dict or list that holds itself?)");
  if (value.is_none()) return nullptr;
  if (py::isinstance<py::bool_>(value)) return value.cast<bool>();
  if (py::isinstance<py::int_>(value)) {
    try {
      return value.cast<long long>();
    } catch (const py::cast_error&) {
      PyErr_Clear();
    }
    // Beyond 64 bits: as a double (as a job file's number), or refused beyond double's range.
    const double x = PyLong_AsDouble(value.ptr());
    if (x == -1.0 && PyErr_Occurred()) {
      PyErr_Clear();
      throw InputError("", pointer, "is an integer beyond double's range (a job holds numbers within it)");
    }
    return x;
  }
  if (py::isinstance<py::float_>(value)) {
    // A job file cannot hold NaN or an infinity (JSON has none), and the schema's ranges cannot refuse
    // them (every comparison with NaN is false): refused here, as the file's parser would.
    const double x = value.cast<double>();
    if (!std::isfinite(x))
      throw InputError("", pointer,
                       "must be a finite number (it is " + py::str(value).cast<std::string>() + ")");
    return x;
  }
  if (py::isinstance<py::str>(value)) return utf8_of(value, pointer);
  if (py::isinstance(value, py::module_::import("os").attr("PathLike")))
    return utf8_of(py::module_::import("os").attr("fspath")(value), pointer);
  if (py::isinstance<py::dict>(value)) {
    json out = json::object();
    for (auto [k, v] : value.cast<py::dict>()) {
      const std::string key = utf8_of(k, pointer + "/(a key)");
      out[key] = to_json(v, pointer + "/" + key, depth + 1);
    }
    return out;
  }
  if (py::isinstance<py::list>(value) || py::isinstance<py::tuple>(value)) {
    json out = json::array();
    std::size_t k = 0;
    for (py::handle v : value) out.push_back(to_json(v, pointer + "/" + std::to_string(k++), depth + 1));
    return out;
  }
  if (py::isinstance(value, py::module_::import("numpy").attr("generic")))
    return to_json(value.attr("item")(), pointer, depth);
  if (py::isinstance<py::array>(value)) return to_json(value.attr("tolist")(), pointer, depth);
  throw InputError("", pointer,
                   "a " + py::str(py::type::handle_of(value).attr("__name__")).cast<std::string>() +
                       " is not a value a job holds (a number, string, bool, list or dict)");
}

// A layer as numpy: one channel (H, W); per-direction channels "000".."K-1" (horizon, horizon_distance,
// horizon_deg) (K, H, W); others (rgb, xyz, sh) (H, W, C). One- and C-channel layers hand their storage over.
py::array layer_array(Layer&& layer, int width, int height) {
  const py::ssize_t w = width, h = height, c = layer.channel_count();
  const bool per_direction = c > 1 && layer.channels.front() == "000";
  if (!per_direction) {
    auto* data = new std::vector<float>(std::move(layer.data));
    py::capsule owner(data, [](void* p) { delete static_cast<std::vector<float>*>(p); });
    if (c == 1) return py::array_t<float>({h, w}, data->data(), owner);
    return py::array_t<float>({h, w, c}, data->data(), owner);
  }
  py::array_t<float> out({c, h, w});
  float* dst = out.mutable_data();
  const float* src = layer.data.data();
  const std::size_t texels = std::size_t(w) * std::size_t(h);
  for (std::size_t t = 0; t < texels; ++t)
    for (py::ssize_t k = 0; k < c; ++k)
      dst[std::size_t(k) * texels + t] = src[t * std::size_t(c) + std::size_t(k)];
  return out;
}

py::dict layers_dict(LayerSet&& set) {
  py::dict out;
  for (Layer& l : set.layers) {
    const std::string name = l.name;
    out[py::str(name)] = layer_array(std::move(l), set.width, set.height);
  }
  return out;
}

// How a bake runs under Python: `work` on a thread of its own with the GIL released, in a TBB arena of
// `threads` (0: all cores); the calling thread wakes every 50 ms to deliver the progress fraction to
// `progress` (on the calling thread, when it changed), to poll `cancel.is_set()` and Python's signal
// handlers. Ctrl-C (or an exception from `progress`) cancels the bake, waits for it to stop and raises that
// exception; a set `cancel` (polled before the bake starts too) raises hfbake.Cancelled. Nothing the bake
// made is kept then.
struct Runner {
  int threads = 0;
  py::object progress = py::none(), cancel = py::none();
  std::atomic<bool> cancelled{false};
  std::atomic<double> fraction{-1.0};

  RunControl control() {
    RunControl rc;
    rc.cancel = &cancelled;
    rc.progress = [this](double f) { fraction.store(f, std::memory_order_relaxed); };
    return rc;
  }

  template <class Work>
  void run(Work&& work) {
    // A `cancel` set before the bake starts stops it as one set during it does (a small field may bake
    // between two polls).
    if (!cancel.is_none() && cancel.attr("is_set")().cast<bool>()) throw Cancelled();
    std::mutex mutex;
    std::condition_variable cv;
    bool done = false;
    std::exception_ptr error;
    std::thread worker([&] {
      try {
        tbb::task_arena arena(threads > 0 ? threads : tbb::task_arena::automatic);
        arena.execute([&] { work(); });
      } catch (...) {
        error = std::current_exception();
      }
      std::lock_guard lock(mutex);
      done = true;
      cv.notify_all();
    });
    bool python_error = false;  // the error indicator holds the exception to raise
    double delivered = -1;
    for (;;) {
      {
        py::gil_scoped_release release;
        std::unique_lock lock(mutex);
        if (cv.wait_for(lock, std::chrono::milliseconds(50), [&] { return done; })) break;
      }
      if (python_error) continue;
      if (PyErr_CheckSignals() != 0) {
        python_error = true;
        cancelled = true;
        continue;
      }
      try {
        if (!cancel.is_none() && cancel.attr("is_set")().cast<bool>()) cancelled = true;
        const double f = fraction.load(std::memory_order_relaxed);
        if (!progress.is_none() && f >= 0 && f != delivered) {
          delivered = f;
          progress(f);
        }
      } catch (py::error_already_set& e) {
        e.restore();
        python_error = true;
        cancelled = true;
      }
    }
    {
      py::gil_scoped_release release;
      worker.join();
    }
    if (python_error) throw py::error_already_set();
    if (error) std::rethrow_exception(error);
    if (!progress.is_none() && delivered != 1.0) progress(1.0);
  }
};

// `threads`: 0 (all cores) or a count.
void check_threads(int threads) {
  if (threads < 0) raise_input_error({{"", "/threads", "must be at least 1 (or None: all cores)"}});
}

// The job document the array API bakes: the placeholder field is a procedural one of the array's size (the
// loader's checks and the memory estimate need a size before the heights; its heights are never made), the
// height keys, the job's keys and one bake entry of the method's keys.
json array_job_document(const std::string& method, int width, int height, const py::dict& entry_keys,
                        const py::dict& height_keys, const py::dict& job_keys) {
  // A side below 2 is refused by complete_scene with the CLI's message; the procedural schema's minimum
  // would name /height/procedural/size instead.
  json doc = {
      {"version", 1},
      {"name", method},
      {"height", {{"procedural", {{"kind", "flat"}, {"size", {std::max(width, 2), std::max(height, 2)}}}}}},
      {"bake", json::array()}};
  for (auto [k, v] : height_keys) {
    const std::string key = py::str(k).cast<std::string>();
    doc["height"][key] = to_json(v, "/" + key);
  }
  for (auto [k, v] : job_keys) {
    const std::string key = py::str(k).cast<std::string>();
    doc[key] = to_json(v, "/" + key);
  }
  json entry = {{"method", method}};
  for (auto [k, v] : entry_keys) {
    const std::string key = py::str(k).cast<std::string>();
    entry[key] = to_json(v, "/" + key);
  }
  doc["bake"].push_back(std::move(entry));
  return doc;
}

// The array functions' bake: (layers, warnings), the warnings heights_warning's lines about the heights
// ("heights: <what>"), for the package to issue as Python warnings.
py::tuple bake_array(const std::string& method, py::object heights_arg, const py::dict& entry_keys,
                     const py::dict& height_keys, const py::dict& job_keys, int threads, py::object progress,
                     py::object cancel, std::optional<std::size_t> memory_limit) {
  if (!find_method(method)) raise_input_error({{"", "/method", "unknown method \"" + method + "\""}});
  if (!py::isinstance<py::array>(heights_arg))
    raise_input_error(
        {{"", "/heights",
          "must be a 2-D array (rows, columns) of heights, a numpy array (numpy.asarray converts a list); it "
          "is a " +
              py::str(py::type::handle_of(heights_arg).attr("__name__")).cast<std::string>()}});
  const py::array heights = heights_arg.cast<py::array>();
  if (heights.ndim() != 2)
    raise_input_error({{"", "/heights",
                        "must be a 2-D array (rows, columns) of heights; it has " +
                            std::to_string(heights.ndim()) + " dimensions"}});
  const py::module_ numpy = py::module_::import("numpy");
  if (!numpy.attr("issubdtype")(heights.dtype(), numpy.attr("number")).cast<bool>() ||
      numpy.attr("issubdtype")(heights.dtype(), numpy.attr("complexfloating")).cast<bool>())
    raise_input_error(
        {{"", "/heights",
          "must hold real numbers (float32 is used as is; other types are converted); it holds " +
              py::str(heights.dtype()).cast<std::string>()}});
  // The sides every method supports, as for a job's height file (cli/scene_loader.hpp).
  if (heights.shape(0) > kMaxFieldSide || heights.shape(1) > kMaxFieldSide)
    raise_input_error({{"", "/heights",
                        "is " + std::to_string(heights.shape(0)) + " x " + std::to_string(heights.shape(1)) +
                            " heights (rows x columns); fields of up to " + std::to_string(kMaxFieldSide) +
                            " texels a side are supported"}});
  const int height = int(heights.shape(0)), width = int(heights.shape(1));

  const std::string file = method + "()";
  JobLoad load = load_job_document(
      array_job_document(method, width, height, entry_keys, height_keys, job_keys), file, std::nullopt);
  if (load.job) load.errors = resolve_job(*load.job);
  if (!load.errors.empty()) raise_lines(load.errors, file, true);
  Job& job = *load.job;
  job.file.clear();  // messages name the keyword arguments, not a file
  try {
    check_job_memory(job, {width, height}, memory_limit, nullptr, "memory_limit");
  } catch (const InputError& e) {  // the limit given is what the caller can change
    raise_input_error({{"", memory_limit ? "/memory_limit" : array_pointer(e.where()), e.what()}});
  }
  // float32 and C-contiguous: read in place; anything else converted once by numpy first, after the memory
  // check (a copy numpy cannot allocate is Python's MemoryError).
  const auto z = py::array_t<float, py::array::c_style | py::array::forcecast>::ensure(heights);
  if (!z) throw std::bad_alloc();

  check_threads(threads);
  Runner runner;
  runner.threads = threads;
  runner.progress = std::move(progress);
  runner.cancel = std::move(cancel);
  LayerSet layers;
  std::string warning;
  std::optional<InputError> input_error;
  runner.run([&] {
    try {
      HeightField field;
      field.width = width;
      field.height = height;
      field.texel_size = job_texel_size(job);
      field.wrap = job.doc["height"].value("wrap", "clamp") == "repeat" ? Wrap::repeat : Wrap::clamp;
      field.z.assign(z.data(), z.data() + std::size_t(width) * std::size_t(height));
      Georeference georeference;
      georeference.geotransform = local_geotransform(field.texel_size);
      HeightSource read_by;
      read_by.nodata_note = apply_height_nodata(job, "heights", field, georeference);
      read_by.reader = "numpy";
      read_by.format = "array";
      read_by.sample_type = "float";
      const Scene scene = complete_scene(job, std::move(field), std::move(georeference), read_by);
      warning = heights_warning(scene);
      layers = run_method(job.bakes.front(), scene, runner.control());
      check_layers_finite(job.bakes.front().stem, layers);  // what bake refuses to write
    } catch (const InputError& e) {
      input_error.emplace(e);
    }
  });
  if (input_error) raise_input_error({{"", array_pointer(input_error->where()), input_error->what()}});
  py::list warnings;
  if (!warning.empty()) warnings.append("heights: " + warning);
  return py::make_tuple(layers_dict(std::move(layers)), warnings);
}

// A job from a path (str or os.PathLike) or a dict (relative paths resolve against the current folder; `name`
// stands for its file in messages), loaded and resolved as `hfbake validate` does. Raises hfbake.InputError
// with every problem.
Job load_resolved_job(py::handle job, const std::optional<std::string>& out) {
  const py::module_ os = py::module_::import("os");
  JobLoad load;
  std::string file;
  const std::optional<fs::path> out_dir = out ? std::optional<fs::path>(*out) : std::nullopt;
  if (py::isinstance<py::dict>(job)) {
    file = "<dict>";
    load = load_job_document(to_json(job, ""), fs::current_path() / file, out_dir);
    file = (fs::current_path() / file).string();
  } else if (py::isinstance<py::str>(job) || py::isinstance(job, os.attr("PathLike"))) {
    file = py::str(os.attr("fspath")(job)).cast<std::string>();
    load = load_job(file, out_dir);
  } else {
    raise_input_error({{"", "/job",
                        "must be a path to a job file or a dict of one; it is a " +
                            py::str(py::type::handle_of(job).attr("__name__")).cast<std::string>()}});
  }
  if (load.job) load.errors = resolve_job(*load.job);
  if (!load.errors.empty()) raise_lines(load.errors, file, false);
  return std::move(*load.job);
}

// validate(job): the checks of `hfbake validate` (schema, every reader, the memory estimate, the scene's
// inputs loaded); returns the size and the estimate.
py::dict validate_job(py::handle job_arg, std::optional<std::size_t> memory_limit) {
  const Job job = load_resolved_job(job_arg, std::nullopt);
  const FieldSize size = probe_field_size(job);
  std::string parts;
  const std::size_t need = check_job_memory(job, size, memory_limit, &parts, "memory_limit");
  HeightsReport heights;
  {
    py::gil_scoped_release release;
    const Scene scene = load_scene(job);
    heights = describe_heights(job, scene);
  }
  py::dict out;
  out["name"] = job.name;
  out["heights"] = heights.line;  // the heights line `hfbake validate` prints
  py::list warnings;              // and its warnings, one line each
  if (!heights.warning.empty()) warnings.append(job.file.string() + ": " + heights.warning);
  out["warnings"] = warnings;
  out["width"] = size.width;
  out["height"] = size.height;
  out["memory_bytes"] = need;
  out["memory_parts"] = parts;
  return out;
}

// bake(job, out): `hfbake bake --out out` of one job; returns (layers by stem, outcome as JSON text).
py::tuple bake_job_api(py::handle job_arg, const std::string& out, int threads, py::object progress,
                       py::object cancel, std::optional<std::size_t> memory_limit, bool use_cache,
                       bool overwrite) {
  const Job job = load_resolved_job(job_arg, out);
  BakeOptions options;
  options.memory_limit = memory_limit;
  options.memory_limit_name = "memory_limit";
  options.overwrite = overwrite;
  options.quiet = true;
  std::optional<ReferenceCache> cache;
  if (use_cache)
    if (const auto dir = default_reference_cache_dir()) cache.emplace(*dir);
  check_threads(threads);
  Runner runner;
  runner.threads = threads;
  runner.progress = std::move(progress);
  runner.cancel = std::move(cancel);
  // Progress: the fraction of the job's steps (the scene, each method, the reference) done.
  const double steps = 1.0 + double(job.bakes.size()) + (job.has_reference ? 1.0 : 0.0);
  std::map<std::string, int> step_index = {{"load", 0}};
  for (std::size_t i = 0; i < job.bakes.size(); ++i) step_index[job.bakes[i].stem] = int(i) + 1;
  step_index["reference"] = int(job.bakes.size()) + 1;
  Progress quiet(Progress::Mode::silent);  // the warnings go to Python, from outcome.warnings
  quiet.set_observer([&](const std::string&, const std::string& step, double f) {
    const auto it = step_index.find(step);
    if (it != step_index.end()) runner.fraction.store((it->second + f) / steps, std::memory_order_relaxed);
  });
  JobOutcome outcome;
  outcome.file = job.file.string();
  outcome.name = job.name;
  std::map<std::string, LayerSet> kept;
  runner.run(
      [&] { bake_job(job, quiet, runner.cancelled, outcome, cache ? &*cache : nullptr, options, &kept); });
  py::dict layers;
  for (auto& [stem, set] : kept) layers[py::str(stem)] = layers_dict(std::move(set));
  json summary = {
      {"file", outcome.file},     {"name", outcome.name},         {"status", job_status_name(outcome.status)},
      {"errors", outcome.errors}, {"warnings", outcome.warnings}, {"methods", outcome.methods}};
  summary["outputs"] = json::array();
  for (const fs::path& p : outcome.outputs) summary["outputs"].push_back(fs::absolute(p).string());
  return py::make_tuple(layers, summary.dump());
}

// compare(now, baseline): `hfbake compare NOW BASELINE` without printing; the result as JSON text.
std::string compare_api(const std::string& now, const std::string& baseline,
                        const std::vector<std::string>& tolerances, bool allow_different_job,
                        bool update_baseline) {
  CompareOptions options;
  options.now = now;
  options.baseline = baseline;
  options.tolerances = tolerances;
  options.allow_different_job = allow_different_job;
  options.update_baseline = update_baseline;
  options.quiet = true;
  const CompareResult r = compare_reports(options);
  if (!r.refusals.empty()) {
    std::vector<Problem> problems;
    for (const std::string& line : r.refusals) problems.push_back({"", "", line});
    raise_input_error(problems);
  }
  return json{{"regression", r.regression},
              {"comparisons", r.comparisons},
              {"text", r.text},
              {"baseline_updated", r.baseline_updated}}
      .dump();
}

}  // namespace
}  // namespace hfbake

PYBIND11_MODULE(_hfbake, m) {
  using namespace hfbake;
  m.doc() = "hfbake's C++ core (the package hfbake wraps it)";
  set_temporary_owner(temporary_owner());  // temporaries a later process can clean up
  m.attr("__version__") = hfbake_version();
  py::register_exception_translator([](std::exception_ptr p) {
    try {
      if (p) std::rethrow_exception(p);
    } catch (const InputError& e) {
      set_input_error({{e.file(), e.where(), e.what()}});
    } catch (const Cancelled&) {
      const py::object type = py::module_::import("hfbake").attr("Cancelled");
      PyErr_SetString(type.ptr(), "the bake was cancelled; nothing was kept");
    }
  });
  m.def("method_names", &method_names);
  m.def("method_summary", [](const std::string& name) {
    const MethodInfo* info = find_method(name);
    return std::string(info ? info->summary : "");
  });
  m.def("method_schema", [](const std::string& name) {
    for (const EmbeddedSchema& s : embedded_schemas())
      if (s.path == "methods/" + name + ".schema.json") return std::string(s.text);
    return std::string();
  });
  m.def("bake_array", &bake_array, py::arg("method"), py::arg("heights"), py::arg("entry_keys"),
        py::arg("height_keys"), py::arg("job_keys"), py::arg("threads") = 0, py::arg("progress") = py::none(),
        py::arg("cancel") = py::none(), py::arg("memory_limit") = std::nullopt);
  m.def("compare", &compare_api, py::arg("now"), py::arg("baseline"), py::arg("tolerances"),
        py::arg("allow_different_job"), py::arg("update_baseline"));
  m.def("validate", &validate_job, py::arg("job"), py::arg("memory_limit") = std::nullopt);
  // The command's warning for a DEM whose CRS is far from true scale at (x, y), or "" (read_dem).
  m.def(
      "site_scale_warning",
      [](const std::string& wkt, double x, double y, const std::string& crs_name) {
        const std::optional<double> k = grid_scale_factor(wkt, x, y);
        return k ? site_scale_warning(*k, crs_name) : std::string();
      },
      py::arg("wkt"), py::arg("x"), py::arg("y"), py::arg("crs_name"));
  // What read_dem refuses in band `band` (0-based) of a georeferenced raster where no data covers it ("" when
  // nothing), in the words a job naming the file gets (io/georaster_input.hpp uncovered_problem).
  m.def(
      "uncovered_problem",
      [](const std::string& path, int band) {
        const std::optional<GeoRasterInfo> info = probe_georaster(path);
        return info ? uncovered_problem(*info, band) : std::string();
      },
      py::arg("path"), py::arg("band"));
  // The note on heights a band declares no unit for, in a CRS whose unit is not the metre (read_dem).
  m.def("unitless_heights_note", &unitless_heights_note, py::arg("pixel_unit"), py::arg("pixel_unit_metres"),
        py::arg("height_unit"));
  // Metres in a unit of length by its name, or None (read_dem's height_unit_factor).
  m.def("metres_per", &metres_per, py::arg("unit"));
  m.def("bake_job", &bake_job_api, py::arg("job"), py::arg("out"), py::arg("threads") = 0,
        py::arg("progress") = py::none(), py::arg("cancel") = py::none(),
        py::arg("memory_limit") = std::nullopt, py::arg("cache") = true, py::arg("overwrite") = false);
}
