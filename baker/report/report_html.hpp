// report.html: the page a person reads beside report.json. One self-contained file (images embedded as
// PNG data URIs, plots drawn as inline SVG, no script or style from a network): per method the baked
// layers, the reference, the signed error image with its colour scale, the metrics table, timings and
// parameters; the hfbake version and the job hash; convergence plots where a job sweeps a parameter.
// Pure data in, text out (no file I/O; PNGs are encoded in memory by OpenImageIO, light goes through
// the job's OpenColorIO display/view like the PNG previews).
#pragma once

#include <cstdint>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "core/layers.hpp"

namespace hfbake {

struct HtmlMethod {
  std::string stem, method;
  const LayerSet* layers = nullptr;  // not owned; may be null (metrics only)
  // Sweeps (job/parameter_sweep.hpp): runs with the same sweep_group >= 0 are plotted together.
  std::string sweep_parameter;
  double sweep_value = 0;
  int sweep_group = -1;
};

struct HtmlInputs {
  nlohmann::json report;                // the report.json document (schemas/report.schema.json)
  std::vector<HtmlMethod> methods;      // in bake order
  const LayerSet* reference = nullptr;  // may be null (metrics only)
  int max_image_size = 320;             // larger fields are box-filtered (OpenImageIO) down to this size
  std::string reference_note;           // e.g. where the reference came from (the reference cache)
  // OpenColorIO display/view for light (RGB) images, as the job's PNG previews (output.preview_display,
  // output.preview_view); empty = the config's default display / that display's default view.
  std::string display, view;
};

std::string report_html(const HtmlInputs& inputs);

// Building blocks, exposed for tests. (The images are PNGs from encode_png in io/preview.hpp.)
std::string base64(const std::string& bytes);
// Escapes & < > " for HTML and XML text and double-quoted attribute values.
std::string html_escape(const std::string& s);

struct PlotSeries {
  std::string name, color;
  std::vector<std::pair<double, double>> points;  // (x, y), sorted by x
  bool dashed = false;
};
// A line plot as inline SVG; logarithmic axes where every value is > 0 (and `log_x` / `log_y` ask for it).
std::string svg_line_plot(const std::string& title, const std::string& x_label, const std::string& y_label,
                          const std::vector<PlotSeries>& series, bool log_x, bool log_y);

// A duration in seconds as a person reads it: three significant digits, whole seconds from 100 s
// ("0.0421", "8.39", "125").
std::string seconds_text(double seconds);

// The diverging colour scale of error images: -1 blue, 0 light grey, +1 red (clamped).
void diverging_colour(double t, std::uint8_t rgb[3]);

}  // namespace hfbake
