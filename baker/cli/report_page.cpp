#include "cli/report_page.hpp"

#include "report/report_html.hpp"

namespace hfbake {

void write_report_page(const Job& job, const ReportInputs& inputs, const nlohmann::json& report,
                       OutputStage& stage, const std::string& reference_note) {
  HtmlInputs html;
  html.reference_note = reference_note;
  html.report = report;
  html.reference = &inputs.reference;
  html.display = job.output.preview_display;
  html.view = job.output.preview_view;
  for (const MethodLayers& m : inputs.methods) {
    HtmlMethod hm;
    hm.stem = m.stem;
    hm.method = m.method;
    hm.layers = &m.layers;
    for (const BakeEntry& e : job.bakes)
      if (e.stem == m.stem && e.sweep_group >= 0 && e.sweep_value.is_number()) {
        hm.sweep_parameter = e.sweep_parameter;
        hm.sweep_value = e.sweep_value.get<double>();
        hm.sweep_group = e.sweep_group;
      }
    html.methods.push_back(std::move(hm));
  }
  stage.write_text("report.html", report_html(html));
}

}  // namespace hfbake
