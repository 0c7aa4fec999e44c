// The files of one pass in an output directory, as simulate_pass --out and the node's
// ~report_file write them: stats.json, timeseries.csv and the measurement files (force_processed,
// contact_losses, droppers, dropper_rainflow, psd, dropper_series when the scene asks for it),
// each whole or not at all and all on the disk before any is renamed into place. The report drawn
// from them (scripts/pass_report) is the tools' business: catenary_sim/tools/report_launcher.hpp.
#pragma once

#include <string>
#include <vector>

#include "catenary_sim/core/output/lateral_statistics.hpp"
#include "catenary_sim/core/model/model.hpp"
#include "catenary_sim/core/engine/state.hpp"
#include "catenary_sim/core/output/pass_recorder.hpp"
#include "catenary_sim/core/output/statistics_json.hpp"

namespace catenary_sim {

// RFC 4180: a field with a comma, a quote or a line break is quoted, its quotes doubled.
std::string csv_field(const std::string& s);

// The names written by write_pass_files (dropper_series.csv only with output.dropper_series,
// the lateral files only on a 3-D line).
std::vector<std::string> pass_file_names(const Model& model);

// Creates `dir` and checks every pass file in it can be written; throws OutputError naming it.
void check_pass_files_writable(const std::string& dir, const Model& model);

// stats.json text with the 3-D line's "lateral" object and "stopped_by_dewirement" added (the
// text as it is on a 2-D line).
std::string add_lateral_statistics(const std::string& stats_json, const Model& model, const LateralStatistics& lateral,
                                   bool stopped_by_dewirement);

// stats.json of a pass, the one document simulate_pass --out, the node's ~stats_file and its
// ~report_file write: the pantographs' statistics, the line's (droppers, steady arms, limits,
// stations) and on a 3-D line (model.lateral) with `lateral` the "lateral" object.
std::string pass_statistics_json(const Model& model, const State& state, const PassRecorder& recorder,
                                 const RunInfo& run, const LateralRecorder* lateral = nullptr,
                                 bool stopped_by_dewirement = false);

// Writes the pass's files into `dir`; throws OutputError (then none is renamed into place).
// On a 3-D line (model.lateral) with `lateral`, also stats.json's "lateral" object and
// lateral.csv, lateral_histogram.csv, blow_off.csv, pull_off.csv and dewirements.csv. `stats`:
// recorder.statistics(model) if the caller has it already (it is not computed twice).
void write_pass_files(const std::string& dir, const Model& model, const State& state, const PassRecorder& recorder,
                      const RunInfo& run, const LateralRecorder* lateral = nullptr,
                      bool stopped_by_dewirement = false, const std::vector<PantographStatistics>* stats = nullptr);

}  // namespace catenary_sim
