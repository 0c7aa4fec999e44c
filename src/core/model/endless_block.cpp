#include "model/endless_block.hpp"

#include <algorithm>
#include <cmath>
#include <numeric>
#include <string>

#include "catenary_sim/core/model/lateral.hpp"
#include "catenary_sim/core/model/window_lengths.hpp"
#include "util/format.hpp"

namespace catenary_sim {

namespace {

// Spans at each end of an endless line's block that the window never reaches: the anchors'
// effect on the design statics (messenger heights, dropper lengths) falls by about a thousand
// per span, so from the third span on the spans are identical to well under a micrometre. A
// stitched line's falls more slowly (its stitch wires carry it across the supports: 1.04 um
// between the third span's messenger and the fourth's, 1.2e-6 of a clamp's force between the
// fourth and the fifth): two spans more.
int endless_margin(const Scene& scene) {
  return scene.sections.front().stitch_wire ? 5 : 3;
}

}  // namespace

void collector_extent(const Scene& scene, double* lead, double* rear) {
  bool first = true;
  *lead = *rear = 0.0;
  auto add = [&](double off) {
    *lead = first ? off : std::max(*lead, off);
    *rear = first ? off : std::min(*rear, off);
    first = false;
  };
  for (const PantographSpec& p : scene.pantographs) {
    for (const CollectorSpec& c : p.collectors) add(c.offset - p.position);
    // Strips on heads: their offsets are from the head's centre (without this a head could start
    // or end off the line, its strip touching nothing and the head rising on its preload).
    for (const HeadSpec& h : p.heads)
      for (const CollectorSpec& c : h.collectors) add(h.offset + c.offset - p.position);
  }
}

double lay_endless_block(Scene& scene, Model& m) {
  double endless_front = 0.0;
  // A block of equal spans: `margin` spans at each end keep the anchors out of the window's
  // reach (endless_margin); the rearmost collector stays within [home, home + span) (step() moves the state back
  // a span when it leaves), so the block must hold the window behind it (B spans, one more for
  // snapping to supports), the train (S) and the window ahead (A) at any speed a command allows.
  const double span = scene.spans.front();
  const double c = std::sqrt(scene.contact_wire.tension / scene.contact_wire.linear_mass);
  double ahead_slow = 0, behind_slow = 0, ahead_fast = 0, behind_fast = 0;
  window_lengths_for(scene.numerics, c, span, 0.0, &ahead_slow, &behind_slow);
  window_lengths_for(scene.numerics, c, span, std::max(scene.train_speed, kMaxTrainSpeed), &ahead_fast, &behind_fast);
  double lead = 0.0, rear = 0.0;
  collector_extent(scene, &lead, &rear);
  auto spans_for = [&](double length) { return static_cast<int>(std::ceil(length / span - 1e-9)); };
  const int margin = endless_margin(scene), behind = spans_for(std::max(behind_slow, behind_fast)) + 1;
  // In a turbulent wind the lateral plane is stepped a gust lead further ahead (lateral.hpp: by
  // its window, or on its own), snapped outward to a support once more.
  const double gusts = gust_lead_time(scene) * std::max(scene.train_speed, kMaxTrainSpeed);
  const int ahead = spans_for(std::max(ahead_slow, ahead_fast) + gusts) + (gusts > 0.0 ? 2 : 1);
  const int train = spans_for(lead - rear);
  // A 3-D line's stagger pattern repeats after `period` supports: the block moves by that many
  // spans (the rearmost collector stays within [home, home + period) spans).
  int period = 1;
  if (scene.stagger) {
    const int a = static_cast<int>(scene.stagger->contact_wire.size());
    const int b = std::max(1, static_cast<int>(scene.stagger->messenger.size()));
    period = a / std::gcd(a, b) * b;
  }
  const int home = margin + behind, count = home + period + train + ahead + margin;
  scene.spans.assign(count, span);
  scene.sections.front().spans = scene.spans;
  if (scene.sections.front().droppers) {
    auto& pos = scene.sections.front().droppers->positions;
    pos.assign(count, pos.front());
    scene.droppers = scene.sections.front().droppers;
  }
  if (scene.sections.front().hangers) {  // a compound line's
    auto& pos = scene.sections.front().hangers->positions;
    pos.assign(count, pos.front());
    scene.hangers = scene.sections.front().hangers;
  }
  m.endless = true;
  m.endless_span = span;
  m.endless_home = home * span;
  m.endless_shift_spans = period;
  m.rear_collector_offset = rear;
  // The block starts a whole number of spans behind, so that the line's supports stay at
  // multiples of the span.
  endless_front = scene.train_start ? *scene.train_start : -rear;
  const double shift = std::floor((endless_front + rear) / span) - home;
  m.initial_line_offset = shift * span;
  scene.train_start = endless_front - m.initial_line_offset;
  return endless_front;
}

// An endless line moves its state back a span at a time, which is exact only if the block's
// spans are identical where the window goes: same nodes, stations relative to the span, design
// heights (to 1 um, against wire motions of millimetres) and masses; same droppers. Sets
// Model::span_nodes.
void check_endless_block(Model& m) {
  const double span = m.endless_span;
  const int count = static_cast<int>(m.scene.spans.size());
  auto fail = [&](const std::string& what) {
    throw SceneError("line.endless: the model's spans are not identical (" + what +
                     "); the state cannot be moved back a span. Report this with the scene");
  };
  const int margin = endless_margin(m.scene);
  const Wire* last_stitch = nullptr;
  for (const Wire& w : m.wires) {
    if (w.is_clamped_wire) {
      // One at every intermediate support of the block: the move hands each one's state to the
      // one a span behind (shift_endless_block), so each must be the one before it a span on.
      const Wire* prev = last_stitch;
      last_stitch = &w;
      m.span_nodes.push_back(0);
      const int k = static_cast<int>(std::lround(0.5 * (w.x.front() + w.x.back()) / span));  // its support
      if (!prev || k <= margin - 1 || k > count - margin) continue;
      if (prev->nodes() != w.nodes()) fail(w.name + ": nodes");
      for (int i = 0; i < w.nodes(); ++i)
        if (std::fabs(w.x[i] - prev->x[i] - span) > 1e-9 * span || std::fabs(w.height[i] - prev->height[i]) > 1e-6 ||
            std::fabs(m.mass[w.w_dof + i] - m.mass[prev->w_dof + i]) > 1e-6 * m.mass[prev->w_dof + i])
          fail(w.name + " at x = " + fmt(w.x[i]) + " m");
      continue;
    }
    if (static_cast<int>(w.support_nodes.size()) != count + 1) fail(w.name + ": supports");
    const int first = margin - 1, last = count - margin;  // spans compared with the next
    const int ns = w.support_nodes[first + 1] - w.support_nodes[first];
    for (int k = first; k < last; ++k) {
      if (w.support_nodes[k + 1] - w.support_nodes[k] != ns || w.support_nodes[k + 2] - w.support_nodes[k + 1] != ns)
        fail(w.name + ": nodes per span");
      for (int i = w.support_nodes[k]; i < w.support_nodes[k + 1]; ++i) {
        const int j = i + ns;
        if (std::fabs(w.x[j] - w.x[i] - span) > 1e-9 * span || std::fabs(w.height[j] - w.height[i]) > 1e-6 ||
            std::fabs(m.mass[w.w_dof + j] - m.mass[w.w_dof + i]) > 1e-6 * m.mass[w.w_dof + i])
          fail(w.name + " at x = " + fmt(w.x[i]) + " m");
      }
    }
    m.span_nodes.push_back(ns);
  }
  const double tol = 1e-6;
  for (std::size_t k = 0; k < m.droppers.size(); ++k)
    for (std::size_t j = k + 1; j < m.droppers.size(); ++j) {
      const Dropper& a = m.droppers[k];
      const Dropper& b = m.droppers[j];
      if (a.span < margin - 1 || a.span >= count - margin || b.span != a.span + 1 || std::fabs(b.x - a.x - span) > 1e-9 * span) continue;
      if (std::fabs(b.static_tension - a.static_tension) > tol * std::fabs(a.static_tension) + 1e-9 ||
          std::fabs(b.stiffness - a.stiffness) > tol * a.stiffness)
        fail("dropper at x = " + fmt(a.x) + " m");
    }
  // A stitched line's clamps, span by span (in line order each one's twin a span on is two clamps on).
  for (std::size_t q = 0; q + 2 < m.clamp_order.size(); ++q) {
    const WireClamp& a = m.clamps[m.clamp_order[q]];
    const WireClamp& b = m.clamps[m.clamp_order[q + 2]];
    const int k = static_cast<int>(std::floor(a.x / span));
    if (k < margin - 1 || k >= count - margin || std::fabs(b.x - a.x - span) > 1e-9 * span) continue;
    if (std::fabs(b.static_force - a.static_force) > tol * std::fabs(a.static_force) + 1e-9)
      fail("stitch wire's clamp at x = " + fmt(a.x) + " m");
  }
}

}  // namespace catenary_sim
