#include "io/color.hpp"

#include <OpenColorIO/OpenColorIO.h>

#include <sys/stat.h>

#include <algorithm>
#include <cstdint>
#include <cstdlib>
#include <sstream>
#include <stdexcept>

#include "core/error.hpp"

namespace OCIO = OCIO_NAMESPACE;

namespace hfbake {

namespace {

// baker/io/ocio/hfbake.ocio, embedded at build time (see CMakeLists.txt).
const char* const kBuiltinConfig =
#include "ocio_builtin_config.inc"
    ;

struct ActiveConfig {
  OCIO::ConstConfigRcPtr config;
  std::string description;
  std::string error;              // non-empty: $OCIO could not be loaded
  std::vector<std::string> luts;  // the files its FileTransforms read, as resolved
};

// The files a config reads: the config itself and every LUT a FileTransform names. OpenColorIO reads them
// whole, blocking: a pipe would hang the process (past a signal), a device such as /dev/zero fill its
// memory. So each must be a regular file of a bounded size, as every other input (io/image_input.hpp).
constexpr std::uintmax_t kMostConfigBytes = std::uintmax_t(64) << 20;
constexpr std::uintmax_t kMostLutBytes = std::uintmax_t(1) << 30;

void check_read_file(const std::string& path, std::uintmax_t most, const std::string& what) {
  struct stat st {};
  if (::stat(path.c_str(), &st) != 0) return;  // missing: OpenColorIO says so itself
  if (!S_ISREG(st.st_mode))
    throw std::runtime_error(what + " " + path +
                             ": not a regular file (a folder, a device, a pipe or a socket)");
  if (std::uintmax_t(st.st_size) > most)
    throw std::runtime_error(what + " " + path + ": " + std::to_string(st.st_size) +
                             " bytes, more than the " + std::to_string(most >> 20) + " MiB it may hold");
}

// Every FileTransform in t (and in the groups it holds), its file resolved as OpenColorIO resolves it.
void check_transform_files(const OCIO::ConstConfigRcPtr& config, const OCIO::ConstTransformRcPtr& t,
                           const std::string& owner, std::vector<std::string>& luts, int depth = 0) {
  if (!t || depth > 64) return;
  if (const auto file = OCIO::DynamicPtrCast<const OCIO::FileTransform>(t)) {
    const char* src = file->getSrc();
    if (!src || !*src) return;
    std::string path;
    try {
      path = config->getCurrentContext()->resolveFileLocation(src);
    } catch (const std::exception&) {
      return;  // not found: OpenColorIO's own error, where the transform is used
    }
    check_read_file(path, kMostLutBytes, owner + " reads the LUT");
    luts.push_back(path);
  } else if (const auto group = OCIO::DynamicPtrCast<const OCIO::GroupTransform>(t)) {
    for (int i = 0; i < group->getNumTransforms(); ++i)
      check_transform_files(config, group->getTransform(i), owner, luts, depth + 1);
  }
}

// Every transform a processor of the config may be built from: the colour spaces' (inactive ones too), the
// looks', the view transforms' and the named transforms'.
void check_config_files(const OCIO::ConstConfigRcPtr& config, std::vector<std::string>& luts) {
  const int spaces = config->getNumColorSpaces(OCIO::SEARCH_REFERENCE_SPACE_ALL, OCIO::COLORSPACE_ALL);
  for (int i = 0; i < spaces; ++i) {
    const char* name =
        config->getColorSpaceNameByIndex(OCIO::SEARCH_REFERENCE_SPACE_ALL, OCIO::COLORSPACE_ALL, i);
    const OCIO::ConstColorSpaceRcPtr cs = config->getColorSpace(name);
    if (!cs) continue;
    const std::string owner = std::string("colour space \"") + name + "\"";
    check_transform_files(config, cs->getTransform(OCIO::COLORSPACE_DIR_TO_REFERENCE), owner, luts);
    check_transform_files(config, cs->getTransform(OCIO::COLORSPACE_DIR_FROM_REFERENCE), owner, luts);
  }
  for (int i = 0; i < config->getNumLooks(); ++i) {
    const char* name = config->getLookNameByIndex(i);
    const OCIO::ConstLookRcPtr look = config->getLook(name);
    if (!look) continue;
    const std::string owner = std::string("look \"") + name + "\"";
    check_transform_files(config, look->getTransform(), owner, luts);
    check_transform_files(config, look->getInverseTransform(), owner, luts);
  }
  for (int i = 0; i < config->getNumViewTransforms(); ++i) {
    const char* name = config->getViewTransformNameByIndex(i);
    const OCIO::ConstViewTransformRcPtr vt = config->getViewTransform(name);
    if (!vt) continue;
    const std::string owner = std::string("view transform \"") + name + "\"";
    check_transform_files(config, vt->getTransform(OCIO::VIEWTRANSFORM_DIR_TO_REFERENCE), owner, luts);
    check_transform_files(config, vt->getTransform(OCIO::VIEWTRANSFORM_DIR_FROM_REFERENCE), owner, luts);
  }
  for (int i = 0; i < config->getNumNamedTransforms(OCIO::NAMEDTRANSFORM_ALL); ++i) {
    const char* name = config->getNamedTransformNameByIndex(OCIO::NAMEDTRANSFORM_ALL, i);
    const OCIO::ConstNamedTransformRcPtr nt = config->getNamedTransform(name);
    if (!nt) continue;
    const std::string owner = std::string("named transform \"") + name + "\"";
    check_transform_files(config, nt->getTransform(OCIO::TRANSFORM_DIR_FORWARD), owner, luts);
    check_transform_files(config, nt->getTransform(OCIO::TRANSFORM_DIR_INVERSE), owner, luts);
  }
}

const ActiveConfig& active_config() {
  static const ActiveConfig active = [] {
    ActiveConfig a;
    const char* env = std::getenv("OCIO");
    try {
      if (env && *env) {
        a.description = std::string("$OCIO (") + env + ")";
        check_read_file(env, kMostConfigBytes, "the config");
        a.config = OCIO::Config::CreateFromFile(env);
        check_config_files(a.config, a.luts);
      } else {
        a.description = "built-in";
        std::istringstream in(kBuiltinConfig);
        a.config = OCIO::Config::CreateFromStream(in);
      }
      a.config->validate();
    } catch (const std::exception& e) {
      a.config.reset();
      a.error = e.what();
    }
    return a;
  }();
  return active;
}

OCIO::ConstConfigRcPtr config_or_throw(const InputSite& site) {
  const ActiveConfig& a = active_config();
  if (!a.config)
    throw InputError(site.job_file, site.pointer, "OpenColorIO config " + a.description + ": " + a.error);
  return a.config;
}

std::string known_spaces(const OCIO::ConstConfigRcPtr& config) {
  std::string names;
  for (int i = 0; i < config->getNumColorSpaces(); ++i)
    names += (names.empty() ? "" : ", ") + std::string(config->getColorSpaceNameByIndex(i));
  return names;
}

void apply(const OCIO::ConstProcessorRcPtr& processor, std::vector<float>& pixels, int channels) {
  if (processor->isNoOp() || pixels.empty()) return;
  const OCIO::ConstCPUProcessorRcPtr cpu = processor->getDefaultCPUProcessor();
  if (channels == 3 || channels == 4) {
    // A run of pixels at a time: OpenColorIO's CPU processor holds float RGBA scratch the width of the
    // image it is given (two copies), which for the whole of a 4096 x 2048 image as one row was 270 MiB.
    constexpr std::size_t kRun = 4096;
    const std::size_t n = pixels.size() / std::size_t(channels);
    for (std::size_t first = 0; first < n; first += kRun) {
      OCIO::PackedImageDesc desc(pixels.data() + first * std::size_t(channels),
                                 long(std::min(kRun, n - first)), 1, channels);
      cpu->apply(desc);
    }
    return;
  }
  // Grey (or any other count): convert each value as a grey RGB triple and keep the first component.
  for (std::size_t i = 0; i < pixels.size(); i += std::size_t(channels)) {
    float rgb[3] = {pixels[i], pixels[i], pixels[i]};
    cpu->applyRGB(rgb);
    pixels[i] = rgb[0];
  }
}

}  // namespace

const std::string& builtin_ocio_config() {
  static const std::string text = kBuiltinConfig;
  return text;
}

OcioIdentity ocio_identity() {
  const ActiveConfig& a = active_config();
  OcioIdentity id;
  if (!a.config) {
    id.text = a.description + ": " + a.error;
    return id;
  }
  std::ostringstream text;
  a.config->serialize(text);
  id.text = text.str();
  id.files = a.luts;
  std::sort(id.files.begin(), id.files.end());
  id.files.erase(std::unique(id.files.begin(), id.files.end()), id.files.end());
  return id;
}

std::string ocio_config_description() {
  const ActiveConfig& a = active_config();
  return a.error.empty() ? a.description : a.description + " (unusable: " + a.error + ")";
}

std::string default_colorspace(bool float_data) {
  return float_data ? "scene_linear" : "sRGB";
}

void check_colorspace(const std::string& colorspace, const InputSite& site) {
  const OCIO::ConstConfigRcPtr config = config_or_throw(site);
  if (!config->getColorSpace(colorspace.c_str()))
    throw InputError(site.job_file, site.pointer,
                     "unknown OpenColorIO colour space \"" + colorspace + "\" (config " +
                         active_config().description + "; it has: " + known_spaces(config) + ")");
}

namespace {
// The display/view actually used (defaults filled in), or InputError.
std::pair<std::string, std::string> resolve_display_view(const std::string& display, const std::string& view,
                                                         const InputSite& display_site,
                                                         const InputSite& view_site) {
  const OCIO::ConstConfigRcPtr config = config_or_throw(display_site);
  const std::string d = display.empty() ? config->getDefaultDisplay() : display;
  bool known = false;
  std::string displays;
  for (int i = 0; i < config->getNumDisplays(); ++i) {
    known = known || d == config->getDisplay(i);
    displays += (displays.empty() ? "" : ", ") + std::string(config->getDisplay(i));
  }
  if (!known)
    throw InputError(display_site.job_file, display_site.pointer,
                     "unknown OpenColorIO display \"" + d + "\" (it has: " + displays + ")");
  const std::string v = view.empty() ? config->getDefaultView(d.c_str()) : view;
  known = false;
  std::string views;
  for (int i = 0; i < config->getNumViews(d.c_str()); ++i) {
    known = known || v == config->getView(d.c_str(), i);
    views += (views.empty() ? "" : ", ") + std::string(config->getView(d.c_str(), i));
  }
  if (!known)
    throw InputError(
        view_site.job_file, view_site.pointer,
        "unknown OpenColorIO view \"" + v + "\" of display \"" + d + "\" (it has: " + views + ")");
  return {d, v};
}
}  // namespace

void check_display_view(const std::string& display, const std::string& view, const InputSite& display_site,
                        const InputSite& view_site) {
  resolve_display_view(display, view, display_site, view_site);
}

void convert_to_linear(std::vector<float>& pixels, int channels, const std::string& colorspace,
                       const InputSite& site) {
  const OCIO::ConstConfigRcPtr config = config_or_throw(site);
  if (!config->getColorSpace(colorspace.c_str()))
    throw InputError(site.job_file, site.pointer,
                     "unknown OpenColorIO colour space \"" + colorspace + "\" (config " +
                         active_config().description + "; it has: " + known_spaces(config) + ")");
  try {
    apply(config->getProcessor(colorspace.c_str(), OCIO::ROLE_SCENE_LINEAR), pixels, channels);
  } catch (const OCIO::Exception& e) {
    throw InputError(site.job_file, site.pointer,
                     "OpenColorIO cannot convert from \"" + colorspace + "\": " + e.what());
  }
}

void convert_to_display(std::vector<float>& rgb, const std::string& display, const std::string& view,
                        const InputSite& site) {
  const OCIO::ConstConfigRcPtr config = config_or_throw(site);
  const auto [d, v] = resolve_display_view(display, view, site, site);
  try {
    OCIO::DisplayViewTransformRcPtr t = OCIO::DisplayViewTransform::Create();
    t->setSrc(OCIO::ROLE_SCENE_LINEAR);
    t->setDisplay(d.c_str());
    t->setView(v.c_str());
    apply(config->getProcessor(t), rgb, 3);
  } catch (const OCIO::Exception& e) {
    throw InputError(site.job_file, site.pointer, std::string("OpenColorIO display transform: ") + e.what());
  }
}

}  // namespace hfbake
