// Everything a method bakes from: the height field with its normals, the surface, the lighting.
// Built once per job by the job loader; methods read it and never modify it.
#pragma once

#include <cstddef>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "env/environment.hpp"
#include "field/coarse_heights.hpp"
#include "field/georeference.hpp"
#include "field/height_field.hpp"

namespace hfbake {

// A surface property of every texel: one value held once (a number or [r, g, b] in the job: no bytes per
// texel) or one value per texel, row-major like the field (an image). Empty: not loaded.
class SurfaceMap {
 public:
  // All n texels have the value v.
  void assign(std::size_t n, Rgb v) {
    std::vector<Rgb>().swap(texels_);
    uniform_ = v;
    size_ = n;
  }
  // One value per texel.
  void assign(std::vector<Rgb> texels) {
    size_ = texels.size();
    texels_ = std::move(texels);
  }
  Rgb operator[](std::size_t t) const { return texels_.empty() ? uniform_ : texels_[t]; }
  std::size_t size() const { return size_; }
  bool empty() const { return size_ == 0; }
  std::size_t bytes() const { return texels_.size() * sizeof(Rgb); }

 private:
  std::vector<Rgb> texels_;  // empty: uniform_ everywhere
  Rgb uniform_{};
  std::size_t size_ = 0;
};

struct Surface {
  SurfaceMap albedo;          // loaded when a method or the reference reads it (or the job names an image)
  std::vector<Rgb> emission;  // per texel emitted radiance; empty = the surface emits nothing
};

// Where the heights came from and what they span, for the line validate and bake print about them
// (cli/scene_loader.hpp describe_heights).
struct HeightSource {
  std::string reader;       // "OpenImageIO", "GDAL", "procedural" or "numpy" (the Python module)
  std::string format;       // the reader's format or driver ("png", "GTiff", ...) or the procedural kind
  std::string sample_type;  // the stored samples: "uint8", "uint16", "float", ... (empty: procedural)
  bool integer = false;     // integer samples, taken as the stored integers
  double stored_min = 0, stored_max = 0;  // the heights as read, before height_scale and height_offset
  double scale = 1, offset = 0;           // height_scale and height_offset
  double world_min = 0, world_max = 0;    // the heights baked, in world units
  bool geographic = false;                // a raster in a geographic CRS, baked in its local frame
  // The band or channel read when the file has several ("band 1 of 2", "channel R of R, G, B"); else empty.
  std::string channel;
  // A GDAL raster's own scale and offset for the band (1 and 0: none declared), which are not applied.
  double file_scale = 1, file_offset = 0;
  // A GDAL raster's units: the projected CRS's unit of the pixels ("" for a geographic raster, baked in
  // metres, or a file without a CRS) and metres in it; the band's unit as the file declares it ("" when
  // none).
  std::string pixel_unit;
  double pixel_unit_metres = 1;
  std::string height_unit;
  // What of the image file is not read (io/image_input.hpp ImageInfo::unread), warned about; "" when nothing.
  std::string unread;
  // Holes filled from a NoData value that look like real heights (cli/scene_inputs.hpp
  // nodata_inside_heights), warned about; "" otherwise.
  std::string nodata_note;
};

// The texels of a field whose results are kept (a tile's interior, in the field's own coordinates;
// width < 0: every texel): what a bake's certified bounds count, since a halo texel's horizons stop at the
// window's edge.
struct KeptTexels {
  int x0 = 0, y0 = 0, width = -1, height = -1;

  bool contains(int i, int j) const {
    return width < 0 || (i >= x0 && j >= y0 && i < x0 + width && j < y0 + height);
  }
};

// Where the field lies in the raster it is cut from: a tile of a raster larger than memory
// (cli/tile_command.hpp) is the window whose texel (0, 0) is the raster's (x0, y0), with the raster's
// coarse copies (one per cell side a method walks, MethodInfo::far_cell). Default: the field is the whole
// raster, and a method coarsens it itself.
struct FieldWindow {
  int x0 = 0, y0 = 0;
  std::vector<std::shared_ptr<const CoarseHeights>> coarse;
  KeptTexels kept;

  // The raster's coarse copy of cells of `cell` texels; null when there is none.
  const CoarseHeights* coarse_of(int cell) const {
    for (const auto& g : coarse)
      if (g->cell == cell) return g.get();
    return nullptr;
  }
};

struct Scene {
  std::string name;  // the job's name
  HeightField field;
  std::vector<Vec3f> normals;  // compute_normals(field)
  Surface surface;
  Environment environment;
  std::vector<DirectionalLight> lights;  // the job's lights plus the built-in sky's sun
  int bounces = 1;
  // The Earth's curvature as every horizon-based method sees it: a caster at horizontal distance d from a
  // receiver is lowered by curvature * d^2 (c = (1 - k) / (2 R) per world unit, terrain/earth.hpp; 0: a
  // flat Earth). Its slope seen from the receiver is (z - z0) / d - c d.
  double curvature = 0;
  double refraction = 0;      // the coefficient k it was made with (for what validate and bake print)
  Georeference georeference;  // the input's CRS, geotransform and holes (for GeoTIFF outputs)
  HeightSource height_source;
  FieldWindow window;
};

}  // namespace hfbake
