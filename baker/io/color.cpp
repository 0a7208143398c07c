#include "io/color.hpp"

#include <OpenColorIO/OpenColorIO.h>

#include <cstdlib>
#include <sstream>

#include "core/error.hpp"

namespace OCIO = OCIO_NAMESPACE;

namespace hfbake {

namespace {

// The reference space is linear Rec.709. Curves use OCIO's ExponentWithLinearTransform (forward =
// decode to linear): sRGB is gamma 2.4 with offset 0.055 (IEC 61966-2-1); the ACES spaces use OCIO's
// built-in transforms (Bradford-adapted matrices).
const char* const kBuiltinConfig = R"yaml(ocio_profile_version: 2.1

description: hfbake built-in config (scene-linear Rec.709 reference; sRGB display)

roles:
  default: Raw
  data: Raw
  reference: Linear Rec.709 (sRGB)
  scene_linear: Linear Rec.709 (sRGB)
  rendering: Linear Rec.709 (sRGB)
  compositing_linear: Linear Rec.709 (sRGB)
  color_picking: sRGB - Texture
  texture_paint: sRGB - Texture
  matte_paint: sRGB - Texture

file_rules:
  - !<Rule> {name: Default, colorspace: default}

displays:
  sRGB:
    - !<View> {name: Standard, colorspace: sRGB - Display}
    - !<View> {name: Raw, colorspace: Raw}

active_displays: [sRGB]
active_views: [Standard, Raw]

colorspaces:
  - !<ColorSpace>
    name: Linear Rec.709 (sRGB)
    aliases: [linear, lin_srgb, lin_rec709, Utility - Linear - sRGB]
    family: Scene-linear
    equalitygroup: ""
    bitdepth: 32f
    description: Scene-linear, Rec.709 primaries, D65 white (hfbake's working space)
    isdata: false
    allocation: lg2
    allocationvars: [-15, 6]

  - !<ColorSpace>
    name: sRGB - Texture
    aliases: [sRGB, srgb, srgb_texture, srgb_tx, Utility - sRGB - Texture]
    family: Texture
    bitdepth: 8ui
    description: The sRGB curve (IEC 61966-2-1) on Rec.709 primaries
    isdata: false
    to_scene_reference: !<ExponentWithLinearTransform> {gamma: 2.4, offset: 0.055}

  - !<ColorSpace>
    name: Gamma 2.2 Rec.709
    aliases: [gamma22, g22_rec709]
    family: Texture
    bitdepth: 8ui
    description: A pure 2.2 power curve on Rec.709 primaries
    isdata: false
    to_scene_reference: !<ExponentTransform> {value: 2.2, style: pass_thru}

  - !<ColorSpace>
    name: ACEScg
    aliases: [acescg, lin_ap1]
    family: Scene-linear
    bitdepth: 32f
    description: Scene-linear AP1 primaries (ACEScg)
    isdata: false
    to_scene_reference: !<BuiltinTransform> {style: UTILITY - ACES-AP1_to_LINEAR-REC709_BFD}

  - !<ColorSpace>
    name: ACES2065-1
    aliases: [aces, aces2065-1, lin_ap0]
    family: Scene-linear
    bitdepth: 32f
    description: Scene-linear AP0 primaries (ACES2065-1)
    isdata: false
    to_scene_reference: !<GroupTransform>
      children:
        - !<BuiltinTransform> {style: ACEScg_to_ACES2065-1, direction: inverse}
        - !<BuiltinTransform> {style: UTILITY - ACES-AP1_to_LINEAR-REC709_BFD}

  - !<ColorSpace>
    name: Raw
    aliases: [raw, none]
    family: Data
    bitdepth: 32f
    description: Non-colour data, never converted
    isdata: true

  - !<ColorSpace>
    name: sRGB - Display
    aliases: [srgb_display]
    family: Display
    bitdepth: 8ui
    description: sRGB display (the sRGB curve, values clamped to [0, 1] by the 8-bit output)
    isdata: false
    from_scene_reference: !<ExponentWithLinearTransform> {gamma: 2.4, offset: 0.055, direction: inverse}
)yaml";

struct ActiveConfig {
  OCIO::ConstConfigRcPtr config;
  std::string description;
  std::string error;  // non-empty: $OCIO could not be loaded
};

const ActiveConfig& active_config() {
  static const ActiveConfig active = [] {
    ActiveConfig a;
    const char* env = std::getenv("OCIO");
    try {
      if (env && *env) {
        a.description = std::string("$OCIO (") + env + ")";
        a.config = OCIO::Config::CreateFromFile(env);
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
    const long n = long(pixels.size() / std::size_t(channels));
    OCIO::PackedImageDesc desc(pixels.data(), n, 1, channels);
    cpu->apply(desc);
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

std::string ocio_config_description() {
  const ActiveConfig& a = active_config();
  return a.error.empty() ? a.description : a.description + " (unusable: " + a.error + ")";
}

std::string default_colorspace(bool float_data) {
  return float_data ? "scene_linear" : "sRGB";
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
  const std::string d = display.empty() ? config->getDefaultDisplay() : display;
  bool known = false;
  for (int i = 0; i < config->getNumDisplays(); ++i) known = known || d == config->getDisplay(i);
  if (!known) throw InputError(site.job_file, site.pointer, "unknown OpenColorIO display \"" + d + "\"");
  const std::string v = view.empty() ? config->getDefaultView(d.c_str()) : view;
  known = false;
  for (int i = 0; i < config->getNumViews(d.c_str()); ++i)
    known = known || v == config->getView(d.c_str(), i);
  if (!known)
    throw InputError(site.job_file, site.pointer,
                     "unknown OpenColorIO view \"" + v + "\" of display \"" + d + "\"");
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
