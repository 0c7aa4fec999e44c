// The scene reader's tools, shared by the files that read the scene's rooms: a strict map reader
// (unknown keys are errors) and the message format of a refused field.
#pragma once

#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include "catenary_sim/core/scene/scene.hpp"
#include "util/edit_distance.hpp"

namespace catenary_sim {
namespace scene_reading {

constexpr double kInf = std::numeric_limits<double>::infinity();

inline std::string fmt(double v) {
  std::ostringstream s;
  s.precision(10);
  s << v;
  return s.str();
}

// 4 significant digits, for limits computed from the scene.
inline std::string fmt4(double v) {
  std::ostringstream s;
  s.precision(4);
  s << v;
  return s.str();
}

[[noreturn]] inline void fail(const std::string& field, const std::string& value, const std::string& allowed) {
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
      fail(field(key), "(missing)" + misspelt(key), "required, a number in " + range(lo, hi, lo_open));
    }
    return parse_number(node_[key], field(key), lo, hi, lo_open);
  }

  std::vector<double> numbers(const std::string& key, double lo, double hi, bool lo_open = false) {
    if (!has(key)) fail(field(key), "(missing)" + misspelt(key), "required, a list of numbers in " + range(lo, hi, lo_open));
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

  // For a required key that is missing: a key of the map within two letters of it that nothing
  // has read, named (" (given: 'support_stifness', misspelt?)"), since the map's unknown keys are
  // found only by finish(), after the refusal; "" if there is none.
  std::string misspelt(const std::string& key) const {
    if (!node_ || !node_.IsMap()) return "";
    for (const auto& kv : node_) {
      if (!kv.first.IsScalar()) continue;
      const std::string given = kv.first.Scalar();
      if (given != key && !used_.count(given) && edit_distance(given, key) <= 2)
        return " (given: '" + given + "', misspelt?)";
    }
    return "";
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
    // A quoted scalar is text ("1500", '1.5e3 '), whatever it spells: a number is written plain.
    if (n.Tag() == "!") fail(field, "'" + raw + "' (in quotes, so text)", "a number in " + range(lo, hi, lo_open) + ", written without quotes");
    // A tag other than YAML's own for numbers makes it something else (!!str 8.0 is text).
    if (n.Tag() != "?" && n.Tag() != "tag:yaml.org,2002:float" && n.Tag() != "tag:yaml.org,2002:int")
      fail(field, "'" + raw + "' (tagged " + n.Tag() + ")", "a number in " + range(lo, hi, lo_open) + ", written plain");
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

}  // namespace scene_reading
}  // namespace catenary_sim
