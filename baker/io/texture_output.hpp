// Engine-ready textures: chosen layers as linear 8- or 16-bit integer images (PNG, TIFF, TGA) or half-float
// OpenEXR (values above 1 kept: light maps as HDR), channel
// packs (R/G/B/A from named layers), normal maps of direction layers (0.5 + 0.5 n, world or tangent space,
// OpenGL or DirectX green), and optional edge padding for atlases. docs/textures.md.
#pragma once

#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include "core/layers.hpp"

namespace hfbake {

// One channel of a texture: channel `channel` of layer `layer`, or a constant when `layer` is empty.
struct TextureSource {
  std::string layer;
  int channel = 0;
  float constant = 0;
};

// The frame a direction layer (bent_normal) is written in:
//   world:   hfbake's world frame as stored in the EXR: R = +x (image right), G = +y (image down), B = +z
//   (up). tangent: the frame of the flat base the height field displaces (the texture's own u, v and its
//   normal):
//            R = +x (image right), B = +z, G = image up (-y) for "opengl", image down (+y) for "directx".
enum class NormalSpace { world, tangent };
enum class GreenAxis { opengl, directx };
enum class Transfer { linear, srgb };

struct TextureSpec {
  // 1 (grey), 3 (RGB) or 4 (RGBA) channels. For a normal map: the X, Y, Z channels of one direction layer.
  std::vector<TextureSource> channels;
  // Encode 0.5 + 0.5 n in `space` (never through the transfer curve). Components within 1e-6 of 0 are
  // written as 0 (128 or 32768: 0.5 is a rounding tie that float noise would otherwise decide).
  bool normal_map = false;
  NormalSpace space = NormalSpace::tangent;
  GreenAxis green = GreenAxis::opengl;
  Transfer transfer = Transfer::linear;  // srgb: the sRGB encoding curve (IEC 61966-2-1) before quantising
  // Multiplies every value read from a layer before the transfer curve and the clamp to [0, 1] (light
  // maps: brings radiance above 1 into range); not normal maps or constants.
  double exposure = 1;
  int bits = 8;  // 8 or 16
  // Texels added on every side: (width + 2 p) x (height + 2 p). A padding texel repeats the nearest edge
  // texel (clamp fields) or the texel one period away (repeat fields: the tile continues).
  int padding = 0;
  bool repeat = false;
};

// How many of a texture's values read from layers (not normal maps, not constants) were above 1 after the
// exposure, and so clipped to 1: what a light map loses silently otherwise.
struct TextureClipping {
  std::size_t clipped = 0, values = 0;
  // Values below 0 (a signed channel, such as bent_normal.X in a pack), clipped to 0.
  std::size_t negative = 0;
  double largest = 0;  // the largest value after the exposure
  double p99 = 0;      // the 99th percentile of the values after the exposure (computed when any clipped)
};

// The texture's size and its quantised values, interleaved, rows top first: round(v * (2^bits - 1)) of
// each channel's value v (times the exposure) clamped to [0, 1] (NaN -> 0), after the normal-map encoding
// or the transfer curve.
struct TexturePixels {
  int width = 0, height = 0, channels = 0;
  std::vector<std::uint16_t> values;
  TextureClipping clipping;
};
TexturePixels texture_pixels(const LayerSet& layers, const TextureSpec& spec);

// The texture's size and its values as a half-float EXR texture holds them, interleaved, rows top first: each
// channel's value times the exposure (a normal map: 0.5 + 0.5 n), neither curved nor clamped (NaN -> 0).
// `bits` and `transfer` do not apply.
struct TextureValues {
  int width = 0, height = 0, channels = 0;
  std::vector<float> values;
};
TextureValues texture_values(const LayerSet& layers, const TextureSpec& spec);

// Writes the texture to `file`; the format follows the extension (.png, .tif, .tga: texture_pixels; .exr:
// half float, texture_values, channels Y, RGB or RGBA). 16 bits need PNG or TIFF. sRGB-encoded files are
// tagged sRGB; linear ones carry no colour tag. Returns what was clipped (nothing for .exr).
// Failure -> InputError naming the file.
TextureClipping write_texture(const std::filesystem::path& file, const LayerSet& layers,
                              const TextureSpec& spec);

}  // namespace hfbake
