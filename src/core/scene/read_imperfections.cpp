#include "scene/read_imperfections.hpp"
#include "scene/capped_file.hpp"

#include <sys/stat.h>

#include <cerrno>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <sstream>
#include <vector>

namespace catenary_sim {

using namespace scene_reading;
namespace {

// A two-column CSV (station in m, value): '#' starts a comment, one header line allowed, comma,
// semicolon, tab or blank separated. Errors name the file, the line and what is allowed.
LineProfile read_profile_csv(const std::string& field, const std::string& path, double lo, double hi) {
  struct stat st {};
  if (::stat(path.c_str(), &st) != 0) fail(field, "'" + path + "'", std::string("a readable CSV file (") + std::strerror(errno) + ")");
  if (S_ISDIR(st.st_mode)) fail(field, "'" + path + "'", "a CSV file, not a directory");
  std::ifstream in(path, std::ios::binary);
  if (!in) fail(field, "'" + path + "'", std::string("a readable CSV file (") + std::strerror(errno) + ")");
  const std::string text = read_capped(in, kMaxSceneFileBytes);
  if (text.size() > kMaxSceneFileBytes)
    fail(field, "'" + path + "'", "a CSV of at most " + std::to_string(kMaxSceneFileBytes >> 20) + " MiB");
  if (in.bad()) fail(field, "'" + path + "'", std::string("a readable CSV file (") + std::strerror(errno) + ")");
  std::istringstream lines(text);
  LineProfile p;
  std::string line;
  bool header_allowed = true;
  for (int no = 1; std::getline(lines, line); ++no) {
    const std::size_t hash = line.find('#');
    if (hash != std::string::npos) line.resize(hash);
    for (char& c : line)
      if (c == ',' || c == ';' || c == '\t' || c == '\r' || c == '"') c = ' ';
    std::istringstream cols(line);
    std::vector<std::string> cell;
    for (std::string c; cols >> c;) cell.push_back(c);
    if (cell.empty()) continue;
    const std::string where = "'" + path + "' line " + std::to_string(no);
    std::vector<double> v;
    for (const std::string& c : cell) {
      char* end = nullptr;
      const double d = std::strtod(c.c_str(), &end);
      if (end != c.c_str() + c.size() || !std::isfinite(d)) {
        v.clear();
        break;
      }
      v.push_back(d);
    }
    if (v.empty() && header_allowed) {  // a header: the first line that is not a comment
      header_allowed = false;
      continue;
    }
    header_allowed = false;
    if (v.size() != 2) fail(field, where + " ('" + (line.size() > 60 ? line.substr(0, 60) + "..." : line) + "')", "two finite numbers: station (m), value");
    if (!p.stations.empty() && v[0] <= p.stations.back())
      fail(field, where + " (station " + fmt(v[0]) + " m)", "stations strictly increasing (previous " + fmt(p.stations.back()) + " m)");
    if (v[1] < lo || v[1] > hi) fail(field, where + " (value " + fmt(v[1]) + ")", "values in [" + fmt(lo) + ", " + fmt(hi) + "]");
    p.stations.push_back(v[0]);
    p.values.push_back(v[1]);
  }
  if (p.stations.size() < 2) fail(field, "'" + path + "' (" + std::to_string(p.stations.size()) + " rows)", "at least two rows: station (m), value");
  return p;
}

// A profile given as `csv: FILE` or as `stations: [..]` with `<values>: [..]`.
LineProfile read_profile(Reader& r, const std::string& values_key, double lo, double hi, const std::string& base_dir) {
  LineProfile p;
  if (r.has("csv")) {
    if (r.has("stations") || r.has(values_key))
      fail(r.field("csv"), "(given with stations)", "either csv or stations and " + values_key);
    std::string path = r.text("csv", "");
    if (!path.empty() && path[0] != '/' && !base_dir.empty()) path = base_dir + "/" + path;
    return read_profile_csv(r.field("csv"), path, lo, hi);
  }
  p.stations = r.numbers("stations", -1e7, 1e7);
  p.values = r.numbers(values_key, lo, hi);
  if (p.values.size() != p.stations.size())
    fail(r.field(values_key), "(" + std::to_string(p.values.size()) + " values)", "one per station (" + std::to_string(p.stations.size()) + ")");
  if (p.stations.size() < 2) fail(r.field("stations"), "(" + std::to_string(p.stations.size()) + " values)", "at least two stations");
  for (std::size_t i = 1; i < p.stations.size(); ++i)
    if (p.stations[i] <= p.stations[i - 1])
      fail(r.field("stations") + "[" + std::to_string(i) + "]", fmt(p.stations[i]), "strictly increasing (previous " + fmt(p.stations[i - 1]) + ")");
  return p;
}

// The random errors' seeds: one shared, and any of the droppers', supports' and stagger's own.
void read_imperfection_seeds(Reader& r, ImperfectionSpec& im) {
  const double seed = r.number("seed", 0.0, 9007199254740992.0, 0.0);
  if (seed != std::floor(seed)) fail("imperfections.seed", fmt(seed), "a whole number >= 0");
  im.seed = static_cast<std::uint64_t>(seed);
  for (const char* k : {"dropper_length_seed", "support_height_seed", "stagger_seed"}) {
    if (!r.has(k)) continue;
    const double v = r.number(k, 0.0, 9007199254740992.0);
    if (v != std::floor(v)) fail(std::string("imperfections.") + k, fmt(v), "a whole number >= 0");
    const std::string key(k);
    (key == "dropper_length_seed"   ? im.dropper_length_seed
     : key == "support_height_seed" ? im.support_height_seed
                                    : im.stagger_seed) = static_cast<std::uint64_t>(v);
  }
}

void read_point_masses(Reader& r, ImperfectionSpec& im) {
  if (!r.has("point_masses")) return;
  const YAML::Node pm = r.child("point_masses");
  if (!pm.IsSequence()) fail("imperfections.point_masses", "(not a list)", "a list of {station: m, mass: kg}");
  for (std::size_t i = 0; i < pm.size(); ++i) {
    Reader q(pm[i], "imperfections.point_masses[" + std::to_string(i) + "]");
    PointMassSpec p;
    p.station = q.number("station", 0.0, 1e7);
    p.mass = q.number("mass", 0.0, 1000.0, std::nullopt, true);
    q.finish();
    im.point_masses.push_back(p);
  }
}

void read_irregularity(Reader& r, ImperfectionSpec& im, const std::string& base_dir) {
  if (!r.has("contact_wire_irregularity")) return;
  Reader q(r.child("contact_wire_irregularity"), "imperfections.contact_wire_irregularity");
  IrregularitySpec& ir = im.contact_wire_irregularity;
  const bool measured = q.has("csv") || q.has("stations") || q.has("deviations");
  if (measured) {
    for (const char* k : {"rms", "wavelength_min", "wavelength_max", "exponent", "seed"})
      if (q.has(k)) fail(q.field(k), "(given with a measured profile)", "either a profile (csv or stations/deviations) or a random one (rms, wavelengths)");
    ir.profile = read_profile(q, "deviations", -0.5, 0.5, base_dir);
  } else {
    ir.rms = q.number("rms", 0.0, 0.1, std::nullopt, true);
    ir.wavelength_min = q.number("wavelength_min", 0.0, 1e4, std::nullopt, true);
    ir.wavelength_max = q.number("wavelength_max", 0.0, 1e4, std::nullopt, true);
    if (ir.wavelength_max <= ir.wavelength_min)
      fail(q.field("wavelength_max"), fmt(ir.wavelength_max), "above wavelength_min (" + fmt(ir.wavelength_min) + " m)");
    ir.exponent = q.number("exponent", 0.0, 6.0, 2.0);
    if (q.has("seed")) {
      const double v = q.number("seed", 0.0, 9007199254740992.0);
      if (v != std::floor(v)) fail(q.field("seed"), fmt(v), "a whole number >= 0");
      ir.seed = static_cast<std::uint64_t>(v);
    }
  }
  q.finish();
}

void read_wear(Reader& r, ImperfectionSpec& im, const std::string& base_dir) {
  if (!r.has("contact_wire_wear")) return;
  Reader q(r.child("contact_wire_wear"), "imperfections.contact_wire_wear");
  WearSpec& w = im.contact_wire_wear;
  // Standards replace a contact wire at 20-30 % wear; 0.5 leaves room for studies beyond.
  const double max_loss = 0.5;
  if (q.has("csv") || q.has("stations")) {
    w.section_loss = read_profile(q, "section_loss", 0.0, max_loss, base_dir);
  } else {
    w.uniform = q.number("section_loss", 0.0, max_loss);
  }
  w.ei_exponent = q.number("ei_exponent", 0.0, 4.0, 2.0);
  q.finish();
}

}  // namespace

void read_imperfections(Reader& top, Scene& s, const std::string& base_dir) {
  if (!top.has("imperfections")) return;
  Reader r(top.child("imperfections"), "imperfections");
  ImperfectionSpec& im = s.imperfections;
  read_imperfection_seeds(r, im);
  im.dropper_length_std = r.number("dropper_length_std", 0.0, 0.1, 0.0);
  if (r.has("dropper_length_errors")) im.dropper_length_errors = r.numbers("dropper_length_errors", -0.5, 0.5);
  if (im.dropper_length_std > 0.0 && !im.dropper_length_errors.empty())
    fail("imperfections.dropper_length_errors", "(given with dropper_length_std)", "give either errors or a std");
  im.support_height_std = r.number("support_height_std", 0.0, 0.2, 0.0);
  if (r.has("support_height_errors")) im.support_height_errors = r.numbers("support_height_errors", -0.5, 0.5);
  if (im.support_height_std > 0.0 && !im.support_height_errors.empty())
    fail("imperfections.support_height_errors", "(given with support_height_std)", "give either errors or a std");
  im.stagger_std = r.number("stagger_std", 0.0, 0.2, 0.0);
  if (r.has("stagger_errors")) im.stagger_errors = r.numbers("stagger_errors", -0.5, 0.5);
  if (im.stagger_std > 0.0 && !im.stagger_errors.empty())
    fail("imperfections.stagger_errors", "(given with stagger_std)", "give either errors or a std");
  read_point_masses(r, im);
  read_irregularity(r, im, base_dir);
  read_wear(r, im, base_dir);
  r.finish();
}

}  // namespace catenary_sim
