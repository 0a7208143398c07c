#include "report/report_html.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>
#include <set>
#include <sstream>
#include <stdexcept>

#include "io/color.hpp"
#include "io/preview.hpp"

namespace hfbake {
namespace {

std::string num(double v, int digits = 4) {
  if (!std::isfinite(v)) return v > 0 ? "inf" : (v < 0 ? "-inf" : "nan");
  char buf[40];
  std::snprintf(buf, sizeof buf, "%.*g", digits, v);
  return buf;
}

std::string json_num(const nlohmann::json& obj, const char* key, int digits = 4) {
  if (!obj.is_object() || !obj.contains(key) || !obj[key].is_number()) return "&ndash;";
  return num(obj[key].get<double>(), digits);
}

// The shown size of a w x h field: the same aspect, neither side above max_size (never enlarged).
struct Shown {
  int width, height;
};
Shown shown_size(int w, int h, int max_size) {
  max_size = std::max(1, max_size);
  const int m = std::max(w, h);
  if (m <= max_size) return {w, h};
  const double s = double(max_size) / m;
  return {std::clamp(int(std::lround(w * s)), 1, max_size), std::clamp(int(std::lround(h * s)), 1, max_size)};
}

// Down-samples interleaved linear values to the shown size with OpenImageIO's box filter (averaging in
// linear, before any display transform).
std::vector<float> down_sample(const std::vector<float>& values, int w, int h, int channels, const Shown& s) {
  return resize_pixels(values, w, h, channels, s.width, s.height, "box");
}

std::uint8_t to_byte(double v) {
  return std::uint8_t(std::lround(255.0 * (std::isfinite(v) ? std::clamp(v, 0.0, 1.0) : 0.0)));
}

// The q-quantile (nearest rank) of the magnitudes of values: one float copy of them (a whole layer's, 4 bytes
// a value, is the most report.html holds beside the layers).
double percentile_abs(const std::vector<float>& values, double q) {
  if (values.empty()) return 0;
  std::vector<float> v(values.size());
  for (std::size_t i = 0; i < v.size(); ++i) v[i] = std::abs(values[i]);
  const std::size_t k = std::min(v.size() - 1, std::size_t(q * double(v.size() - 1) + 0.5));
  std::nth_element(v.begin(), v.begin() + std::ptrdiff_t(k), v.end());
  return double(v[k]);
}

struct Img {
  std::string data_uri;
  int width = 0, height = 0;                // as shown
  int source_width = 0, source_height = 0;  // the field's texels
};

Img png_image(const std::vector<std::uint8_t>& px, int channels, const Shown& s, int w, int h) {
  return {"data:image/png;base64," + base64(encode_png(s.width, s.height, channels, px)), s.width, s.height,
          w, h};
}

// A layer shown as an image, scaled by `display_max`: 1 channel as grey with the value as the pixel value
// (how texture tools show an AO map), 3 channels (light) as RGB through the page's OpenColorIO
// display/view (the job's, as the PNG previews). Down-sampled in linear first.
Img layer_image(const Layer& l, int w, int h, int max_size, double display_max, const HtmlInputs& in) {
  const int nc = l.channel_count();
  const Shown s = shown_size(w, h, max_size);
  std::vector<float> v = down_sample(l.data, w, h, nc, s);
  for (float& x : v) x = float(x / display_max);
  if (nc == 3) convert_to_display(v, in.display, in.view, InputSite{"report.html", "output/preview_display"});
  std::vector<std::uint8_t> px(v.size());
  for (std::size_t i = 0; i < v.size(); ++i) px[i] = to_byte(v[i]);
  return png_image(px, nc, s, w, h);
}

std::string legend(const std::string& left, const std::string& mid, const std::string& right,
                   const std::string& gradient, const std::string& caption) {
  std::ostringstream h;
  h << "<div class=\"legend\"><div class=\"bar\" style=\"background:linear-gradient(to right," << gradient
    << ")\"></div><div class=\"ticks\"><span>" << html_escape(left) << "</span><span>" << html_escape(mid)
    << "</span><span>" << html_escape(right) << "</span></div><div class=\"cap\">" << html_escape(caption)
    << "</div></div>";
  return h.str();
}

std::string figure(const Img& img, const std::string& caption, const std::string& legend_html) {
  std::ostringstream h;
  h << "<figure><img src=\"" << img.data_uri << "\" width=\""
    << img.width * std::max(1, 256 / std::max(img.width, img.height)) << "\" alt=\"" << html_escape(caption)
    << "\"><figcaption>" << html_escape(caption);
  if (img.width != img.source_width || img.height != img.source_height)
    h << " (" << img.source_width << "&times;" << img.source_height << " box-filtered to " << img.width
      << "&times;" << img.height << ")";
  h << "</figcaption>" << legend_html << "</figure>";
  return h.str();
}

const char* const kMetricColumns[][2] = {
    {"mae", "mae"},         {"rmse", "rmse"}, {"rel_mae", "rel_mae"}, {"excess_rmse", "excess_rmse"},
    {"p99", "p99"},         {"max", "max"},   {"psnr", "psnr (dB)"},  {"bias", "bias"},
    {"noise_rmse", "noise"}};

std::string metrics_table(const std::string& stem, const nlohmann::json& layers,
                          const std::set<std::string>& failed) {
  std::ostringstream h;
  h << "<table class=\"metrics\"><tr><th>layer</th>";
  for (const auto& c : kMetricColumns) h << "<th>" << c[1] << "</th>";
  h << "</tr>\n";
  for (auto& [layer, m] : layers.items()) {
    h << "<tr><td>" << html_escape(layer) << "</td>";
    for (const auto& c : kMetricColumns) {
      const bool bad = failed.count(stem + "." + layer + "." + c[0]) > 0;
      h << "<td" << (bad ? " class=\"bad\" title=\"threshold or baseline failed\"" : "") << ">"
        << json_num(m, c[0]) << "</td>";
    }
    h << "</tr>\n";
  }
  h << "</table>\n";
  return h.str();
}

// obj[key] when it is an object, else an empty object (a reference that outlives the call).
const nlohmann::json& sub(const nlohmann::json& obj, const std::string& key) {
  static const nlohmann::json empty = nlohmann::json::object();
  if (obj.is_object()) {
    const auto it = obj.find(key);
    if (it != obj.end() && it->is_object()) return *it;
  }
  return empty;
}

const char* const kPalette[] = {"#1f77b4", "#d62728", "#2ca02c", "#9467bd", "#ff7f0e", "#8c564b"};

}  // namespace

std::string seconds_text(double seconds) {
  char buf[32];
  std::snprintf(buf, sizeof buf, seconds >= 100 ? "%.0f" : "%.3g", seconds);
  return buf;
}

void diverging_colour(double t, std::uint8_t rgb[3]) {
  // Blue (59, 76, 192) - light grey (221, 221, 221) - red (180, 4, 38): the ends of Moreland's cool-warm map.
  static const double lo[3] = {59, 76, 192}, mid[3] = {221, 221, 221}, hi[3] = {180, 4, 38};
  t = std::clamp(std::isfinite(t) ? t : 0.0, -1.0, 1.0);
  const double* end = t < 0 ? lo : hi;
  const double a = std::abs(t);
  for (int c = 0; c < 3; ++c) rgb[c] = std::uint8_t(std::lround(mid[c] + a * (end[c] - mid[c])));
}

std::string html_escape(const std::string& s) {
  std::string out;
  out.reserve(s.size());
  for (char c : s) {
    switch (c) {
      case '&':
        out += "&amp;";
        break;
      case '<':
        out += "&lt;";
        break;
      case '>':
        out += "&gt;";
        break;
      case '"':
        out += "&quot;";
        break;
      default:
        out += c;
    }
  }
  return out;
}

std::string base64(const std::string& bytes) {
  static const char* t = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::string out;
  out.reserve((bytes.size() + 2) / 3 * 4);
  std::size_t i = 0;
  for (; i + 2 < bytes.size(); i += 3) {
    const std::uint32_t v =
        (std::uint8_t(bytes[i]) << 16) | (std::uint8_t(bytes[i + 1]) << 8) | std::uint8_t(bytes[i + 2]);
    out += {t[v >> 18], t[(v >> 12) & 63], t[(v >> 6) & 63], t[v & 63]};
  }
  if (i + 1 == bytes.size()) {
    const std::uint32_t v = std::uint8_t(bytes[i]) << 16;
    out += {t[v >> 18], t[(v >> 12) & 63], '=', '='};
  } else if (i + 2 == bytes.size()) {
    const std::uint32_t v = (std::uint8_t(bytes[i]) << 16) | (std::uint8_t(bytes[i + 1]) << 8);
    out += {t[v >> 18], t[(v >> 12) & 63], t[(v >> 6) & 63], '='};
  }
  return out;
}

std::string svg_line_plot(const std::string& title, const std::string& x_label, const std::string& y_label,
                          const std::vector<PlotSeries>& series, bool log_x, bool log_y) {
  double x0 = INFINITY, x1 = -INFINITY, y0 = INFINITY, y1 = -INFINITY;
  std::set<double> xs;
  for (const PlotSeries& s : series)
    for (auto [x, y] : s.points) {
      if (!std::isfinite(x) || !std::isfinite(y)) continue;
      x0 = std::min(x0, x), x1 = std::max(x1, x), y0 = std::min(y0, y), y1 = std::max(y1, y);
      xs.insert(x);
      if (x <= 0) log_x = false;
      if (y <= 0) log_y = false;
    }
  if (!(x0 <= x1) || !(y0 <= y1)) return "<p>(nothing to plot)</p>";
  auto tx = [&](double v) { return log_x ? std::log10(v) : v; };
  auto ty = [&](double v) { return log_y ? std::log10(v) : v; };
  double ax0 = tx(x0), ax1 = tx(x1), ay0 = ty(y0), ay1 = ty(y1);
  if (ax1 - ax0 < 1e-12) ax0 -= 0.5, ax1 += 0.5;
  if (ay1 - ay0 < 1e-12)
    ay0 -= log_y ? 0.5 : std::max(1e-12, std::abs(ay0) * 0.5),
        ay1 += log_y ? 0.5 : std::max(1e-12, std::abs(ay1) * 0.5);
  const double pad_y = 0.06 * (ay1 - ay0);
  ay0 -= pad_y, ay1 += pad_y;
  if (!log_y && y0 >= 0) ay0 = std::max(ay0, 0.0);
  const int W = 440, H = 280, L = 64, R = 130, T = 28, B = 44;
  auto px = [&](double x) { return L + (tx(x) - ax0) / (ax1 - ax0) * (W - L - R); };
  auto py = [&](double y) { return H - B - (ty(y) - ay0) / (ay1 - ay0) * (H - T - B); };
  std::ostringstream s;
  s << "<svg xmlns=\"http://www.w3.org/2000/svg\" class=\"plot\" width=\"" << W << "\" height=\"" << H
    << "\" viewBox=\"0 0 " << W << " " << H << "\" font-family=\"sans-serif\" font-size=\"11\">";
  s << "<title>" << html_escape(title) << "</title><rect x=\"0\" y=\"0\" width=\"" << W << "\" height=\"" << H
    << "\" fill=\"white\"/>";
  s << "<text x=\"" << (L + (W - L - R) / 2) << "\" y=\"16\" text-anchor=\"middle\" font-size=\"12\">"
    << html_escape(title) << "</text>";
  // Axes, x ticks at the swept values, y ticks at decades (log) or 5 even steps.
  s << "<rect x=\"" << L << "\" y=\"" << T << "\" width=\"" << (W - L - R) << "\" height=\"" << (H - T - B)
    << "\" fill=\"none\" stroke=\"#888\"/>";
  for (double x : xs) {
    const double p = px(x);
    s << "<line x1=\"" << p << "\" x2=\"" << p << "\" y1=\"" << T << "\" y2=\"" << (H - B)
      << "\" stroke=\"#eee\"/><text x=\"" << p << "\" y=\"" << (H - B + 14) << "\" text-anchor=\"middle\">"
      << num(x) << "</text>";
  }
  std::vector<double> yt;
  if (log_y) {
    for (double e = std::floor(ay0); e <= std::ceil(ay1); e += 1)
      if (e >= ay0 && e <= ay1) yt.push_back(std::pow(10.0, e));
    if (yt.size() < 2)
      for (double m : {2.0, 5.0})
        for (double e = std::floor(ay0); e <= std::ceil(ay1); e += 1) {
          const double v = m * std::pow(10.0, e);
          if (std::log10(v) >= ay0 && std::log10(v) <= ay1) yt.push_back(v);
        }
  } else {
    for (int k = 0; k <= 4; ++k) yt.push_back(ay0 + (ay1 - ay0) * k / 4);
  }
  for (double y : yt) {
    const double p = py(y);
    s << "<line x1=\"" << L << "\" x2=\"" << (W - R) << "\" y1=\"" << p << "\" y2=\"" << p
      << "\" stroke=\"#eee\"/><text x=\"" << (L - 4) << "\" y=\"" << (p + 4) << "\" text-anchor=\"end\">"
      << num(y, 3) << "</text>";
  }
  s << "<text x=\"" << (L + (W - L - R) / 2) << "\" y=\"" << (H - 8) << "\" text-anchor=\"middle\">"
    << html_escape(x_label) << (log_x ? " (log)" : "") << "</text>";
  s << "<text transform=\"translate(14," << (T + (H - T - B) / 2) << ") rotate(-90)\" text-anchor=\"middle\">"
    << html_escape(y_label) << (log_y ? " (log)" : "") << "</text>";
  int row = 0;
  for (const PlotSeries& sr : series) {
    std::string pts;
    for (auto [x, y] : sr.points)
      if (std::isfinite(x) && std::isfinite(y)) pts += num(px(x), 6) + "," + num(py(y), 6) + " ";
    if (pts.empty()) continue;
    s << "<polyline fill=\"none\" stroke=\"" << sr.color << "\" stroke-width=\"2\""
      << (sr.dashed ? " stroke-dasharray=\"5,4\"" : "") << " points=\"" << pts << "\"/>";
    if (!sr.dashed)
      for (auto [x, y] : sr.points)
        if (std::isfinite(x) && std::isfinite(y))
          s << "<circle cx=\"" << num(px(x), 6) << "\" cy=\"" << num(py(y), 6) << "\" r=\"3\" fill=\""
            << sr.color << "\"/>";
    const int ly = T + 8 + 16 * row++;
    s << "<line x1=\"" << (W - R + 10) << "\" x2=\"" << (W - R + 28) << "\" y1=\"" << ly << "\" y2=\"" << ly
      << "\" stroke=\"" << sr.color << "\" stroke-width=\"2\""
      << (sr.dashed ? " stroke-dasharray=\"5,4\"" : "") << "/><text x=\"" << (W - R + 32) << "\" y=\""
      << (ly + 4) << "\">" << html_escape(sr.name) << "</text>";
  }
  s << "</svg>";
  return s.str();
}

namespace {

// --- the page's sections, in page order -------------------------------------------------------------------

// Styles, title and the verdict.
// The page's verdict: what was checked and how it went.
enum class Verdict { passed, failed, unchecked };

void write_head(std::ostringstream& h, const std::string& name, Verdict verdict) {
  h << "<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\">"
    << "<meta name=\"viewport\" content=\"width=device-width, initial-scale=1\">"
    << "<title>hfbake report: " << html_escape(name) << "</title>\n<style>\n"
    << "body{font-family:system-ui,sans-serif;margin:1.5em 2em;color:#222;background:#fff}\n"
    << "h1{margin-bottom:0.2em}h2{border-bottom:1px solid #ccc;margin-top:1.6em}h3{margin-bottom:0.3em}\n"
    << "table{border-collapse:collapse;margin:0.4em 0 0.8em}td,th{border:1px solid #ccc;padding:3px 8px;"
    << "text-align:right;font-variant-numeric:tabular-nums}th{background:#f3f3f3}td:first-child,th:first-"
       "child"
    << "{text-align:left}\n.bad{color:#b00;font-weight:bold;background:#fdecea}.ok{color:#070;font-weight:"
       "bold}.none{color:#555;font-weight:bold}\n"
    << ".meta td{text-align:left}.figs{display:flex;flex-wrap:wrap;gap:14px;align-items:flex-start}\n"
    << "figure{margin:0}figure img{image-rendering:pixelated;border:1px solid #999;display:block}\n"
    << "figcaption{font-size:90%;margin-top:3px}.legend{width:256px;font-size:80%}\n"
    << ".legend .bar{height:10px;border:1px solid #999}.legend "
       ".ticks{display:flex;justify-content:space-between}\n"
    << "pre{background:#f6f6f6;padding:6px;display:inline-block;margin:0}.plots{display:flex;flex-wrap:wrap;"
       "gap:12px}\n"
    << "</style></head>\n<body>\n";
  h << "<h1>hfbake report: " << html_escape(name) << "</h1>\n";
  const char* cls = verdict == Verdict::failed ? "bad" : verdict == Verdict::passed ? "ok" : "none";
  const char* text = verdict == Verdict::failed   ? "FAILED: a threshold or the baseline regressed"
                     : verdict == Verdict::passed ? "PASSED: every threshold held"
                                                  : "No thresholds set and no baseline: nothing was checked "
                                                    "(report.thresholds, report.baseline)";
  h << "<p class=\"" << cls << "\" id=\"verdict\">" << text << "</p>\n";
}

// Job, version, field size, compared region, reference.
void write_job_table(std::ostringstream& h, const nlohmann::json& r, const HtmlInputs& in) {
  const nlohmann::json none = nlohmann::json::object();
  const nlohmann::json job = r.value("job", none);
  const nlohmann::json ref_doc = r.value("reference", none);
  h << "<table class=\"meta\">";
  h << "<tr><th>job file</th><td>" << html_escape(job.value("file", std::string())) << "</td></tr>";
  h << "<tr><th>job hash</th><td><code>" << html_escape(job.value("hash", std::string()))
    << "</code></td></tr>";
  h << "<tr><th>hfbake version</th><td>" << html_escape(r.value("hfbake_version", std::string()))
    << "</td></tr>";
  if (r.contains("size") && r["size"].is_array() && r["size"].size() == 2)
    h << "<tr><th>field</th><td>" << r["size"][0].get<int>() << " &times; " << r["size"][1].get<int>()
      << " texels</td></tr>";
  if (r.contains("region")) {
    const auto& g = r["region"];
    h << "<tr><th>compared region</th><td>columns [" << g.value("x0", 0) << ", " << g.value("x1", 0)
      << "), rows [" << g.value("y0", 0) << ", " << g.value("y1", 0) << ") (crop " << r.value("crop", 0)
      << ")</td></tr>";
  }
  h << "<tr><th>reference</th><td>" << json_num(ref_doc, "seconds") << " s, parameters <code>"
    << html_escape(ref_doc.value("parameters", none).dump()) << "</code>"
    << (in.reference_note.empty() ? "" : "<br>" + html_escape(in.reference_note)) << "</td></tr>";
  h << "</table>\n";
}

void write_summary(std::ostringstream& h, const HtmlInputs& in, const nlohmann::json& methods,
                   const std::set<std::string>& failed) {
  // Summary: one row per method and layer, the error beyond the reference's noise first.
  h << "<h2>Summary</h2>\n<p>excess_rmse: the method's error beyond the reference's own noise, "
       "sqrt(max(rmse<sup>2</sup> &minus; noise<sup>2</sup>, 0)); rmse includes that noise.</p>\n"
       "<table class=\"summary\"><tr><th>method</th><th>time (s)</th><th>layer</th><th>excess_rmse</th>"
    << "<th>rmse</th><th>noise</th><th>rel_mae</th><th>p99</th><th>psnr (dB)</th></tr>\n";
  // In bake order (the inputs), then anything the report has that the inputs do not name.
  std::vector<std::string> order;
  for (const HtmlMethod& hm : in.methods)
    if (methods.contains(hm.stem)) order.push_back(hm.stem);
  for (auto& [stem, m] : methods.items())
    if (std::find(order.begin(), order.end(), stem) == order.end()) order.push_back(stem);
  for (const std::string& stem : order) {
    const nlohmann::json& m = methods[stem];
    const nlohmann::json& layers = sub(m, "layers");
    const std::string seconds = m.contains("seconds") && m["seconds"].is_number()
                                    ? seconds_text(m["seconds"].get<double>())
                                    : "&ndash;";
    if (layers.empty())
      h << "<tr><td>" << html_escape(stem) << "</td><td>" << seconds << "</td><td colspan=\"7\">no layer "
        << "compared</td></tr>\n";
    for (auto& [layer, mm] : layers.items()) {
      h << "<tr><td>" << html_escape(stem) << "</td><td>" << seconds << "</td><td>" << html_escape(layer)
        << "</td>";
      for (const char* k : {"excess_rmse", "rmse", "noise_rmse", "rel_mae", "p99", "psnr"})
        h << "<td" << (failed.count(stem + "." + layer + "." + k) ? " class=\"bad\"" : "") << ">"
          << json_num(mm, k) << "</td>";
      h << "</tr>\n";
    }
  }
  h << "</table>\n";
  // Directions: the angle between the method's and the reference's unit vectors per texel.
  std::ostringstream angles;
  for (const std::string& stem : order)
    for (auto& [layer, mm] : sub(methods[stem], "layers").items())
      if (mm.contains("angle_mean_deg"))
        angles << "<tr><td>" << html_escape(stem) << "</td><td>" << html_escape(layer) << "</td><td>"
               << json_num(mm, "angle_mean_deg", 3) << "</td><td>" << json_num(mm, "angle_p99_deg", 3)
               << "</td><td>" << json_num(mm, "angle_max_deg", 3) << "</td></tr>\n";
  if (!angles.str().empty())
    h << "<h3>Directions</h3>\n<table class=\"angles\"><tr><th>method</th><th>layer</th><th>mean angle "
         "(&deg;)</th><th>p99 angle (&deg;)</th><th>max angle (&deg;)</th></tr>\n"
      << angles.str() << "</table>\n";
}

void write_thresholds(std::ostringstream& h, const nlohmann::json& r) {
  // Thresholds and baseline.
  const nlohmann::json thresholds = r.value("thresholds", nlohmann::json::array());
  if (!thresholds.empty()) {
    h << "<h2>Thresholds</h2>\n<table class=\"thresholds\"><tr><th>key</th><th>limit</th><th>value</th><th>"
      << "</th></tr>\n";
    for (const auto& t : thresholds) {
      const bool ok = t.value("passed", false);
      h << "<tr><td>" << html_escape(t.value("key", std::string())) << "</td><td>"
        << (t.value("kind", std::string("max")) == "min" ? "&ge; " : "&le; ") << json_num(t, "limit")
        << "</td><td>" << json_num(t, "value") << "</td><td class=\"" << (ok ? "ok" : "bad") << "\">"
        << (ok ? "held" : html_escape("FAILED " + t.value("error", std::string()))) << "</td></tr>\n";
    }
    h << "</table>\n";
  }
}

void write_baseline(std::ostringstream& h, const nlohmann::json& r) {
  if (r.contains("baseline")) {
    const auto& b = r["baseline"];
    const auto regs = b.value("regressions", nlohmann::json::array());
    h << "<h2>Baseline</h2>\n<p>Against <code>" << html_escape(b.value("file", std::string()))
      << "</code> (regression: new &gt; "
      << "old &times; (1 + " << json_num(b, "rel_tolerance") << ") + " << json_num(b, "abs_tolerance")
      << "): "
      << (regs.empty() ? "<span class=\"ok\">nothing regressed</span>"
                       : "<span class=\"bad\">regressed</span>")
      << "</p>\n";
    if (!regs.empty()) {
      h << "<table class=\"baseline\"><tr><th>key</th><th>baseline</th><th>new</th></tr>\n";
      for (const auto& g : regs)
        h << "<tr><td>" << html_escape(g.value("key", std::string())) << "</td><td>"
          << json_num(g, "baseline") << "</td><td class=\"bad\">" << json_num(g, "value") << "</td></tr>\n";
      h << "</table>\n";
    }
  }
}

void write_convergence(std::ostringstream& h, const HtmlInputs& in, const nlohmann::json& methods,
                       const nlohmann::json& ref_doc) {
  // Convergence: every sweep group, each layer, error metrics against the swept parameter.
  std::map<int, std::vector<const HtmlMethod*>> groups;
  for (const HtmlMethod& m : in.methods)
    if (m.sweep_group >= 0 && methods.contains(m.stem)) groups[m.sweep_group].push_back(&m);
  if (!groups.empty()) {
    h << "<h2>Convergence</h2>\n";
    for (auto& [group, runs] : groups) {
      std::sort(runs.begin(), runs.end(), [](auto* a, auto* b) { return a->sweep_value < b->sweep_value; });
      const std::string param = runs.front()->sweep_parameter, method = runs.front()->method;
      std::set<std::string> layers;
      for (const HtmlMethod* m : runs)
        for (auto& [layer, mm] : sub(methods[m->stem], "layers").items()) layers.insert(layer);
      h << "<h3>" << html_escape(method) << ": error against " << html_escape(param)
        << "</h3>\n<div class=\"plots\">";
      for (const std::string& layer : layers) {
        std::vector<PlotSeries> series;
        int colour = 0;
        for (const char* metric : {"rmse", "mae", "excess_rmse", "p99"}) {
          PlotSeries s{metric, kPalette[colour++ % 6], {}, false};
          for (const HtmlMethod* m : runs) {
            const nlohmann::json& mm = sub(sub(methods[m->stem], "layers"), layer);
            if (mm.contains(metric) && mm[metric].is_number())
              s.points.emplace_back(m->sweep_value, mm[metric].get<double>());
          }
          if (!s.points.empty()) series.push_back(std::move(s));
        }
        // The reference's noise floor: below it the method's error cannot be resolved.
        const nlohmann::json& rl = sub(sub(ref_doc, "layers"), layer);
        if (rl.contains("noise_rmse") && rl["noise_rmse"].is_number() && rl["noise_rmse"].get<double>() > 0)
          series.push_back({"reference noise",
                            "#777",
                            {{runs.front()->sweep_value, rl["noise_rmse"].get<double>()},
                             {runs.back()->sweep_value, rl["noise_rmse"].get<double>()}},
                            true});
        h << svg_line_plot(method + " " + layer, param, "error", series, true, true);
      }
      PlotSeries time{"seconds", kPalette[0], {}, false};
      for (const HtmlMethod* m : runs)
        time.points.emplace_back(m->sweep_value, methods[m->stem].value("seconds", 0.0));
      h << svg_line_plot(method + " time", param, "seconds", {time}, true, true);
      h << "</div>\n";
    }
  }
}

// "+0.012" / "-0.012" (appended, not char* + string: GCC 12 reports a false -Wrestrict on that form here).
std::string signed_text(char sign, const std::string& number) {
  std::string t(1, sign);
  t += number;
  return t;
}

// The method's image, the reference's and the signed error per compared layer of one or three channels.
void write_layer_figures(std::ostringstream& h, const HtmlInputs& in, const HtmlMethod& hm,
                         const nlohmann::json& m) {
  const nlohmann::json none = nlohmann::json::object();
  const int w = hm.layers->width, ht = hm.layers->height;
  const nlohmann::json compared = m.value("layers", none);
  for (auto& [layer_name, mm] : compared.items()) {
    const Layer* ml = hm.layers->find(layer_name);
    const Layer* rl = in.reference->find(layer_name);
    if (!ml || !rl || ml->channel_count() != rl->channel_count()) continue;
    const int nc = ml->channel_count();
    if (nc != 1 && nc != 3) {
      h << "<p><code>" << html_escape(layer_name) << "</code>: " << nc << " channels, metrics only.</p>\n";
      continue;
    }
    // One display scale for the method and the reference: the 99.5th percentile of the reference.
    double display_max = percentile_abs(rl->data, 0.995);
    if (!(display_max > 0)) display_max = 1;
    // Signed error, mean over the channels, box-filtered like the images.
    const Shown shown = shown_size(w, ht, in.max_image_size);
    std::vector<float> full_err(std::size_t(w) * ht);
    for (std::size_t t = 0; t < full_err.size(); ++t) {
      double s = 0;
      for (int c = 0; c < nc; ++c) s += double(ml->data[t * nc + c]) - double(rl->data[t * nc + c]);
      full_err[t] = float(s / nc);
    }
    const std::vector<float> err = down_sample(full_err, w, ht, 1, shown);
    double scale = percentile_abs(err, 0.99);
    if (!(scale > 0)) scale = percentile_abs(err, 1.0);
    if (!(scale > 0)) scale = 1e-6;
    std::vector<std::uint8_t> px(err.size() * 3);
    for (std::size_t i = 0; i < err.size(); ++i) diverging_colour(err[i] / scale, &px[3 * i]);
    const Img err_img = png_image(px, 3, shown, w, ht);

    std::uint8_t lo[3], mid[3], hi[3];
    diverging_colour(-1, lo), diverging_colour(0, mid), diverging_colour(1, hi);
    char grad[160];
    std::snprintf(grad, sizeof grad, "rgb(%d,%d,%d),rgb(%d,%d,%d),rgb(%d,%d,%d)", lo[0], lo[1], lo[2], mid[0],
                  mid[1], mid[2], hi[0], hi[1], hi[2]);
    const std::string value_legend = legend(
        "0", num(display_max / 2, 3), num(display_max, 3), "#000,#bcbcbc,#fff",
        nc == 1 ? "value (linear grey, clipped at " + num(display_max, 3) + ")"
                : "light (OpenColorIO display " + (in.display.empty() ? "default" : in.display) + ", view " +
                      (in.view.empty() ? "default" : in.view) + ", clipped at " + num(display_max, 3) + ")");
    h << "<h3>" << html_escape(hm.stem) << " &middot; " << html_escape(layer_name)
      << "</h3>\n<div class=\"figs\">"
      << figure(layer_image(*ml, w, ht, in.max_image_size, display_max, in), hm.stem + " " + layer_name,
                value_legend)
      << figure(layer_image(*rl, w, ht, in.max_image_size, display_max, in), "reference " + layer_name,
                value_legend)
      << figure(err_img, "error: " + hm.stem + " - reference" + (nc > 1 ? " (mean of channels)" : ""),
                legend(signed_text('-', num(scale, 3)), "0", signed_text('+', num(scale, 3)), grad,
                       "signed error; blue: method too dark, red: too bright; clipped at p99 |error|"))
      << "</div>\n";
  }
}

void write_method(std::ostringstream& h, const HtmlInputs& in, const HtmlMethod& hm, const nlohmann::json& m,
                  const std::set<std::string>& failed) {
  const nlohmann::json none = nlohmann::json::object();
  h << "<h2 id=\"m-" << html_escape(hm.stem) << "\">" << html_escape(hm.stem) << "</h2>\n";
  h << "<p>method <b>" << html_escape(m.value("method", hm.method)) << "</b>, " << json_num(m, "seconds", 3)
    << " s, parameters <pre>" << html_escape(m.value("parameters", none).dump()) << "</pre></p>\n";
  h << metrics_table(hm.stem, m.value("layers", none), failed);
  const auto not_compared = m.value("not_compared", nlohmann::json::array());
  if (!not_compared.empty()) {
    const nlohmann::json reasons = m.value("not_compared_reasons", none);
    h << "<p>Not compared:</p>\n<ul class=\"not-compared\">";
    for (const auto& n : not_compared) {
      const std::string layer = n.get<std::string>();
      h << "<li><code>" << html_escape(layer) << "</code>";
      if (reasons.contains(layer) && reasons[layer].is_string())
        h << ": " << html_escape(reasons[layer].get<std::string>());
      h << "</li>";
    }
    h << "</ul>\n";
  }
  if (!hm.layers || !in.reference) return;
  if (hm.layers->width != in.reference->width || hm.layers->height != in.reference->height) return;
  write_layer_figures(h, in, hm, m);
}

void write_footer(std::ostringstream& h, const nlohmann::json& r) {
  // A check a browser runs on load: every image decoded (the headless browser test reads the result).
  h << "<script>\nwindow.addEventListener('load', function () {\n"
    << "  var imgs = document.images, ok = 0;\n"
    << "  for (var i = 0; i < imgs.length; ++i) if (imgs[i].complete && imgs[i].naturalWidth > 0) ++ok;\n"
    << "  document.body.setAttribute('data-images', imgs.length);\n"
    << "  document.body.setAttribute('data-images-decoded', ok);\n"
    << "  document.body.setAttribute('data-tables', document.querySelectorAll('table').length);\n"
    << "  if (ok !== imgs.length) console.error('hfbake report: ' + (imgs.length - ok) + ' images did not "
       "decode');\n"
    << "});\n</script>\n";
  h << "<p style=\"color:#777;font-size:85%\">Written by hfbake "
    << html_escape(r.value("hfbake_version", std::string()))
    << ". Self-contained: no file or network access is needed to view it.</p>\n</body></html>\n";
}

}  // namespace

std::string report_html(const HtmlInputs& in) {
  const nlohmann::json& r = in.report;
  const nlohmann::json none = nlohmann::json::object();
  const nlohmann::json job = r.value("job", none), methods = r.value("methods", none);
  const nlohmann::json ref_doc = r.value("reference", none);
  const std::string name = job.value("name", std::string("job"));

  // Keys that failed a threshold or the baseline: their cells are marked.
  std::set<std::string> failed;
  for (const auto& t : r.value("thresholds", nlohmann::json::array()))
    if (!t.value("passed", true)) failed.insert(t.value("key", std::string()));
  if (r.contains("baseline"))
    for (const auto& reg : r["baseline"].value("regressions", nlohmann::json::array()))
      failed.insert(reg.value("key", std::string()));

  std::ostringstream h;
  const bool checked = !r.value("thresholds", nlohmann::json::array()).empty() || r.contains("baseline");
  write_head(h, name,
             !r.value("passed", true) ? Verdict::failed
             : checked                ? Verdict::passed
                                      : Verdict::unchecked);
  write_job_table(h, r, in);
  write_summary(h, in, methods, failed);
  write_thresholds(h, r);
  write_baseline(h, r);
  write_convergence(h, in, methods, ref_doc);
  for (const HtmlMethod& hm : in.methods)
    if (methods.contains(hm.stem)) write_method(h, in, hm, methods[hm.stem], failed);
  write_footer(h, r);
  return h.str();
}

}  // namespace hfbake
