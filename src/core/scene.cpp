#include "catenary_sim/core/scene.hpp"

#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <limits>
#include <set>
#include <sstream>

namespace catenary_sim {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

std::string fmt(double v) {
  std::ostringstream s;
  s.precision(10);
  s << v;
  return s.str();
}

[[noreturn]] void fail(const std::string& field, const std::string& value, const std::string& allowed) {
  throw SceneError("scene field '" + field + "' = " + value + ": " + allowed);
}

// Reads the YAML maps strictly: unknown keys are errors, so that a typo never silently falls
// back to a default.
class Reader {
 public:
  Reader(const YAML::Node& node, std::string path) : node_(node), path_(std::move(path)) {
    if (node_ && !node_.IsNull() && !node_.IsMap()) fail(path_, "(not a map)", "expected a map of fields");
  }

  std::string field(const std::string& key) const { return path_.empty() ? key : path_ + "." + key; }
  bool has(const std::string& key) {
    used_.insert(key);
    return node_ && node_.IsMap() && node_[key] && !node_[key].IsNull();
  }
  YAML::Node child(const std::string& key) {
    used_.insert(key);
    return node_ && node_.IsMap() ? node_[key] : YAML::Node();
  }

  double number(const std::string& key, double lo, double hi, std::optional<double> def = std::nullopt,
                bool lo_open = false) {
    if (!has(key)) {
      if (def) return *def;
      fail(field(key), "(missing)", "required, a number in " + range(lo, hi, lo_open));
    }
    return parse_number(node_[key], field(key), lo, hi, lo_open);
  }

  std::vector<double> numbers(const std::string& key, double lo, double hi, bool lo_open = false) {
    if (!has(key)) fail(field(key), "(missing)", "required, a list of numbers in " + range(lo, hi, lo_open));
    const YAML::Node n = node_[key];
    if (!n.IsSequence()) fail(field(key), "(not a list)", "a list of numbers in " + range(lo, hi, lo_open));
    std::vector<double> out;
    for (std::size_t i = 0; i < n.size(); ++i)
      out.push_back(parse_number(n[i], field(key) + "[" + std::to_string(i) + "]", lo, hi, lo_open));
    return out;
  }

  std::string text(const std::string& key, const std::string& def) {
    if (!has(key)) return def;
    const YAML::Node n = node_[key];
    if (!n.IsScalar()) fail(field(key), "(not a scalar)", "a string");
    return n.as<std::string>();
  }

  void finish() const {
    if (!node_ || !node_.IsMap()) return;
    for (const auto& kv : node_) {
      const std::string key = kv.first.as<std::string>();
      if (!used_.count(key)) fail(field(key), "(unknown field)", "not a field of '" + (path_.empty() ? "scene" : path_) + "'; check the spelling against README.md");
    }
  }

  static std::string range(double lo, double hi, bool lo_open) {
    std::string s = lo_open ? "(" : "[";
    s += std::isinf(lo) ? "-inf" : fmt(lo);
    s += ", ";
    s += std::isinf(hi) ? "inf)" : fmt(hi) + "]";
    return s;
  }

  static double parse_number(const YAML::Node& n, const std::string& field, double lo, double hi, bool lo_open) {
    if (!n.IsScalar()) fail(field, "(not a scalar)", "a number in " + range(lo, hi, lo_open));
    const std::string raw = n.as<std::string>();
    double v = 0.0;
    try {
      v = n.as<double>();
    } catch (const YAML::Exception&) {
      fail(field, "'" + raw + "'", "a number in " + range(lo, hi, lo_open));
    }
    if (!std::isfinite(v) || v < lo || v > hi || (lo_open && v == lo))
      fail(field, raw, "allowed range " + range(lo, hi, lo_open));
    return v;
  }

 private:
  YAML::Node node_;
  std::string path_;
  std::set<std::string> used_;
};

WireSpec read_wire(Reader& r) {
  WireSpec w;
  w.linear_mass = r.number("linear_mass", 0.0, 100.0, std::nullopt, true);
  w.bending_stiffness = r.number("bending_stiffness", 0.0, 1e6, 0.0);
  w.tension = r.number("tension", 0.0, 1e6, std::nullopt, true);
  return w;
}

SupportSpec read_support(Reader& r) {
  SupportSpec s;
  s.stiffness = r.number("stiffness", 0.0, 1e10, std::nullopt, true);
  s.mass = r.number("mass", 0.0, 1000.0, 0.0);
  r.finish();
  return s;
}

PantographSpec read_pantograph(const YAML::Node& node, const std::string& path, std::size_t index) {
  Reader r(node, path);
  PantographSpec p;
  p.name = r.text("name", "pantograph_" + std::to_string(index));
  p.position = r.number("position", 0.0, 10000.0, 0.0);
  const std::string type = r.text("type", "lumped");
  if (type == "lumped") {
    p.moving_force = false;
  } else if (type == "moving_force") {
    p.moving_force = true;
  } else {
    fail(r.field("type"), "'" + type + "'", "one of: lumped, moving_force");
  }
  p.static_uplift = r.number("static_uplift", 0.0, 2000.0);
  p.aero_coefficient = r.number("aero_coefficient", -1.0, 1.0, 0.0);
  if (!p.moving_force) {
    p.masses = r.numbers("masses", 0.0, 1000.0, true);
    p.stiffness = r.numbers("stiffness", 0.0, 1e8);
    p.damping = r.has("damping") ? r.numbers("damping", 0.0, 1e6) : std::vector<double>(p.masses.size(), 0.0);
    if (p.masses.empty()) fail(r.field("masses"), "[]", "at least one mass (the head first)");
    if (p.stiffness.size() != p.masses.size())
      fail(r.field("stiffness"), std::to_string(p.stiffness.size()) + " values",
           "one per mass (" + std::to_string(p.masses.size()) + "): the spring below each mass, the last to the roof");
    if (p.damping.size() != p.masses.size())
      fail(r.field("damping"), std::to_string(p.damping.size()) + " values",
           "one per mass (" + std::to_string(p.masses.size()) + ")");
    for (std::size_t i = 0; i + 1 < p.stiffness.size(); ++i)
      if (p.stiffness[i] <= 0.0)
        fail(r.field("stiffness") + "[" + std::to_string(i) + "]", fmt(p.stiffness[i]),
             "must be > 0 between two masses (only the last, to the roof, may be 0)");
  } else {
    for (const char* k : {"masses", "stiffness", "damping"})
      if (r.has(k)) fail(r.field(k), "(given)", "not allowed for type moving_force (it has no masses)");
  }
  if (r.has("collectors")) {
    const YAML::Node cs = r.child("collectors");
    if (!cs.IsSequence() || cs.size() == 0) fail(r.field("collectors"), "(not a non-empty list)", "a list of {offset: m}");
    for (std::size_t i = 0; i < cs.size(); ++i) {
      Reader c(cs[i], r.field("collectors") + "[" + std::to_string(i) + "]");
      CollectorSpec col;
      col.offset = c.number("offset", -5.0, 5.0, 0.0);
      c.finish();
      p.collectors.push_back(col);
    }
  } else {
    p.collectors.push_back(CollectorSpec{});
  }
  r.finish();
  return p;
}

}  // namespace

double Scene::line_length() const {
  double s = 0.0;
  for (double l : spans) s += l;
  return s;
}

int Scene::analysis_first() const {
  const int n = static_cast<int>(spans.size());
  return output.analysis_first_span ? *output.analysis_first_span : (n > 4 ? 2 : 0);
}

int Scene::analysis_last() const {
  const int n = static_cast<int>(spans.size());
  return output.analysis_last_span ? *output.analysis_last_span : (n > 4 ? n - 2 : n);
}

Scene scene_from_yaml(const YAML::Node& root) {
  if (!root || !root.IsMap()) throw SceneError("scene: the document must be a YAML map of sections (line, contact_wire, ...)");
  Reader top(root, "");
  Scene s;
  s.name = top.text("name", "scene");
  s.gravity = top.number("gravity", 0.0, 100.0, 9.81);

  {
    Reader r(top.child("line"), "line");
    if (!top.has("line")) fail("line", "(missing)", "required section with spans or span_length and span_count");
    s.contact_wire_height = r.number("contact_wire_height", 0.0, 100.0, 5.3);
    s.encumbrance = r.number("encumbrance", 0.0, 10.0, 1.2, true);
    if (r.has("spans")) {
      if (r.has("span_length") || r.has("span_count"))
        fail("line.spans", "(given with span_length/span_count)", "give either spans or span_length and span_count");
      s.spans = r.numbers("spans", 0.5, 500.0);
    } else {
      const double len = r.number("span_length", 0.5, 500.0);
      const double count = r.number("span_count", 1.0, 10000.0);
      if (count != std::floor(count)) fail("line.span_count", fmt(count), "a whole number >= 1");
      s.spans.assign(static_cast<std::size_t>(count), len);
    }
    if (s.spans.empty()) fail("line.spans", "[]", "at least one span");
    r.finish();
  }
  {
    if (!top.has("contact_wire")) fail("contact_wire", "(missing)", "required section");
    Reader r(top.child("contact_wire"), "contact_wire");
    static_cast<WireSpec&>(s.contact_wire) = read_wire(r);
    s.contact_wire.presag = r.number("presag", -1.0, 1.0, 0.0);
    r.finish();
  }
  if (top.has("messenger")) {
    Reader r(top.child("messenger"), "messenger");
    s.messenger = read_wire(r);
    r.finish();
  }
  if (top.has("droppers")) {
    Reader r(top.child("droppers"), "droppers");
    DropperSpec d;
    if (r.has("positions") == r.has("positions_per_span"))
      fail("droppers.positions", "(both or neither given)", "give positions (same in every span) or positions_per_span");
    if (r.has("positions")) {
      d.positions.assign(s.spans.size(), r.numbers("positions", 0.0, 500.0, true));
    } else {
      const YAML::Node per = r.child("positions_per_span");
      if (!per.IsSequence() || per.size() != s.spans.size())
        fail("droppers.positions_per_span", "(" + std::to_string(per.IsSequence() ? per.size() : 0) + " entries)",
             "one list per span (" + std::to_string(s.spans.size()) + ")");
      for (std::size_t i = 0; i < per.size(); ++i) {
        std::vector<double> v;
        if (!per[i].IsSequence()) fail("droppers.positions_per_span[" + std::to_string(i) + "]", "(not a list)", "a list of positions in m");
        for (std::size_t j = 0; j < per[i].size(); ++j)
          v.push_back(Reader::parse_number(per[i][j], "droppers.positions_per_span[" + std::to_string(i) + "][" + std::to_string(j) + "]", 0.0, 500.0, true));
        d.positions.push_back(v);
      }
    }
    d.axial_stiffness = r.number("axial_stiffness", 0.0, 1e10, std::nullopt, true);
    d.linear_mass = r.number("linear_mass", 0.0, 10.0, 0.0);
    d.clamp_mass_contact = r.number("clamp_mass_contact", 0.0, 100.0, 0.0);
    d.clamp_mass_messenger = r.number("clamp_mass_messenger", 0.0, 100.0, 0.0);
    r.finish();
    s.droppers = d;
  }
  if (top.has("steady_arms")) {
    Reader r(top.child("steady_arms"), "steady_arms");
    s.steady_arms = read_support(r);
  }
  if (top.has("messenger_supports")) {
    Reader r(top.child("messenger_supports"), "messenger_supports");
    s.messenger_supports = read_support(r);
  }
  if (top.has("damping")) {
    Reader r(top.child("damping"), "damping");
    s.rayleigh_alpha = r.number("alpha", 0.0, 100.0, 0.0);
    s.rayleigh_beta = r.number("beta", 0.0, 0.1, 0.0);
    r.finish();
  }
  if (top.has("contact")) {
    Reader r(top.child("contact"), "contact");
    s.contact.stiffness = r.number("stiffness", 0.0, 1e9, 50000.0, true);
    s.contact.rub_length = r.number("rub_length", 0.0, 5.0, 0.0);
    r.finish();
  }
  if (top.has("pantographs")) {
    const YAML::Node ps = top.child("pantographs");
    if (!ps.IsSequence()) fail("pantographs", "(not a list)", "a list of pantographs");
    for (std::size_t i = 0; i < ps.size(); ++i)
      s.pantographs.push_back(read_pantograph(ps[i], "pantographs[" + std::to_string(i) + "]", i));
  }
  if (top.has("train")) {
    Reader r(top.child("train"), "train");
    if (r.has("speed") && r.has("speed_kmh")) fail("train.speed", "(given with speed_kmh)", "give either speed (m/s) or speed_kmh");
    if (r.has("speed_kmh")) s.train_speed = r.number("speed_kmh", 0.0, 1000.0) / 3.6;
    else s.train_speed = r.number("speed", 0.0, 300.0, 0.0);
    if (r.has("start")) s.train_start = r.number("start", -kInf, kInf);
    if (r.has("end")) s.train_end = r.number("end", -kInf, kInf);
    r.finish();
  }
  if (top.has("numerics")) {
    Reader r(top.child("numerics"), "numerics");
    s.numerics.element_length = r.number("element_length", 0.01, 10.0, 0.25);
    if (r.has("dt")) {
      const YAML::Node n = r.child("dt");
      if (!(n.IsScalar() && n.as<std::string>() == "auto"))
        s.numerics.dt = Reader::parse_number(n, "numerics.dt", 0.0, 0.1, true);
    }
    s.numerics.safety_factor = r.number("safety_factor", 0.0, 1.0, 0.9, true);
    const std::string rot = r.text("rotary_inertia", "condensed");
    if (rot == "condensed") s.numerics.rotary_inertia = RotaryInertia::kCondensed;
    else if (rot == "lumped") s.numerics.rotary_inertia = RotaryInertia::kLumped;
    else fail("numerics.rotary_inertia", "'" + rot + "'", "one of: condensed (massless rotations, statically condensed), lumped (HRZ rotary inertia)");
    s.numerics.divergence_limit = r.number("divergence_limit", 0.0, 1000.0, 5.0, true);
    r.finish();
  }
  if (top.has("output")) {
    Reader r(top.child("output"), "output");
    if (r.has("analysis_spans")) {
      const std::vector<double> a = r.numbers("analysis_spans", 0.0, 1e6);
      if (a.size() != 2 || a[0] != std::floor(a[0]) || a[1] != std::floor(a[1]))
        fail("output.analysis_spans", "(" + std::to_string(a.size()) + " values)", "two whole span indices [first, last)");
      s.output.analysis_first_span = static_cast<int>(a[0]);
      s.output.analysis_last_span = static_cast<int>(a[1]);
    }
    s.output.filter_cutoff = r.number("filter_cutoff", 0.0, 10000.0, 20.0, true);
    s.output.sample_rate = r.number("sample_rate", 0.0, 1e6, 0.0);
    r.finish();
  }
  top.finish();
  validate(s);
  return s;
}

void validate(const Scene& s) {
  const double line = s.line_length();
  if (s.droppers && !s.messenger)
    fail("droppers", "(given)", "droppers hang the contact wire from a messenger: add a messenger section or remove droppers");
  if (s.messenger_supports && !s.messenger)
    fail("messenger_supports", "(given)", "needs a messenger section");
  if (s.contact_wire.presag != 0.0 && !s.droppers)
    fail("contact_wire.presag", fmt(s.contact_wire.presag), "0 without droppers (the presag is set by the dropper lengths)");
  if (s.droppers) {
    if (s.droppers->positions.size() != s.spans.size())
      fail("droppers.positions_per_span", std::to_string(s.droppers->positions.size()) + " lists", "one per span");
    for (std::size_t i = 0; i < s.spans.size(); ++i) {
      const auto& p = s.droppers->positions[i];
      for (std::size_t j = 0; j < p.size(); ++j) {
        const std::string f = "droppers.positions (span " + std::to_string(i) + ", dropper " + std::to_string(j) + ")";
        if (p[j] <= 0.0 || p[j] >= s.spans[i])
          fail(f, fmt(p[j]), "strictly inside the span (0, " + fmt(s.spans[i]) + ") m");
        if (j > 0 && p[j] <= p[j - 1]) fail(f, fmt(p[j]), "increasing along the span (previous " + fmt(p[j - 1]) + ")");
      }
    }
  }
  std::set<std::string> names;
  for (std::size_t i = 0; i < s.pantographs.size(); ++i) {
    const auto& p = s.pantographs[i];
    if (!names.insert(p.name).second)
      fail("pantographs[" + std::to_string(i) + "].name", "'" + p.name + "'", "unique among pantographs");
  }
  const int a0 = s.analysis_first(), a1 = s.analysis_last();
  if (a0 < 0 || a1 > static_cast<int>(s.spans.size()) || a0 >= a1)
    fail("output.analysis_spans", "[" + std::to_string(a0) + ", " + std::to_string(a1) + "]",
         "0 <= first < last <= span count (" + std::to_string(s.spans.size()) + ")");
  if (s.numerics.element_length > *std::min_element(s.spans.begin(), s.spans.end()))
    fail("numerics.element_length", fmt(s.numerics.element_length), "at most the shortest span");
  if (s.train_start && s.train_end && *s.train_end < *s.train_start)
    fail("train.end", fmt(*s.train_end), ">= train.start (" + fmt(*s.train_start) + ")");
  if (s.train_end && *s.train_end > line + 1e-9)
    fail("train.end", fmt(*s.train_end), "at most the line length " + fmt(line) + " m");
}

namespace {

YAML::Node apply_override(YAML::Node root, const std::string& assignment) {
  const auto eq = assignment.find('=');
  if (eq == std::string::npos || eq == 0)
    throw SceneError("override '" + assignment + "': expected key.path=value, e.g. numerics.element_length=0.125");
  const std::string key = assignment.substr(0, eq);
  YAML::Node value;
  try {
    value = YAML::Load(assignment.substr(eq + 1));
  } catch (const YAML::Exception& e) {
    throw SceneError("override '" + assignment + "': value is not valid YAML (" + e.what() + ")");
  }
  std::vector<std::string> parts;
  std::stringstream ss(key);
  for (std::string p; std::getline(ss, p, '.');) parts.push_back(p);
  // Walk down, creating maps as needed; numeric parts index sequences.
  std::vector<YAML::Node> chain{root};
  for (std::size_t i = 0; i + 1 < parts.size(); ++i) {
    YAML::Node cur = chain.back();
    const bool is_index = !parts[i].empty() && parts[i].find_first_not_of("0123456789") == std::string::npos;
    if (cur.IsSequence() && is_index) {
      const std::size_t idx = std::stoul(parts[i]);
      if (idx >= cur.size())
        throw SceneError("override '" + assignment + "': index " + parts[i] + " out of range (" + std::to_string(cur.size()) + " entries)");
      chain.push_back(cur[idx]);
    } else {
      if (!cur[parts[i]]) cur[parts[i]] = YAML::Node(YAML::NodeType::Map);
      chain.push_back(cur[parts[i]]);
    }
  }
  YAML::Node last = chain.back();
  const std::string& leaf = parts.back();
  const bool is_index = !leaf.empty() && leaf.find_first_not_of("0123456789") == std::string::npos;
  if (last.IsSequence() && is_index) {
    const std::size_t idx = std::stoul(leaf);
    if (idx >= last.size())
      throw SceneError("override '" + assignment + "': index " + leaf + " out of range");
    last[idx] = value;
  } else {
    last[leaf] = value;
  }
  return root;
}

Scene load_from_node(YAML::Node root, const std::vector<std::string>& overrides) {
  if (!root || !root.IsMap()) throw SceneError("scene: the document must be a YAML map of sections (line, contact_wire, ...)");
  for (const auto& o : overrides) root = apply_override(root, o);
  return scene_from_yaml(root);
}

}  // namespace

Scene load_scene_string(const std::string& yaml, const std::vector<std::string>& overrides) {
  YAML::Node root;
  try {
    root = YAML::Load(yaml);
  } catch (const YAML::Exception& e) {
    throw SceneError(std::string("scene: not valid YAML: ") + e.what());
  }
  return load_from_node(root, overrides);
}

Scene load_scene_file(const std::string& path, const std::vector<std::string>& overrides) {
  std::ifstream in(path);
  if (!in) throw SceneError("scene file '" + path + "': cannot be opened");
  std::stringstream buf;
  buf << in.rdbuf();
  try {
    return load_scene_string(buf.str(), overrides);
  } catch (const SceneError& e) {
    throw SceneError(path + ": " + e.what());
  }
}

}  // namespace catenary_sim
