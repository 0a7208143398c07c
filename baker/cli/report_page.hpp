// report.html beside report.json: the job's runs, their layers and the reference, handed to report_html.
#pragma once

#include <nlohmann/json.hpp>

#include "cli/outputs.hpp"
#include "cli/report_writer.hpp"
#include "job/manifest.hpp"

namespace hfbake {

// Stages report.html for `report` (the report.json document write_report produced).
// `reference_note` is shown beside the reference's time (e.g. that it came from the reference cache).
void write_report_page(const Job& job, const ReportInputs& inputs, const nlohmann::json& report,
                       OutputStage& stage, const std::string& reference_note = "");

}  // namespace hfbake
