#include "scene/document_shape.hpp"

#include <yaml-cpp/depthguard.h>
#include <yaml-cpp/eventhandler.h>

#include <cstdint>
#include <cstdio>
#include <initializer_list>
#include <set>
#include <sstream>
#include <vector>

#include "scene/scene_reader.hpp"

namespace catenary_sim {

using namespace scene_reading;
namespace {

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

}  // namespace

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

namespace {

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

}  // namespace

// Throws SceneError (naming `what`) for YAML that is not one acyclic document of bounded expansion.
void check_yaml_shape(const std::string& text, const std::string& what) {
  std::istringstream in(text);
  YAML::Parser parser(in);
  DocumentShape shape(what);
  try {
    while (parser.HandleNextDocument(shape)) {
    }
  } catch (const YAML::Exception& e) {
    throw SceneError(what + ": not valid YAML: " + yaml_error_text(e));
  }
}

std::string yaml_error_text(const YAML::Exception& e) {
  if (const auto* deep = dynamic_cast<const YAML::DeepRecursion*>(&e))
    return "nested " + std::to_string(deep->depth()) + " levels deep at line " + std::to_string(e.mark.line + 1) +
           ", column " + std::to_string(e.mark.column + 1) +
           ": the YAML reader's limit; a scene's fields nest a few levels";
  return e.what();
}

void check_text(const std::string& text, const std::string& what) {
  const auto byte = [&](std::size_t i) { return static_cast<unsigned char>(text[i]); };
  const auto starts = [&](std::initializer_list<unsigned char> mark) {
    if (text.size() < mark.size()) return false;
    std::size_t i = 0;
    for (unsigned char c : mark)
      if (byte(i++) != c) return false;
    return true;
  };
  if (starts({0xFE, 0xFF}) || starts({0xFF, 0xFE}) || starts({0x00, 0x00, 0xFE, 0xFF})) return;
  std::size_t line = 1, column = 1;
  for (std::size_t i = 0; i < text.size();) {
    const unsigned char c = byte(i);
    // The sequence's length and the least code point it may hold (overlong forms are not UTF-8).
    std::size_t n = 1;
    unsigned long cp = c, least = 0;
    if (c >= 0xF0 && c <= 0xF4) n = 4, cp = c & 0x07, least = 0x10000;
    else if (c >= 0xE0 && c <= 0xEF) n = 3, cp = c & 0x0F, least = 0x800;
    else if (c >= 0xC2 && c <= 0xDF) n = 2, cp = c & 0x1F, least = 0x80;
    else if (c >= 0x80) n = 0;
    bool ok = n > 0 && i + n <= text.size();
    for (std::size_t k = 1; ok && k < n; ++k) {
      ok = (byte(i + k) & 0xC0) == 0x80;
      cp = (cp << 6) | (byte(i + k) & 0x3F);
    }
    ok = ok && cp >= least && cp <= 0x10FFFF && !(cp >= 0xD800 && cp <= 0xDFFF);
    const std::string at = " at line " + std::to_string(line) + ", column " + std::to_string(column);
    if (!ok) {
      char hex[8];
      std::snprintf(hex, sizeof hex, "0x%02X", c);
      throw SceneError(what + ": not UTF-8 text (byte " + hex + at + "): expected YAML text, UTF-8");
    }
    if (c == 0) throw SceneError(what + ": not text (a NUL byte" + at + "): expected YAML text, UTF-8");
    if (c == '\n') ++line, column = 1;
    else ++column;
    i += n;
  }
}

}  // namespace catenary_sim
