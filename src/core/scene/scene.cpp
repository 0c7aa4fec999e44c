#include "catenary_sim/core/scene/scene.hpp"

#include <sys/stat.h>
#include <yaml-cpp/eventhandler.h>
#include <yaml-cpp/yaml.h>

#include <cerrno>
#include <cstring>

#include <algorithm>
#include <cmath>
#include <numeric>
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

// 4 significant digits, for limits computed from the scene.
std::string fmt4(double v) {
  std::ostringstream s;
  s.precision(4);
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

  bool boolean(const std::string& key, bool def) {
    if (!has(key)) return def;
    const YAML::Node n = node_[key];
    bool v = false;
    if (!n.IsScalar() || !YAML::convert<bool>::decode(n, v))
      fail(field(key), n.IsScalar() ? "'" + n.as<std::string>() + "'" : "(not a scalar)", "true or false");
    return v;
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
      if (!used_.count(key)) fail(field(key), "(unknown field)", "not a field of '" + (path_.empty() ? "scene" : path_) + "'; check the spelling against docs/scene_reference.md");
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

const char* kind_of(const YAML::Node& n) {
  switch (n.Type()) {
    case YAML::NodeType::Sequence: return "a list";
    case YAML::NodeType::Map: return "a map";
    case YAML::NodeType::Null: return "empty";
    default: return "a value";
  }
}

std::string where(const YAML::Node& n) {
  const YAML::Mark m = n.Mark();
  if (m.line < 0) return "";
  return " (line " + std::to_string(m.line + 1) + ", column " + std::to_string(m.column + 1) + ")";
}

// The whole document before any field is read: every key a plain name given once, no empty value.
// yaml-cpp keeps the first of two equal keys and throws on a non-scalar key only when it is read,
// so both would otherwise be a silent wrong value or an abort.
void check_document(const YAML::Node& n, const std::string& path) {
  if (n.IsMap()) {
    std::set<std::string> seen;
    for (const auto& kv : n) {
      if (!kv.first.IsScalar())
        throw SceneError("scene: a key" + where(kv.first) + (path.empty() ? "" : " in '" + path + "'") + " is " +
                         kind_of(kv.first) + "; keys are plain field names");
      const std::string key = kv.first.Scalar();
      const std::string f = path.empty() ? key : path + "." + key;
      if (!seen.insert(key).second) fail(f, "(given twice" + where(kv.first) + ")", "each field once");
      if (kv.second.IsNull())
        fail(f, "(empty" + where(kv.first) + ")", "a value; remove the field to use its default");
      check_document(kv.second, f);
    }
  } else if (n.IsSequence()) {
    for (std::size_t i = 0; i < n.size(); ++i) check_document(n[i], path + "[" + std::to_string(i) + "]");
  }
}

// The YAML text before it is built into nodes. yaml-cpp shares an aliased node instead of copying
// it, so a tree walk visits it once per alias: an alias inside its own anchor is a cycle (the walk
// never ends) and nested aliases multiply (9 levels of 9 aliases: 9^9 visits from 2.8 kB). Counts
// every node as the walk will visit it (an alias adds its anchor's whole expanded size) and
// refuses a cycle, an expansion beyond kMaxAliasExpansion, and a second document (YAML::Load
// reads the first only, so the rest would be silently ignored).
class DocumentShape : public YAML::EventHandler {
 public:
  explicit DocumentShape(std::string what) : what_(std::move(what)) {}
  int documents = 0;

  void OnDocumentStart(const YAML::Mark& mark) override {
    start_ = mark;
    content_ = false;
  }
  void OnDocumentEnd() override {
    if (!content_) return;  // an empty document (a trailing '---') holds nothing to ignore
    if (++documents > 1)
      throw SceneError(what_ + ": a second YAML document" + at(start_) +
                       "; a scene is one document (remove the '---' and what follows, or merge it into the first)");
  }
  void OnNull(const YAML::Mark&, YAML::anchor_t anchor) override {
    if (stack_.empty() && anchor == YAML::NullAnchor) return;  // the empty document itself
    node(anchor, 1);
  }
  void OnScalar(const YAML::Mark&, const std::string&, YAML::anchor_t anchor, const std::string&) override { node(anchor, 1); }
  void OnAlias(const YAML::Mark& mark, YAML::anchor_t anchor) override {
    const std::string name = anchor < names_.size() && !names_[anchor].empty() ? names_[anchor] : std::to_string(anchor);
    for (const Open& o : stack_)
      if (o.anchor == anchor)
        throw SceneError(what_ + ": the alias '*" + name + "'" + at(mark) + " lies inside its own anchor '&" + name +
                         "': a node that contains itself, which no scene field can hold; write the value out");
    const std::uint64_t size = anchor < sizes_.size() ? sizes_[anchor] : 1;
    expanded_ += size;
    if (expanded_ > kMaxAliasExpansion)
      throw SceneError(what_ + ": the aliases expand to more than " + std::to_string(kMaxAliasExpansion) +
                       " nodes (refused at '*" + name + "'" + at(mark) +
                       "); anchors and aliases are allowed for repeated values, not for nesting repeats of repeats");
    add(size);
  }
  void OnSequenceStart(const YAML::Mark&, const std::string&, YAML::anchor_t anchor, YAML::EmitterStyle::value) override {
    open(anchor);
  }
  void OnSequenceEnd() override { close(); }
  void OnMapStart(const YAML::Mark&, const std::string&, YAML::anchor_t anchor, YAML::EmitterStyle::value) override {
    open(anchor);
  }
  void OnMapEnd() override { close(); }
  void OnAnchor(const YAML::Mark&, const std::string& name) override { pending_name_ = name; }

 private:
  struct Open {
    YAML::anchor_t anchor;
    std::uint64_t size;
  };
  static std::string at(const YAML::Mark& m) {
    return m.line < 0 ? "" : " (line " + std::to_string(m.line + 1) + ", column " + std::to_string(m.column + 1) + ")";
  }
  void name(YAML::anchor_t anchor) {
    if (anchor == YAML::NullAnchor) return;
    if (names_.size() <= anchor) names_.resize(anchor + 1);
    names_[anchor] = pending_name_;
  }
  void add(std::uint64_t size) {
    content_ = true;
    if (!stack_.empty()) stack_.back().size += size;
  }
  void node(YAML::anchor_t anchor, std::uint64_t size) {
    name(anchor);
    record(anchor, size);
    add(size);
  }
  void record(YAML::anchor_t anchor, std::uint64_t size) {
    if (anchor == YAML::NullAnchor) return;
    if (sizes_.size() <= anchor) sizes_.resize(anchor + 1, 1);
    sizes_[anchor] = size;
  }
  void open(YAML::anchor_t anchor) {
    name(anchor);
    content_ = true;
    stack_.push_back({anchor, 1});
  }
  void close() {
    const Open o = stack_.back();
    stack_.pop_back();
    record(o.anchor, o.size);
    add(o.size);
  }

  std::string what_;
  YAML::Mark start_;
  bool content_ = false;
  std::vector<Open> stack_;
  std::vector<std::uint64_t> sizes_;
  std::vector<std::string> names_;
  std::string pending_name_;
  std::uint64_t expanded_ = 0;
};

// Throws SceneError (naming `what`) for YAML that is not one acyclic document of bounded expansion.
void check_yaml_shape(const std::string& text, const std::string& what) {
  std::istringstream in(text);
  YAML::Parser parser(in);
  DocumentShape shape(what);
  try {
    while (parser.HandleNextDocument(shape)) {
    }
  } catch (const YAML::Exception& e) {
    throw SceneError(what + ": not valid YAML: " + e.what());
  }
}

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
  } else if (type == "external") {
    p.moving_force = true;
    p.external = true;
  } else {
    fail(r.field("type"), "'" + type + "'", "one of: lumped, moving_force, external (hardware in the loop)");
  }
  p.static_uplift = r.number("static_uplift", 0.0, 2000.0);
  p.aero_coefficient = r.number("aero_coefficient", -1.0, 1.0, 0.0);
  if (r.has("aero_coefficient_trailing")) p.aero_coefficient_trailing = r.number("aero_coefficient_trailing", -1.0, 1.0);
  const std::string knee = r.text("knee", "leading");
  if (knee != "leading" && knee != "trailing")
    fail(r.field("knee"), "'" + knee + "'", "leading or trailing (the frame's knee in the direction of travel)");
  p.knee_trailing = knee == "trailing";
  if (r.has("target_mean_force")) {
    const YAML::Node t = r.child("target_mean_force");
    Reader tr(t, r.field("target_mean_force"));
    TargetMeanForce target;
    const std::string unit = tr.text("speed_unit", "m/s");
    if (unit != "m/s" && unit != "km/h")
      fail(tr.field("speed_unit"), "'" + unit + "'", "m/s or km/h (the unit of v in Fm(v) = a v^2 + b)");
    target.speed_kmh = unit == "km/h";
    // a: up to 1 N s^2/m^2 (1/12.96 of that per (km/h)^2), about 10 times EN 50367's curves.
    target.a = tr.number("a", 0.0, target.speed_kmh ? 1.0 / 12.96 : 1.0);
    target.b = tr.number("b", 0.0, 2000.0);
    if (tr.has("tolerance")) target.tolerance = tr.number("tolerance", 0.0, 2000.0);
    tr.finish();
    p.target_mean_force = target;
  }
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
      if (r.has(k)) fail(r.field(k), "(given)", "not allowed for type " + type + " (it has no masses)");
  }
  auto read_collectors = [](Reader& r, std::vector<CollectorSpec>& out) {
    if (!r.has("collectors")) {
      out.push_back(CollectorSpec{});
      return;
    }
    const YAML::Node cs = r.child("collectors");
    if (!cs.IsSequence() || cs.size() == 0) fail(r.field("collectors"), "(not a non-empty list)", "a list of {offset: m, working_width: m}");
    for (std::size_t i = 0; i < cs.size(); ++i) {
      Reader c(cs[i], r.field("collectors") + "[" + std::to_string(i) + "]");
      CollectorSpec col;
      col.offset = c.number("offset", -5.0, 5.0, 0.0);
      if (c.has("working_width")) col.working_width = c.number("working_width", 0.0, 5.0, std::nullopt, true);
      c.finish();
      out.push_back(col);
    }
  };
  if (r.has("heads")) {
    if (p.moving_force) fail(r.field("heads"), "(given)", "not allowed for type " + type + " (it has no masses)");
    if (r.has("collectors"))
      fail(r.field("collectors"), "(given with heads)", "collectors on the heads (heads[i].collectors) when heads are given");
    const YAML::Node hs = r.child("heads");
    if (!hs.IsSequence() || hs.size() == 0) fail(r.field("heads"), "(not a non-empty list)", "a list of heads");
    for (std::size_t i = 0; i < hs.size(); ++i) {
      Reader h(hs[i], r.field("heads") + "[" + std::to_string(i) + "]");
      HeadSpec head;
      head.mass = h.number("mass", 0.0, 1000.0, std::nullopt, true);
      if (!h.has("stiffness"))
        fail(h.field("stiffness"), "(missing)", "a suspension spring > 0 N/m to the top frame mass (a head without "
                                                "suspension is the chain's first mass: give no heads)");
      head.stiffness = h.number("stiffness", 0.0, 1e8, std::nullopt, true);
      head.damping = h.number("damping", 0.0, 1e6, 0.0);
      head.offset = h.number("offset", -5.0, 5.0, 0.0);
      head.length = h.number("length", 0.0, 5.0, 0.5, true);
      head.aero_coefficient = h.number("aero_coefficient", -1.0, 1.0, 0.0);
      if (h.has("aero_coefficient_trailing")) head.aero_coefficient_trailing = h.number("aero_coefficient_trailing", -1.0, 1.0);
      read_collectors(h, head.collectors);
      for (std::size_t c = 0; c < head.collectors.size(); ++c)
        if (std::fabs(head.collectors[c].offset) > 0.5 * head.length + 1e-12)
          fail(h.field("collectors") + "[" + std::to_string(c) + "].offset", fmt(head.collectors[c].offset),
               "within the head: |offset| <= length / 2 = " + fmt(0.5 * head.length) + " m from its centre");
      h.finish();
      p.heads.push_back(head);
    }
  } else {
    read_collectors(r, p.collectors);
  }
  r.finish();
  return p;
}

void read_spans(Reader& r, const std::string& path, std::vector<double>& spans) {
  if (r.has("spans")) {
    if (r.has("span_length") || r.has("span_count"))
      fail(path + ".spans", "(given with span_length/span_count)", "give either spans or span_length and span_count");
    spans = r.numbers("spans", 0.5, 500.0);
  } else {
    const double len = r.number("span_length", 0.5, 500.0);
    const double count = r.number("span_count", 1.0, 10000.0);
    if (count != std::floor(count)) fail(path + ".span_count", fmt(count), "a whole number >= 1");
    spans.assign(static_cast<std::size_t>(count), len);
  }
  if (spans.empty()) fail(path + ".spans", "[]", "at least one span");
}

// The wire, dropper and support parts of a section (or the scene's defaults when defaults is null).
void read_section_parts(Reader& r, const std::string& path, SectionSpec& sec, const SectionSpec* defaults) {
  const std::string pre = path.empty() ? "" : path + ".";
  if (r.has("contact_wire")) {
    Reader w(r.child("contact_wire"), pre + "contact_wire");
    static_cast<WireSpec&>(sec.contact_wire) = read_wire(w);
    sec.contact_wire.presag = w.number("presag", -1.0, 1.0, 0.0);
    w.finish();
  } else if (!defaults) {
    fail("contact_wire", "(missing)", "required section");
  }
  if (r.has("messenger")) {
    Reader w(r.child("messenger"), pre + "messenger");
    sec.messenger = read_wire(w);
    w.finish();
  }
  if (r.has("droppers")) {
    Reader d(r.child("droppers"), pre + "droppers");
    DropperSpec ds;
    const std::string f = pre + "droppers";
    if (d.has("positions") == d.has("positions_per_span"))
      fail(f + ".positions", "(both or neither given)", "give positions (same in every span) or positions_per_span");
    if (d.has("positions")) {
      ds.positions.assign(1, d.numbers("positions", 0.0, 500.0, true));  // expanded per span later
      if (ds.positions.front().empty())
        fail(f + ".positions", "[]", "at least one dropper position in m from the span start (or remove the droppers section)");
    } else {
      const YAML::Node per = d.child("positions_per_span");
      if (!per.IsSequence()) fail(f + ".positions_per_span", "(not a list)", "one list of positions per span");
      for (std::size_t i = 0; i < per.size(); ++i) {
        std::vector<double> v;
        const std::string fi = f + ".positions_per_span[" + std::to_string(i) + "]";
        if (!per[i].IsSequence()) fail(fi, "(not a list)", "a list of positions in m");
        for (std::size_t j = 0; j < per[i].size(); ++j)
          v.push_back(Reader::parse_number(per[i][j], fi + "[" + std::to_string(j) + "]", 0.0, 500.0, true));
        ds.positions.push_back(v);
      }
      ds.per_span = true;
      std::size_t count = 0;
      for (const auto& v : ds.positions) count += v.size();
      if (count == 0)
        fail(f + ".positions_per_span", "(no dropper in any span)", "at least one dropper position (or remove the droppers section)");
    }
    if (d.has("transition_positions")) ds.transition_positions = d.numbers("transition_positions", 0.0, 500.0, true);
    ds.axial_stiffness = d.number("axial_stiffness", 0.0, 1e10, std::nullopt, true);
    ds.linear_mass = d.number("linear_mass", 0.0, 10.0, 0.0);
    ds.clamp_mass_contact = d.number("clamp_mass_contact", 0.0, 100.0, 0.0);
    ds.clamp_mass_messenger = d.number("clamp_mass_messenger", 0.0, 100.0, 0.0);
    d.finish();
    sec.droppers = ds;
  }
  if (r.has("steady_arms")) {
    Reader a(r.child("steady_arms"), pre + "steady_arms");
    sec.steady_arms = read_support(a);
  }
  if (r.has("messenger_supports")) {
    Reader a(r.child("messenger_supports"), pre + "messenger_supports");
    sec.messenger_supports = read_support(a);
  }
}

// Section stations from the overlaps, dropper positions per span, and the line's spans (the union
// of every section's supports).
void resolve_line(Scene& s) {
  const int k = s.overlap ? s.overlap->spans : 0;
  std::vector<double> supports;
  for (std::size_t i = 0; i < s.sections.size(); ++i) {
    SectionSpec& sec = s.sections[i];
    const std::string path = s.sections.size() > 1 ? "sections[" + std::to_string(i) + "]" : "line";
    if (i > 0) {
      const SectionSpec& prev = s.sections[i - 1];
      if (static_cast<int>(prev.spans.size()) < k || static_cast<int>(sec.spans.size()) < k)
        fail(path + ".spans", std::to_string(sec.spans.size()) + " spans",
             "at least overlap.spans (" + std::to_string(k) + ") in every section");
      for (int j = 0; j < k; ++j) {
        const double a = prev.spans[prev.spans.size() - k + j], b = sec.spans[j];
        if (std::fabs(a - b) > 1e-9)
          fail(path + ".spans[" + std::to_string(j) + "]", fmt(b),
               "equal to the overlapping span of the previous section (" + fmt(a) + " m)");
      }
      double st = prev.start;
      for (std::size_t j = 0; j + k < prev.spans.size(); ++j) st += prev.spans[j];
      sec.start = st;
    }
    if (sec.droppers) {
      DropperSpec& d = *sec.droppers;
      const std::size_t n = sec.spans.size();
      if (d.per_span) {
        if (d.positions.size() != n)
          fail(path + ".droppers.positions_per_span", "(" + std::to_string(d.positions.size()) + " entries)",
               "one list per span (" + std::to_string(n) + ")");
      } else {
        const std::vector<double> common = d.positions.empty() ? std::vector<double>{} : d.positions.front();
        d.positions.assign(n, common);
        if (!d.transition_positions.empty()) {
          if (sec.last_span_transition) d.positions[n - 1] = d.transition_positions;
          if (sec.first_span_transition) {
            std::vector<double> mirrored;
            for (auto it = d.transition_positions.rbegin(); it != d.transition_positions.rend(); ++it)
              mirrored.push_back(sec.spans[0] - *it);
            d.positions[0] = mirrored;
          }
        }
      }
    }
    double x = sec.start;
    supports.push_back(x);
    for (double l : sec.spans) supports.push_back(x += l);
  }
  std::sort(supports.begin(), supports.end());
  s.spans.clear();
  for (std::size_t i = 1; i < supports.size(); ++i)
    if (supports[i] - supports[i - 1] > 1e-9) s.spans.push_back(supports[i] - supports[i - 1]);
  if (!s.sections.empty()) s.droppers = s.sections.front().droppers;
}

}  // namespace

double SectionSpec::length() const {
  double l = 0.0;
  for (double x : spans) l += x;
  return l;
}

std::string TrainSpeedLimit::text() const {
  std::ostringstream s;
  s.precision(4);
  if (below_wave_speed)
    s << "0 to below " << max << " m/s (" << max * 3.6 << " km/h), the contact wire's wave speed c = sqrt(T / rhoA): "
      << "a faster pass is supercritical (the wire's wave cannot run ahead of the pantograph), outside what the model "
         "covers; numerics.allow_supercritical: true runs it anyway";
  else
    s << "0 to " << max << " m/s (" << max * 3.6 << " km/h)";
  return s.str();
}

TrainSpeedLimit train_speed_limit(const Scene& scene) {
  TrainSpeedLimit l;
  l.wave_speed = std::numeric_limits<double>::infinity();
  for (const SectionSpec& sec : scene.sections)
    if (sec.contact_wire.linear_mass > 0.0)
      l.wave_speed = std::min(l.wave_speed, std::sqrt(sec.contact_wire.tension / sec.contact_wire.linear_mass));
  l.below_wave_speed = !scene.numerics.allow_supercritical && l.wave_speed <= kMaxTrainSpeed;
  l.max = l.below_wave_speed ? l.wave_speed : kMaxTrainSpeed;
  return l;
}

double wind_field_points(const Scene& scene) {
  if (!scene.wind || !scene.wind->turbulence) return 0.0;
  // The stretch whose points the field holds at once: a finite line's whole length; an endless
  // line generates its points as the block moves and holds the block's only, a block of spans
  // around the train and the lateral plane's gust lead, at most kMaxGustLead s of travel at the
  // speed ceiling (the block's exact length is the model's).
  double reach = scene.line_length();
  if (scene.endless) reach = 16.0 * scene.spans.front() + kMaxGustLead * kMaxTrainSpeed;
  return std::ceil(reach / scene.wind->turbulence->spacing) + 1.0;
}

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

namespace {

// A two-column CSV (station in m, value): '#' starts a comment, one header line allowed, comma,
// semicolon, tab or blank separated. Errors name the file, the line and what is allowed.
LineProfile read_profile_csv(const std::string& field, const std::string& path, double lo, double hi) {
  struct stat st {};
  if (::stat(path.c_str(), &st) != 0) fail(field, "'" + path + "'", std::string("a readable CSV file (") + std::strerror(errno) + ")");
  if (S_ISDIR(st.st_mode)) fail(field, "'" + path + "'", "a CSV file, not a directory");
  std::ifstream in(path, std::ios::binary);
  if (!in) fail(field, "'" + path + "'", std::string("a readable CSV file (") + std::strerror(errno) + ")");
  // Read at most the cap and one byte more (/dev/zero or a huge file must not fill the memory).
  std::string text(kMaxSceneFileBytes + 1, '\0');
  in.read(&text[0], static_cast<std::streamsize>(text.size()));
  text.resize(static_cast<std::size_t>(in.gcount()));
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

}  // namespace

double LineProfile::at(double x) const {
  if (stations.empty() || x < stations.front() || x > stations.back()) return 0.0;
  const auto it = std::upper_bound(stations.begin(), stations.end(), x);
  if (it == stations.end()) return values.back();
  const std::size_t j = static_cast<std::size_t>(it - stations.begin());
  const double t = (x - stations[j - 1]) / (stations[j] - stations[j - 1]);
  return values[j - 1] + t * (values[j] - values[j - 1]);
}

namespace {

std::uint64_t read_seed(Reader& r, const std::string& key) {
  const double v = r.number(key, 0.0, 9007199254740992.0, 0.0);
  if (v != std::floor(v)) fail(r.field(key), fmt(v), "a whole number >= 0");
  return static_cast<std::uint64_t>(v);
}

}  // namespace

double PantographHeadSpec::sway(double t) const {
  if (sway_times.empty()) return sway_amplitude * std::sin(2.0 * M_PI * sway_frequency * t);
  if (t <= sway_times.front()) return sway_lateral.front();
  if (t >= sway_times.back()) return sway_lateral.back();
  const std::size_t k = std::upper_bound(sway_times.begin(), sway_times.end(), t) - sway_times.begin();
  const double a = (t - sway_times[k - 1]) / (sway_times[k] - sway_times[k - 1]);
  return sway_lateral[k - 1] + a * (sway_lateral[k] - sway_lateral[k - 1]);
}

namespace {

// The 3-D line's rooms: stagger, alignment, wind, pantograph_head (scene.hpp).
void read_lateral_parts(Reader& top, Scene& s) {
  if (top.has("stagger")) {
    Reader r(top.child("stagger"), "stagger");
    StaggerSpec st;
    st.contact_wire = r.numbers("contact_wire", -1.0, 1.0);
    if (st.contact_wire.empty()) fail("stagger.contact_wire", "(empty list)", "at least one offset, m");
    if (r.has("messenger")) {
      st.messenger = r.numbers("messenger", -1.0, 1.0);
      // An empty list reads as "no offsets": neither the contact wire's (what the field's absence
      // gives) nor 0 is what it says, so it is asked for explicitly.
      if (st.messenger.empty())
        fail("stagger.messenger", "(empty list)",
             "at least one offset, m ([0.0]: the messenger above the track centre); leave the field out for the "
             "messenger above the contact wire (its stagger)");
    }
    st.per_support = r.boolean("per_support", false);
    if (r.has("steady_arm_stiffness")) st.steady_arm_stiffness = r.number("steady_arm_stiffness", 0.0, 1e9, std::nullopt, true);
    if (r.has("messenger_support_stiffness"))
      st.messenger_support_stiffness = r.number("messenger_support_stiffness", 0.0, 1e9, std::nullopt, true);
    r.finish();
    s.stagger = st;
  }
  if (top.has("alignment")) {
    Reader r(top.child("alignment"), "alignment");
    if (r.has("radius")) {
      // The whole line on one radius: what an endless line can repeat (every span alike).
      if (r.has("curves"))
        fail("alignment.radius", "(given with alignment.curves)", "one of the two: curves placed by station, or radius for the whole line");
      s.alignment.radius = r.number("radius", -1e6, 1e6);
      if (std::fabs(s.alignment.radius) < 100.0)
        fail("alignment.radius", fmt(s.alignment.radius), "|radius| of at least 100 m (+ to the left, - to the right)");
    }
    const YAML::Node cs = r.has("radius") ? YAML::Node(YAML::NodeType::Sequence) : r.child("curves");
    if (!cs || !cs.IsSequence())
      fail("alignment.curves", "(missing or not a list)", "a list of {start, length, radius[, transition]}, or alignment.radius");
    for (std::size_t i = 0; i < cs.size(); ++i) {
      Reader q(cs[i], "alignment.curves[" + std::to_string(i) + "]");
      CurveSpec c;
      c.start = q.number("start", 0.0, 1e7);
      c.length = q.number("length", 0.0, 1e6, std::nullopt, true);
      // Wires are chords between supports; the small-angle lateral plane needs radius >> span.
      c.radius = q.number("radius", -1e6, 1e6);
      if (std::fabs(c.radius) < 100.0)
        fail(q.field("radius"), fmt(c.radius), "|radius| of at least 100 m (+ to the left, - to the right)");
      c.transition = q.number("transition", 0.0, 1e6, 0.0);
      if (2.0 * c.transition > c.length)
        fail(q.field("transition"), fmt(c.transition), "at most half the curve's length (" + fmt(0.5 * c.length) + " m)");
      if (i > 0 && c.start < s.alignment.curves.back().start + s.alignment.curves.back().length)
        fail(q.field("start"), fmt(c.start), "after the end of the previous curve (" +
             fmt(s.alignment.curves.back().start + s.alignment.curves.back().length) + " m)");
      q.finish();
      s.alignment.curves.push_back(c);
    }
    r.finish();
  }
  if (top.has("wind")) {
    Reader r(top.child("wind"), "wind");
    WindSpec w;
    w.speed = r.number("speed", 0.0, 70.0);
    w.direction = r.number("direction", -360.0, 360.0, 90.0);
    w.air_density = r.number("air_density", 0.0, 2.0, 1.225, true);
    auto drag = [&](const char* key, WireDragSpec& d) {
      if (!r.has(key)) return;
      Reader q(r.child(key), std::string("wind.") + key);
      d.diameter = q.number("diameter", 0.0, 0.1, d.diameter, true);
      d.drag_coefficient = q.number("drag_coefficient", 0.0, 3.0, d.drag_coefficient);
      q.finish();
    };
    drag("contact_wire", w.contact_wire);
    drag("messenger", w.messenger);
    if (r.has("turbulence")) {
      Reader q(r.child("turbulence"), "wind.turbulence");
      TurbulenceSpec t;
      t.intensity = q.number("intensity", 0.0, 0.5, std::nullopt, true);
      t.length_scale = q.number("length_scale", 0.0, 1000.0, 50.0, true);
      t.coherence_decay = q.number("coherence_decay", 0.0, 100.0, 10.0, true);
      t.max_frequency = q.number("max_frequency", 0.0, 50.0, 5.0, true);
      t.spacing = q.number("spacing", 0.0, 100.0, 5.0, true);
      t.seed = read_seed(q, "seed");
      q.finish();
      if (!(w.speed > 0.0)) fail("wind.speed", fmt(w.speed), "above 0 with wind.turbulence (its spectrum scales with the mean speed)");
      w.turbulence = t;
    }
    if (r.has("blow_off_limit")) w.blow_off_limit = r.number("blow_off_limit", 0.0, 10.0, std::nullopt, true);
    r.finish();
    s.wind = w;
  }
  if (top.has("pantograph_head")) {
    Reader r(top.child("pantograph_head"), "pantograph_head");
    PantographHeadSpec& h = s.pantograph_head;
    h.working_width = r.number("working_width", 0.0, 5.0, 1.2, true);
    h.horn_width = r.number("horn_width", 0.0, 5.0, std::max(1.95, h.working_width), true);
    if (h.horn_width < h.working_width)
      fail("pantograph_head.horn_width", fmt(h.horn_width), "at least the working width (" + fmt(h.working_width) + " m)");
    const std::string act = r.text("on_dewirement", "continue");
    if (act == "continue") h.on_dewirement = DewirementAction::kContinue;
    else if (act == "stop") h.on_dewirement = DewirementAction::kStop;
    else fail("pantograph_head.on_dewirement", "'" + act + "'", "one of: continue (record and go on), stop (end the pass)");
    if (r.has("sway")) {
      Reader q(r.child("sway"), "pantograph_head.sway");
      if (q.has("times") || q.has("lateral")) {
        // A measured sway: samples in time (a car body's lateral motion at the pantograph).
        if (q.has("amplitude") || q.has("frequency"))
          fail("pantograph_head.sway", "(amplitude/frequency and times/lateral)", "one of: {amplitude, frequency} or {times, lateral}");
        h.sway_times = q.numbers("times", 0.0, 1e6);
        h.sway_lateral = q.numbers("lateral", -1.0, 1.0);
        if (h.sway_times.empty()) fail("pantograph_head.sway.times", "(empty list)", "at least one time, s");
        if (h.sway_lateral.size() != h.sway_times.size())
          fail("pantograph_head.sway.lateral", "(" + std::to_string(h.sway_lateral.size()) + " values)",
               "one per time of pantograph_head.sway.times (" + std::to_string(h.sway_times.size()) + ")");
        for (std::size_t i = 1; i < h.sway_times.size(); ++i)
          if (!(h.sway_times[i] > h.sway_times[i - 1]))
            fail("pantograph_head.sway.times[" + std::to_string(i) + "]", fmt(h.sway_times[i]),
                 "after the time before it (" + fmt(h.sway_times[i - 1]) + " s): increasing times");
      } else {
        h.sway_amplitude = q.number("amplitude", 0.0, 1.0);
        h.sway_frequency = q.number("frequency", 0.0, 20.0);
      }
      q.finish();
    }
    h.histogram_bin = r.number("histogram_bin", 0.0, 1.0, 0.02, true);
    r.finish();
  }
}

}  // namespace

Scene scene_from_yaml(const YAML::Node& root, const std::string& base_dir) {
  bool reference_defaults = false;  // preset reference, element length and damping its own
  if (!root || !root.IsMap()) throw SceneError("scene: the document must be a YAML map of sections (line, contact_wire, ...)");
  Reader top(root, "");
  Scene s;
  s.name = top.text("name", "scene");
  s.gravity = top.number("gravity", 0.0, 100.0, 9.81);

  {
    Reader r(top.child("line"), "line");
    if (!top.has("line")) fail("line", "(missing)", "required section with spans (or span_length and span_count)");
    s.contact_wire_height = r.number("contact_wire_height", 0.0, 100.0, 5.3);
    s.encumbrance = r.number("encumbrance", 0.0, 10.0, 1.2, true);
    const bool has_sections = top.has("sections");
    if (has_sections && (r.has("spans") || r.has("span_length") || r.has("span_count")))
      fail("line.spans", "(given with sections)", "with sections, every section gives its own spans");
    SectionSpec defaults;
    s.endless = r.boolean("endless", false);
    if (s.endless) {
      if (has_sections) fail("line.endless", "true", "a single tension section (remove the sections list)");
      if (r.has("spans") || r.has("span_count"))
        fail(r.has("spans") ? "line.spans" : "line.span_count", "(given with endless: true)",
             "an endless line repeats one span: give span_length only");
      defaults.spans.assign(1, r.number("span_length", 0.5, 500.0));
    } else if (!has_sections) {
      read_spans(r, "line", defaults.spans);
    }
    read_section_parts(top, "", defaults, nullptr);
    if (!has_sections) {
      defaults.contact_wire_count = 1;
      s.sections.push_back(defaults);
    } else {
      const YAML::Node secs = top.child("sections");
      if (!secs.IsSequence() || secs.size() == 0) fail("sections", "(not a non-empty list)", "a list of tension sections");
      for (std::size_t i = 0; i < secs.size(); ++i) {
        const std::string path = "sections[" + std::to_string(i) + "]";
        Reader sr(secs[i], path);
        SectionSpec sec = defaults;
        read_spans(sr, path, sec.spans);
        read_section_parts(sr, path, sec, &defaults);
        const double count = sr.number("contact_wire_count", 1.0, 2.0, 1.0);
        if (count != std::floor(count)) fail(sr.field("contact_wire_count"), fmt(count), "1 or 2 (twin contact wire)");
        sec.contact_wire_count = static_cast<int>(count);
        sec.first_span_transition = sr.boolean("first_span_transition", i > 0);
        sec.last_span_transition = sr.boolean("last_span_transition", i + 1 < secs.size());
        sr.finish();
        s.sections.push_back(sec);
      }
    }
    r.finish();
  }
  if (top.has("overlap")) {
    Reader r(top.child("overlap"), "overlap");
    OverlapSpec o;
    const double k = r.number("spans", 1.0, 10.0, 1.0);
    if (k != std::floor(k)) fail("overlap.spans", fmt(k), "a whole number of transition spans >= 1");
    o.spans = static_cast<int>(k);
    if (r.has("support_rise")) o.support_rise = r.number("support_rise", 0.0, 2.0);
    if (r.has("design_force")) o.design_force = r.number("design_force", 0.0, 2000.0, std::nullopt, true);
    r.finish();
    s.overlap = o;
  } else if (s.sections.size() > 1) {
    s.overlap = OverlapSpec{};
  }
  // The first section's parts stay available as the scene's defaults.
  const SectionSpec& first = s.sections.front();
  s.contact_wire = first.contact_wire;
  s.messenger = first.messenger;
  s.droppers = first.droppers;
  s.steady_arms = first.steady_arms;
  s.messenger_supports = first.messenger_supports;
  resolve_line(s);
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
    // Any finite speed >= 0 here; validate() applies the limit (train_speed_limit).
    if (r.has("speed_kmh")) s.train_speed = r.number("speed_kmh", 0.0, kInf) / 3.6;
    else s.train_speed = r.number("speed", 0.0, kInf, 0.0);
    if (r.has("start")) s.train_start = r.number("start", -kInf, kInf);
    if (r.has("end")) s.train_end = r.number("end", -kInf, kInf);
    r.finish();
  }
  if (top.has("numerics")) {
    Reader r(top.child("numerics"), "numerics");
    // A preset sets the defaults of the fidelity ladder; every field can still be set on its own.
    const std::string preset = r.text("preset", "");
    double h = 0.25;
    // Element lengths measured in bench/speed_accuracy (BENCHMARKS.md): all explicit, because on
    // these lines the condensed explicit scheme is the fastest at every accuracy level. The
    // reference rung chosen in bench_reference_rung against h = 0.03125 m: h = 0.0625 m with the
    // centred damping keeps every statistic within 0.05 % of that finer solution, its dt the
    // undamped limit (with the half-step damping, the stiffness-proportional damping of the
    // shortest mesh modes cut it 2.6x; where the centred step does not go, h = 0.1 m below).
    if (preset == "fast") {
      h = 1.0;
    } else if (preset == "balanced") {
      h = 0.5;
    } else if (preset == "accurate" || preset.empty()) {
      h = 0.25;
    } else if (preset == "reference") {
      h = 0.0625;
    } else {
      fail("numerics.preset", "'" + preset + "'", "one of: fast, balanced, accurate, reference");
    }
    s.numerics.preset = preset;
    reference_defaults = preset == "reference" && !r.has("element_length") && !r.has("damping");
    s.numerics.element_length = r.number("element_length", 0.01, 10.0, h);
    if (r.has("dt")) {
      const YAML::Node n = r.child("dt");
      if (!(n.IsScalar() && n.as<std::string>() == "auto"))
        s.numerics.dt = Reader::parse_number(n, "numerics.dt", 0.0, 0.1, true);
    }
    s.numerics.safety_factor = r.number("safety_factor", 0.0, 1.0, 0.9, true);
    const std::string integ = r.text("integrator", "explicit");
    if (integ == "explicit") s.numerics.integrator = Integrator::kExplicit;
    else if (integ == "implicit") s.numerics.integrator = Integrator::kImplicit;
    else fail("numerics.integrator", "'" + integ + "'", "one of: explicit (central differences, eq. 19-21), implicit (Newmark average acceleration)");
    const std::string rt = r.text("rotary_inertia", s.numerics.integrator == Integrator::kImplicit ? "lumped" : "condensed");
    if (rt == "condensed") s.numerics.rotary_inertia = RotaryInertia::kCondensed;
    else if (rt == "lumped") s.numerics.rotary_inertia = RotaryInertia::kLumped;
    else fail("numerics.rotary_inertia", "'" + rt + "'", "one of: condensed (massless rotations, statically condensed), lumped (HRZ rotary inertia)");
    if (s.numerics.integrator == Integrator::kImplicit && s.numerics.rotary_inertia == RotaryInertia::kCondensed)
      fail("numerics.rotary_inertia", "'condensed'", "lumped with the implicit integrator (its matrix holds the rotations as DOFs)");
    const std::string dmp = r.text("damping", preset == "reference" ? "centred" : "half_step");
    if (dmp == "half_step") s.numerics.damping = DampingStep::kHalfStep;
    else if (dmp == "centred") s.numerics.damping = DampingStep::kCentred;
    else fail("numerics.damping", "'" + dmp + "'", "one of: half_step (C v at v_{n-1/2}, eq. 19-21), centred (C v at (v_{n+1/2} + v_{n-1/2}) / 2)");
    s.numerics.divergence_limit = r.number("divergence_limit", 0.0, 1000.0, 5.0, true);
    s.numerics.allow_supercritical = r.boolean("allow_supercritical", false);
    if (r.has("window")) {
      const YAML::Node wn = r.child("window");
      if (wn.IsScalar() && wn.as<std::string>() == "auto") {
        s.numerics.window_auto = true;  // lengths from speed and wave speed: window_lengths()
      } else if (wn.IsScalar() && wn.as<std::string>() == "off") {
      } else {
        Reader w(wn, "numerics.window");
        s.numerics.window_ahead = w.number("ahead", 0.0, 1e5, std::nullopt, true);
        s.numerics.window_behind = w.number("behind", 0.0, 1e5, std::nullopt, true);
        w.finish();
      }
    }
    if (r.has("gust_lead")) {
      const YAML::Node n = r.child("gust_lead");
      const std::string raw = n.IsScalar() ? n.as<std::string>() : "(not a scalar)";
      if (raw != "auto") {
        double v = std::nan("");
        if (n.IsScalar()) {
          try {
            v = n.as<double>();
          } catch (const YAML::Exception&) {
          }
        }
        if (!(v >= 0.0 && v <= kMaxGustLead))
          fail("numerics.gust_lead", raw, "auto, or seconds of travel in [0, " + fmt(kMaxGustLead) + "]");
        s.numerics.gust_lead = v;
      }
    }
    r.finish();
  }
  if (top.has("imperfections")) {
    Reader r(top.child("imperfections"), "imperfections");
    ImperfectionSpec& im = s.imperfections;
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
    if (r.has("point_masses")) {
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
    if (r.has("contact_wire_irregularity")) {
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
    if (r.has("contact_wire_wear")) {
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
    s.output.sensor_bandwidth = r.number("sensor_bandwidth", 0.0, 10000.0, 20.0, true);
    s.output.dropper_series = r.boolean("dropper_series", false);
    auto optional_number = [&](const char* key, double lo, double hi, bool lo_open) -> std::optional<double> {
      if (!r.has(key)) return std::nullopt;
      return r.number(key, lo, hi, std::nullopt, lo_open);
    };
    s.output.allowed_uplift = optional_number("allowed_uplift", 0.0, 10.0, true);
    s.output.max_stat_force = optional_number("max_stat_force", 0.0, 1e5, true);
    s.output.min_stat_force = optional_number("min_stat_force", -1e5, 1e5, false);
    s.output.max_contact_loss_percent = optional_number("max_contact_loss_percent", 0.0, 100.0, false);
    r.finish();
  }
  read_lateral_parts(top, s);
  top.finish();
  // The reference rung's centred damping steps a whole 2-D line with the explicit scheme and beta
  // > 0 (NumericsSpec::damping); elsewhere (a window, an endless line, a 3-D line) the rung is
  // h = 0.1 m with the half-step damping, the finest its explicit dt allows at a reference's cost
  // (docs/benchmark_history.md, "Choosing the reference rung").
  if (reference_defaults && (s.numerics.windowed() || s.endless || s.lateral() || !(s.rayleigh_beta > 0.0) ||
                             s.numerics.integrator != Integrator::kExplicit ||
                             s.numerics.rotary_inertia != RotaryInertia::kCondensed)) {
    s.numerics.element_length = 0.1;
    s.numerics.damping = DampingStep::kHalfStep;
  }
  // On a finite line one radius is one curve over the whole line (heading from station 0).
  if (!s.endless && s.alignment.radius != 0.0) {
    s.alignment.curves = {CurveSpec{0.0, s.line_length(), s.alignment.radius, 0.0}};
    s.alignment.radius = 0.0;
  }
  validate(s);
  return s;
}

void validate(const Scene& s) {
  const double line = s.line_length();
  if (s.sections.empty()) fail("line", "(no tension section)", "at least one section of spans");
  for (std::size_t si = 0; si < s.sections.size(); ++si) {
    const SectionSpec& sec = s.sections[si];
    const std::string pre = s.sections.size() > 1 ? "sections[" + std::to_string(si) + "]." : "";
    if (sec.droppers && !sec.messenger)
      fail(pre + "droppers", "(given)", "droppers hang the contact wire from a messenger: add a messenger section or remove droppers");
    if (sec.messenger_supports && !sec.messenger) fail(pre + "messenger_supports", "(given)", "needs a messenger section");
    if (sec.contact_wire_count == 2 && !sec.droppers)
      fail(pre + "contact_wire_count", "2", "a twin contact wire hangs from droppers: add droppers and a messenger");
    if (sec.contact_wire.presag != 0.0 && !sec.droppers)
      fail(pre + "contact_wire.presag", fmt(sec.contact_wire.presag), "0 without droppers (the presag is set by the dropper lengths)");
    if (!sec.droppers) continue;
    if (sec.droppers->positions.size() != sec.spans.size())
      fail(pre + "droppers.positions_per_span", std::to_string(sec.droppers->positions.size()) + " lists", "one per span");
    for (std::size_t i = 0; i < sec.spans.size(); ++i) {
      const auto& p = sec.droppers->positions[i];
      for (std::size_t j = 0; j < p.size(); ++j) {
        const std::string f = pre + "droppers.positions (span " + std::to_string(i) + ", dropper " + std::to_string(j) + ")";
        if (p[j] <= 0.0 || p[j] >= sec.spans[i])
          fail(f, fmt(p[j]), "strictly inside the span (0, " + fmt(sec.spans[i]) + ") m");
        if (j > 0 && p[j] <= p[j - 1]) fail(f, fmt(p[j]), "increasing along the span (previous " + fmt(p[j - 1]) + ")");
      }
    }
  }
  const TrainSpeedLimit speed = train_speed_limit(s);
  if (!speed.allows(s.train_speed)) {
    const double v = s.train_speed;
    std::string value = fmt(v * 3.6) + " (" + fmt(v) + " m/s";
    if (v >= speed.wave_speed) value += ", " + fmt4(v / speed.wave_speed) + " times the contact wire's wave speed";
    fail("train.speed_kmh", value + ")", "allowed " + speed.text());
  }
  {
    const PantographHeadSpec& h = s.pantograph_head;
    if (!(h.histogram_bin > 0.0) || h.horn_width / h.histogram_bin > kMaxHistogramBins)
      fail("pantograph_head.histogram_bin", fmt(h.histogram_bin),
           "allowed [" + fmt4(h.horn_width / kMaxHistogramBins) + ", 1] m: at most " + fmt(kMaxHistogramBins) +
               " bins across pantograph_head.horn_width = " + fmt(h.horn_width) + " m");
  }
  if (s.wind && s.wind->turbulence) {
    const double points = wind_field_points(s);
    if (!(points <= kMaxWindFieldPoints)) {
      const double spacing = s.wind->turbulence->spacing, reach = (points - 1.0) * spacing;
      fail("wind.turbulence.spacing", fmt(spacing),
           "allowed [" + fmt4(reach / (kMaxWindFieldPoints - 1.0)) + ", 100] m here: at most " + fmt(kMaxWindFieldPoints) +
               " field points over the " + fmt4(reach) + " m of line the field holds at once (this spacing gives " + fmt4(points) +
                   ")");
    }
  }
  if (s.numerics.damping == DampingStep::kCentred && s.numerics.safety_factor > kCentredMaxSafetyFactor)
    fail("numerics.safety_factor", fmt(s.numerics.safety_factor),
         "at most " + fmt(kCentredMaxSafetyFactor) + " with numerics.damping: centred (its stability estimate is no bound "
         "at the estimate itself; half_step takes up to 1)");
  // Fields that could never act in this scene are refused rather than silently ignored.
  if (s.numerics.gust_lead && !(s.wind && s.wind->turbulence && s.numerics.windowed()))
    fail("numerics.gust_lead", fmt(*s.numerics.gust_lead),
         "only with a turbulent wind (wind.turbulence) and the moving window (numerics.window): it is how much further "
         "ahead the lateral window reaches; remove it here");
  if (!s.lateral())
    for (std::size_t i = 0; i < s.pantographs.size(); ++i) {
      const PantographSpec& p = s.pantographs[i];
      auto check = [&](const std::vector<CollectorSpec>& cs, const std::string& field) {
        for (std::size_t j = 0; j < cs.size(); ++j)
          if (cs[j].working_width)
            fail(field + "[" + std::to_string(j) + "].working_width", fmt(*cs[j].working_width),
                 "only on a 3-D line (stagger, alignment, wind or pantograph_head.sway): a 2-D line has no lateral "
                 "contact point to keep on the strip; remove it here");
      };
      const std::string pf = "pantographs[" + std::to_string(i) + "]";
      check(p.collectors, pf + ".collectors");
      for (std::size_t h = 0; h < p.heads.size(); ++h) check(p.heads[h].collectors, pf + ".heads[" + std::to_string(h) + "].collectors");
    }
  std::set<std::string> names;
  for (std::size_t i = 0; i < s.pantographs.size(); ++i) {
    const auto& p = s.pantographs[i];
    const std::string pre = "pantographs[" + std::to_string(i) + "].";
    if (!names.insert(p.name).second) fail(pre + "name", "'" + p.name + "'", "unique among pantographs");
    // The uplift F0 + a v^2 pushes the head up against the wire; a net downward push is not a
    // pantograph (it would pull the head off the wire and the roof spring alone cannot hold it).
    const double v = s.train_speed, uplift = p.net_uplift(v);
    if (!p.moving_force && uplift < 0.0) {
      // Name the term that pulls down most (the frame's, or a head's, for the knee in use).
      std::string f = pre + (p.knee_trailing && p.aero_coefficient_trailing ? "aero_coefficient_trailing" : "aero_coefficient");
      double worst = p.frame_aero();
      for (std::size_t h = 0; h < p.heads.size(); ++h) {
        const double a = PantographSpec::head_aero(p.heads[h], p.knee_trailing);
        if (a < worst) {
          worst = a;
          f = pre + "heads[" + std::to_string(h) + "]." +
              (p.knee_trailing && p.heads[h].aero_coefficient_trailing ? "aero_coefficient_trailing" : "aero_coefficient");
        }
      }
      fail(f, fmt(worst),
           "a net uplift >= 0 at " + fmt(v * 3.6) + " km/h (knee " + (p.knee_trailing ? "trailing" : "leading") +
               "): static_uplift + (frame and heads' aero coefficients) v^2 = " + fmt(uplift) +
               " N; a net downward aerodynamic pull is not physical for a pantograph in service");
    }
  }
  if ((s.imperfections.stagger_std > 0.0 || !s.imperfections.stagger_errors.empty()) && !s.stagger)
    fail(s.imperfections.stagger_std > 0.0 ? "imperfections.stagger_std" : "imperfections.stagger_errors", "(given)",
         "a 3-D line: give the design stagger (scene field 'stagger') the errors move");
  if (s.imperfections.any()) {
    if (s.endless)
      fail("imperfections", "(given)", "a finite line: an endless line repeats one perfect span");
    // The mesh carries a wavelength of at least two elements (shorter ones alias onto longer ones).
    const IrregularitySpec& ir = s.imperfections.contact_wire_irregularity;
    if (ir.rms > 0.0 && ir.wavelength_min < 2.0 * s.numerics.element_length)
      fail("imperfections.contact_wire_irregularity.wavelength_min", fmt(ir.wavelength_min),
           "at least two elements (2 x numerics.element_length = " + fmt(2.0 * s.numerics.element_length) +
               " m): the mesh cannot carry a shorter wave");
    for (std::size_t i = 0; i < s.imperfections.point_masses.size(); ++i)
      if (s.imperfections.point_masses[i].station > line + 1e-9)
        fail("imperfections.point_masses[" + std::to_string(i) + "].station", fmt(s.imperfections.point_masses[i].station),
             "on the line, [0, " + fmt(line) + "] m");
  }
  if (s.lateral()) {
    // A strip's own working width lies within the head's horns (pantograph_head.horn_width).
    auto check_strips = [&](const std::vector<CollectorSpec>& cs, const std::string& field) {
      for (std::size_t j = 0; j < cs.size(); ++j)
        if (cs[j].working_width && *cs[j].working_width > s.pantograph_head.horn_width + 1e-12)
          fail(field + "[" + std::to_string(j) + "].working_width", fmt(*cs[j].working_width),
               "at most pantograph_head.horn_width = " + fmt(s.pantograph_head.horn_width) + " m");
    };
    for (std::size_t i = 0; i < s.pantographs.size(); ++i) {
      const std::string pf = "pantographs[" + std::to_string(i) + "]";
      check_strips(s.pantographs[i].collectors, pf + ".collectors");
      for (std::size_t h = 0; h < s.pantographs[i].heads.size(); ++h)
        check_strips(s.pantographs[i].heads[h].collectors, pf + ".heads[" + std::to_string(h) + "].collectors");
    }
    // An endless line repeats its block of spans: a stagger pattern repeats with it (the block
    // moves by whole patterns), and so does one radius for the whole line; a curve placed by
    // station or a list per support does not.
    if (s.endless && !s.alignment.curves.empty())
      fail("alignment.curves", "(given with line.endless: true)",
           "a finite line: curves are placed by station; an endless line takes alignment.radius (every span on one curve)");
    if (s.endless && s.stagger && s.stagger->per_support)
      fail("stagger.per_support", "true (with line.endless: true)",
           "false on an endless line: give the stagger as a pattern repeated over the supports");
    if (s.endless && s.stagger) {
      const std::size_t a = s.stagger->contact_wire.size(), b = std::max<std::size_t>(1, s.stagger->messenger.size());
      if (a * b / std::gcd(a, b) > 8)
        fail("stagger.contact_wire", "(a pattern of " + std::to_string(a) + " with a messenger pattern of " + std::to_string(b) + ")",
             "on an endless line, patterns that repeat together within 8 supports (the block moves by whole patterns)");
    }
    const double half = 0.5 * s.pantograph_head.working_width;
    if (s.stagger) {
      for (std::size_t i = 0; i < s.stagger->contact_wire.size(); ++i)
        if (std::fabs(s.stagger->contact_wire[i]) >= half)
          fail("stagger.contact_wire[" + std::to_string(i) + "]", fmt(s.stagger->contact_wire[i]),
               "inside the pantograph head's working width, |stagger| < " + fmt(half) + " m (pantograph_head.working_width / 2)");
      if (s.stagger->per_support) {
        // Supports along the line, counting an overlap's shared supports once.
        const std::size_t line_supports = s.spans.size() + 1;
        if (s.stagger->contact_wire.size() != line_supports)
          fail("stagger.contact_wire", "(" + std::to_string(s.stagger->contact_wire.size()) + " values)",
               "one per support of the line with per_support: true (" + std::to_string(line_supports) + ")");
        if (!s.stagger->messenger.empty() && s.stagger->messenger.size() != line_supports)
          fail("stagger.messenger", "(" + std::to_string(s.stagger->messenger.size()) + " values)",
               "one per support of the line with per_support: true (" + std::to_string(line_supports) + ")");
      }
    }
    for (std::size_t i = 0; i < s.alignment.curves.size(); ++i)
      if (s.alignment.curves[i].start >= line)
        fail("alignment.curves[" + std::to_string(i) + "].start", fmt(s.alignment.curves[i].start), "on the line, below " + fmt(line) + " m");
  }
  if (s.endless) {
    if (!s.numerics.windowed())
      fail("numerics.window", "off", "auto or {ahead, behind} on an endless line (only the window around the train is modelled)");
    if (!s.train_end) fail("train.end", "(missing)", "required on an endless line: the train front's station where the pass ends, m");
    if (s.droppers && s.droppers->per_span)
      fail("droppers.positions_per_span", "(given)", "an endless line repeats one span: give droppers.positions");
    if (s.output.analysis_first_span && s.output.analysis_last_span &&
        !(0 <= *s.output.analysis_first_span && *s.output.analysis_first_span < *s.output.analysis_last_span))
      fail("output.analysis_spans", "[" + std::to_string(*s.output.analysis_first_span) + ", " + std::to_string(*s.output.analysis_last_span) + "]",
           "0 <= first < last (span indices along the endless line)");
    if (s.train_start && *s.train_end < *s.train_start)
      fail("train.end", fmt(*s.train_end), ">= train.start (" + fmt(*s.train_start) + ")");
    if (s.numerics.element_length > s.spans.front() + 1e-12)
      fail("numerics.element_length", fmt(s.numerics.element_length), "at most the span length");
    return;
  }
  const int a0 = s.analysis_first(), a1 = s.analysis_last();
  if (a0 < 0 || a1 > static_cast<int>(s.spans.size()) || a0 >= a1)
    fail("output.analysis_spans", "[" + std::to_string(a0) + ", " + std::to_string(a1) + "]",
         "0 <= first < last <= span count (" + std::to_string(s.spans.size()) + ")");
  if (s.numerics.element_length > *std::min_element(s.spans.begin(), s.spans.end()) + 1e-12)
    fail("numerics.element_length", fmt(s.numerics.element_length), "at most the shortest span");
  if (s.train_start && s.train_end && *s.train_end < *s.train_start)
    fail("train.end", fmt(*s.train_end), ">= train.start (" + fmt(*s.train_start) + ")");
  if (s.train_end && *s.train_end > line + 1e-9)
    fail("train.end", fmt(*s.train_end), "at most the line length " + fmt(line) + " m");
}

namespace {

// A part of a dotted key that indexes a list: digits only, small enough to be an index.
bool index_of(const std::string& part, std::size_t* idx) {
  if (part.empty() || part.find_first_not_of("0123456789") != std::string::npos) return false;
  *idx = part.size() > 9 ? std::numeric_limits<std::size_t>::max() : std::stoul(part);
  return true;
}

// Applies "a.b.0.c=value" to the tree. A value of null removes the field (back to its default).
void apply_override(YAML::Node root, const std::string& assignment) {
  const auto eq = assignment.find('=');
  auto bad = [&](const std::string& why) -> SceneError {
    return SceneError("override '" + assignment + "': " + why);
  };
  if (eq == std::string::npos || eq == 0) throw bad("expected key.path=value, e.g. numerics.element_length=0.125");
  const std::string key = assignment.substr(0, eq);
  YAML::Node value;
  try {
    value = YAML::Load(assignment.substr(eq + 1));
  } catch (const YAML::Exception& e) {
    throw bad(std::string("value is not valid YAML (") + e.what() + ")");
  }
  check_yaml_shape(assignment.substr(eq + 1), "override '" + assignment + "'");
  std::vector<std::string> parts;
  std::stringstream ss(key);
  for (std::string p; std::getline(ss, p, '.');) parts.push_back(p);
  if (key.back() == '.') parts.push_back("");
  for (const std::string& p : parts)
    if (p.empty()) throw bad("empty part in the key '" + key + "' (fields are joined by single dots)");
  // Walk down, creating maps as needed; numeric parts index lists.
  YAML::Node cur = root;
  std::string walked;
  for (std::size_t i = 0; i < parts.size(); ++i) {
    const std::string& part = parts[i];
    const bool leaf = i + 1 == parts.size();
    const std::string here = walked.empty() ? "the scene" : "'" + walked + "'";
    std::size_t idx = 0;
    if (cur.IsSequence()) {
      if (!index_of(part, &idx)) throw bad(here + " is a list: expected " + (cur.size() ? "an index 0.." + std::to_string(cur.size() - 1) : std::string("no index (it is empty)")) + ", not '" + part + "'");
      if (idx >= cur.size())
        throw bad("index " + part + " out of range: " + here + " has " + std::to_string(cur.size()) + " entries");
      if (leaf) {
        if (value.IsNull()) throw bad("a list entry cannot be removed with null");
        cur[idx] = value;
        return;
      }
      cur.reset(cur[idx]);
    } else if (cur.IsMap() || cur.IsNull() || !cur.IsDefined()) {
      if (leaf) {
        if (value.IsNull()) {
          if (cur.IsMap()) cur.remove(part);
        } else {
          cur[part] = value;
        }
        return;
      }
      if (!cur[part] || cur[part].IsNull()) cur[part] = YAML::Node(YAML::NodeType::Map);
      cur.reset(cur[part]);
    } else {
      throw bad(here + " is a value ('" + cur.Scalar() + "'), it has no field '" + part + "'");
    }
    walked += (walked.empty() ? "" : ".") + part;
  }
}

Scene load_from_node(YAML::Node root, const std::vector<std::string>& overrides, const std::string& base_dir) {
  if (!root || !root.IsMap()) throw SceneError("scene: the document must be a YAML map of sections (line, contact_wire, ...)");
  try {
    for (const auto& o : overrides) apply_override(root, o);
    check_document(root, "");
    return scene_from_yaml(root, base_dir);
  } catch (const YAML::Exception& e) {
    // Not expected after check_document; a field is still better named by the reader, but never abort.
    throw SceneError(std::string("scene: ") + e.what());
  } catch (const std::logic_error& e) {
    throw SceneError(std::string("scene: ") + e.what());
  }
}

}  // namespace

Scene load_scene_string(const std::string& yaml, const std::vector<std::string>& overrides, const std::string& base_dir) {
  YAML::Node root;
  try {
    root = YAML::Load(yaml);
  } catch (const YAML::Exception& e) {
    throw SceneError(std::string("scene: not valid YAML: ") + e.what());
  }
  check_yaml_shape(yaml, "scene");
  return load_from_node(root, overrides, base_dir);
}


Scene load_scene_file(const std::string& path, const std::vector<std::string>& overrides) {
  struct stat st {};
  if (::stat(path.c_str(), &st) != 0)
    throw SceneError("scene file '" + path + "': cannot be opened (" + std::strerror(errno) + ")");
  if (S_ISDIR(st.st_mode)) throw SceneError("scene file '" + path + "': is a directory, expected a YAML file");
  std::ifstream in(path, std::ios::binary);
  if (!in) throw SceneError("scene file '" + path + "': cannot be opened (" + std::strerror(errno) + ")");
  // Read at most the cap and one byte more: /dev/zero or a huge file must not fill the memory.
  std::string text(kMaxSceneFileBytes + 1, '\0');
  in.read(&text[0], static_cast<std::streamsize>(text.size()));
  text.resize(static_cast<std::size_t>(in.gcount()));
  if (text.size() > kMaxSceneFileBytes)
    throw SceneError("scene file '" + path + "': larger than " + std::to_string(kMaxSceneFileBytes >> 20) +
                     " MiB, the limit for a scene (scenes are a few kB of YAML)");
  if (in.bad()) throw SceneError("scene file '" + path + "': read error (" + std::strerror(errno) + ")");
  try {
    const std::size_t slash = path.rfind('/');
    return load_scene_string(text, overrides, slash == std::string::npos ? "" : path.substr(0, slash == 0 ? 1 : slash));
  } catch (const SceneError& e) {
    throw SceneError(path + ": " + e.what());
  }
}

}  // namespace catenary_sim
