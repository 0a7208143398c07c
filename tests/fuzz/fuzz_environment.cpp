// libFuzzer harness: an environment image's bytes through load_environment, as a lat-long, a cube cross or
// all six faces of a cube map (the first byte picks the layout and the file's extension): the header probe,
// the pixel limit, the decode, the colour conversion, the finite and non-negative checks and the resampling.
// A bad image must be a one-line error naming the job file and the key; anything else is a finding.
#include <cstdint>
#include <string>

#include "core/error.hpp"
#include "fuzz_support.hpp"
#include "io/image_input.hpp"
#include "io/load_environment.hpp"

using namespace hfbake;

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static const char* const kExtensions[] = {".exr", ".hdr", ".png", ".tif"};
  if (size < 1) return 0;
  const std::string name = std::string("env") + kExtensions[data[0] % 4];
  const std::filesystem::path file = fuzz::write_scratch(name, data + 1, size - 1);
  nlohmann::json env;
  switch ((data[0] / 4) % 3) {
    case 0:
      env["latlong"] = name;
      break;
    case 1:
      env["cross"] = name;
      break;
    default:
      env["cubemap"] = {name, name, name, name, name, name};
  }
  if (data[0] & 0x80) env["rotation_deg"] = 30;
  EnvironmentLoadOptions options;
  options.job_file = "job.json";
  options.max_height = 16;  // the resampled map's size does not change what is checked; keeps runs fast
  try {
    // The loader's own limit is 2^27 pixels (1.5 GiB of floats); the fuzzer's budget is 2^20.
    const ImageInfo info = probe_image(file, {"job.json", "/environment"});
    if (std::uint64_t(info.width) * std::uint64_t(info.height) > (1u << 20)) return 0;
    (void)load_environment(env, fuzz::scratch_dir(), options);
  } catch (const InputError& e) {
    fuzz::check_error_line(e.line(), "job.json");
  }
  return 0;
}
