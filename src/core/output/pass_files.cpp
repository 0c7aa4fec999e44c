#include "catenary_sim/core/output/pass_files.hpp"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <deque>
#include <future>
#include <iomanip>
#include <memory>
#include <sstream>

#include <nlohmann/json.hpp>

#include "catenary_sim/core/output/output_files.hpp"
#include "catenary_sim/core/output/line_measures.hpp"

namespace catenary_sim {

namespace {

// A CSV of rows (time first), written in pieces of about 1 MiB. A value that does not exist (NaN)
// is an empty field, as RFC 4180 readers take a missing value, never the text "nan".
// 9 significant digits as printf's %.9g (to_chars' general format is specified to match it),
// without the stream's per-number locale and format work: the series is most of a pass's output.
void append_number(std::string& out, double v) {
  char buf[32];
  const std::to_chars_result r = std::to_chars(buf, buf + sizeof buf, v, std::chars_format::general, 9);
  out.append(buf, static_cast<std::size_t>(r.ptr - buf));  // (pointer and length: no range replace)
}

void write_rows(AtomicFile& f, const std::vector<std::string>& columns, const std::deque<PassRecorder::Row>& rows) {
  constexpr std::size_t kPiece = 1u << 20;
  std::string c;
  // A piece and the longest row past it, held from the start: growing by doubling copied the
  // piece over and over, a good part of writing the series.
  c.reserve(kPiece + 32 * (columns.size() + 2));
  c = "time_s";
  for (const std::string& col : columns) c += "," + csv_field(col);
  c += "\n";
  for (const auto& row : rows) {
    append_number(c, row.time);
    for (double v : row.values) {
      c += ',';
      if (std::isfinite(v)) append_number(c, v);
    }
    c += '\n';
    if (c.size() > kPiece) {
      f.write(c);
      c.clear();
    }
  }
  f.write(c);
}

}  // namespace

std::string csv_field(const std::string& s) {
  if (s.find_first_of(",\"\r\n") == std::string::npos) return s;
  std::string out = "\"";
  for (char c : s) out += c == '"' ? std::string("\"\"") : std::string(1, c);
  return out + "\"";
}

std::vector<std::string> pass_file_names(const Model& model) {
  std::vector<std::string> names{"stats.json",   "timeseries.csv",       "force_processed.csv", "contact_losses.csv",
                                 "droppers.csv", "dropper_rainflow.csv", "psd.csv"};
  if (model.scene.output.dropper_series) names.push_back("dropper_series.csv");
  if (model.lateral)
    for (const char* n : {"lateral.csv", "lateral_histogram.csv", "blow_off.csv", "pull_off.csv", "dewirements.csv"})
      names.push_back(n);
  return names;
}

void check_pass_files_writable(const std::string& dir, const Model& model) {
  make_directories(dir);
  for (const std::string& name : pass_file_names(model)) check_writable(dir + "/" + name);
}

std::string add_lateral_statistics(const std::string& stats_json, const Model& m, const LateralStatistics& lateral,
                                   bool stopped_by_dewirement) {
  if (!m.lateral) return stats_json;
  nlohmann::json j = nlohmann::json::parse(stats_json);
  j["lateral"] = nlohmann::json::parse(lateral_statistics_json(m, lateral));
  j["stopped_by_dewirement"] = stopped_by_dewirement;
  return j.dump(2, ' ', false, nlohmann::json::error_handler_t::replace) + "\n";
}

namespace {
std::string stats_document(const Model& m, const State& st, const std::vector<PantographStatistics>& stats,
                           const LineStatistics& line, const RunInfo& run, const LateralStatistics& lateral,
                           bool stopped_by_dewirement) {
  return add_lateral_statistics(statistics_json(m, st, stats, run, &line), m, lateral, stopped_by_dewirement);
}
}  // namespace

std::string pass_statistics_json(const Model& m, const State& st, const PassRecorder& recorder, const RunInfo& run,
                                 const LateralRecorder* lateral, bool stopped_by_dewirement) {
  const LateralStatistics lateral_stats = m.lateral && lateral ? lateral->statistics(m, st) : LateralStatistics{};
  return stats_document(m, st, recorder.statistics(m), recorder.line_statistics(m), run, lateral_stats,
                        stopped_by_dewirement);
}

void write_pass_files(const std::string& dir, const Model& m, const State& st, const PassRecorder& recorder,
                      const RunInfo& run, const LateralRecorder* lateral, bool stopped_by_dewirement,
                      const std::vector<PantographStatistics>* given) {
  const std::vector<PantographStatistics> computed = given ? std::vector<PantographStatistics>{} : recorder.statistics(m);
  const std::vector<PantographStatistics>& stats = given ? *given : computed;
  const LineStatistics line = recorder.line_statistics(m);
  std::vector<std::unique_ptr<AtomicFile>> files;
  // Each file's writing to the disk starts as soon as it is complete, while the next is formatted.
  auto add = [&](const std::string& name) -> AtomicFile& {
    if (!files.empty()) files.back()->start_writeback();
    files.push_back(std::make_unique<AtomicFile>(dir + "/" + name));
    return *files.back();
  };
  write_rows(add("timeseries.csv"), recorder.columns(), recorder.rows());
  const bool three_d = m.lateral && lateral;
  const LateralStatistics lateral_stats = three_d ? lateral->statistics(m, st) : LateralStatistics{};
  add("stats.json").write(stats_document(m, st, stats, line, run, lateral_stats, stopped_by_dewirement));
  write_rows(add("force_processed.csv"), recorder.processed_columns(), recorder.processed_rows(m));
  {
    std::ostringstream c;
    c << std::setprecision(9) << "pantograph,start_time_s,station_m,duration_s,length_m\n";
    for (const PantographStatistics& p : stats)
      for (const ContactLossEvent& e : p.loss_events)
        c << csv_field(p.name) << "," << e.start_time << "," << e.station << "," << e.duration << "," << e.length << "\n";
    add("contact_losses.csv").write(c.str());
  }
  {
    std::ostringstream c, r;
    // A compound line's droppers.csv says which rows are hangers (auxiliary messenger to contact wire).
    const bool compound = std::any_of(line.droppers.begin(), line.droppers.end(), [](const DropperStatistics& d) { return d.hanger; });
    c << std::setprecision(9) << "station_m,static_tension_N,max_force_N,min_force_N,slack_percent,rainflow_cycles,max_range_N"
      << (compound ? ",hanger\n" : "\n");
    r << std::setprecision(9) << "station_m,range_from_N,range_to_N,cycles\n";
    for (const DropperStatistics& d : line.droppers) {
      c << d.station << "," << d.static_tension << "," << d.max_force << "," << d.min_force << "," << d.slack_percent << ","
        << d.cycles << "," << d.max_range;
      c << (compound ? (d.hanger ? ",1\n" : ",0\n") : "\n");
      for (std::size_t b = 0; b < d.histogram.size(); ++b)
        r << d.station << "," << b * line.range_bin_n << "," << (b + 1) * line.range_bin_n << "," << d.histogram[b] << "\n";
    }
    add("droppers.csv").write(c.str());
    add("dropper_rainflow.csv").write(r.str());
  }
  {
    std::ostringstream c;
    c << std::setprecision(9) << "pantograph,frequency_hz,psd_N2_per_hz\n";
    const std::vector<Spectrum> spectra = recorder.spectra(m);
    for (std::size_t p = 0; p < spectra.size(); ++p)
      for (std::size_t k = 0; k < spectra[p].frequency.size() && spectra[p].frequency[k] <= kSpectrumMaxHz; ++k)
        c << csv_field(m.pantographs[p].name) << "," << spectra[p].frequency[k] << "," << spectra[p].psd[k] << "\n";
    add("psd.csv").write(c.str());
  }
  if (m.scene.output.dropper_series) write_rows(add("dropper_series.csv"), recorder.dropper_columns(), recorder.dropper_rows());
  if (three_d) {
    write_rows(add("lateral.csv"), lateral->columns(), lateral->rows());
    std::ostringstream h, b, p, d;
    h << std::setprecision(9) << "pantograph,collector,from_m,to_m,percent_of_contact_time\n";
    for (const LateralContactStatistics& c : lateral_stats.contacts)
      for (std::size_t k = 0; k < c.histogram_percent.size(); ++k)
        h << csv_field(c.pantograph) << "," << c.collector << "," << c.from + k * c.bin << "," << c.from + (k + 1) * c.bin
          << "," << c.histogram_percent[k] << "\n";
    add("lateral_histogram.csv").write(h.str());
    b << std::setprecision(9) << "span,start_m,end_m,static_blow_off_m,max_blow_off_m,exceeded\n";
    for (const SpanBlowOff& s : lateral_stats.spans)
      b << s.span << "," << s.start << "," << s.end << "," << s.static_m << "," << s.max_m << "," << s.exceeded << "\n";
    add("blow_off.csv").write(b.str());
    p << std::setprecision(9) << "wire,station_m,stagger_m,anchor,rigid,pull_off_N,pull_off_mean_wind_N\n";
    for (const LateralSupport& s : m.lateral->supports)
      p << csv_field(m.wires[s.wire].name) << "," << s.x << "," << s.stagger << "," << s.anchor << "," << s.rigid << ","
        << s.pull_off << "," << s.pull_off_wind << "\n";
    add("pull_off.csv").write(p.str());
    d << std::setprecision(9) << "pantograph,collector,time_s,station_m,lateral_m\n";
    for (const DewirementEvent& e : lateral_stats.events)
      d << csv_field(m.pantographs[e.pantograph].name) << "," << e.collector << "," << e.time << "," << e.station << ","
        << e.lateral << "\n";
    add("dewirements.csv").write(d.str());
  }
  // All on the disk before any is renamed into place: a full disk leaves the old set (or none),
  // never a new CSV beside an old stats.json.
  // Each is fsync'd once, here (commit() does not repeat it), all at once: the file system
  // commits their metadata together and the waits for the disk overlap instead of adding up.
  files.back()->start_writeback();
  std::vector<std::future<void>> synced;
  for (auto& f : files) synced.push_back(std::async(std::launch::async, [&f] { f->flush(); }));
  for (auto& s : synced) s.wait();
  for (auto& s : synced) s.get();  // the first failure, as an OutputError
  for (auto& f : files) f->commit();
}

}  // namespace catenary_sim
