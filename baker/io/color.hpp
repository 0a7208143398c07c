// Colour management through OpenColorIO. hfbake works in scene-linear Rec.709 (sRGB primaries). The
// config is $OCIO when that variable names a file, else hfbake's built-in config (OCIO 2.1 has no
// built-in configs of its own): colour spaces
//   "Linear Rec.709 (sRGB)"  aliases linear, scene_linear, lin_srgb, lin_rec709        (the reference)
//   "sRGB - Texture"         aliases sRGB, srgb, srgb_texture, srgb_tx                 (sRGB curve)
//   "Gamma 2.2 Rec.709"      aliases gamma22, g22_rec709
//   "ACEScg"                 aliases acescg, lin_ap1
//   "ACES2065-1"             aliases aces, aces2065-1, lin_ap0
//   "Raw"                    aliases raw, data, none                                   (no conversion)
// and one display "sRGB" with the views "Standard" (the sRGB curve) and "Raw".
#pragma once

#include <string>
#include <vector>

#include "io/image_input.hpp"

namespace hfbake {

// The built-in config as OCIO YAML (what `hfbake` uses when $OCIO is unset).
const std::string& builtin_ocio_config();

// Describes the active config: "$OCIO (<path>)" or "built-in".
std::string ocio_config_description();

// What the colour conversions of this process depend on, for keys of cached results (the reference
// cache): the active config as text (OpenColorIO's serialisation, or why it is unusable) and the LUT files
// its transforms read (resolved, sorted), whose bytes the key must cover too.
struct OcioIdentity {
  std::string text;
  std::vector<std::string> files;
};
OcioIdentity ocio_identity();

// The default input colour space for float (linear) or integer (sRGB) images.
std::string default_colorspace(bool float_data);

// For `hfbake validate`: InputError at the site if the active config has no such colour space, display
// or view (empty display/view = the defaults, always valid when the config loads).
void check_colorspace(const std::string& colorspace, const InputSite& site);
void check_display_view(const std::string& display, const std::string& view, const InputSite& display_site,
                        const InputSite& view_site);

// Converts interleaved pixels with `channels` channels (1: grey, 3: RGB, 4: RGBA with alpha untouched)
// from `colorspace` to scene-linear in place. Unknown colour space -> InputError at `site`.
void convert_to_linear(std::vector<float>& pixels, int channels, const std::string& colorspace,
                       const InputSite& site);

// Converts interleaved RGB scene-linear pixels to a display through a display/view (empty = the
// config's default display / that display's default view), in place. Unknown names -> InputError.
void convert_to_display(std::vector<float>& rgb, const std::string& display, const std::string& view,
                        const InputSite& site);

}  // namespace hfbake
