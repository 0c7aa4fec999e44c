// One wire, or two on the same node stations, per pack: the fused step runs their independent
// condensation sweeps in the lanes of one vector register (engine/wire_lanes.cpp). The packs hold
// copies of the wires' band, factors, load and masses, laid out per node and lane.
#include "model/wire_packs.hpp"

#include <cassert>

#include "catenary_sim/core/model/wire_band.hpp"
#include "catenary_sim/core/model/wire_packs.hpp"
#include "model/twisted_half.hpp"

namespace catenary_sim {

namespace {

// Whether pack p's lone wire is swept from both ends (Wire::twisted): on a 2-D line with the
// half-step damping (the lateral plane and the centred step lay out their own sweeps per node).
// A wire stepped whole needs an odd count of nodes, so that the two halves meet at one; in a
// window the window's count decides (WireWindow::meet). (A bridle's 33 nodes so swept measured
// 0.98-0.99 of one lane's cost.)
bool sweeps_from_both_ends(const Model& m, const WireLanes& p) {
  return p.lanes == 1 && p.nodes >= 3 && !m.scene.lateral() && m.scene.numerics.damping != DampingStep::kCentred &&
         (m.scene.numerics.windowed() || p.nodes % 2 == 1);
}

}  // namespace

void lay_out_twisted(const Model& m, const TwistedRange& r, double* coef, double* factors) {
  constexpr int L = 2, NC = WireLanes::kCoefficients;
  for (int k = 0; k <= r.meet; ++k) {
    double* c = coef + static_cast<std::size_t>(k) * NC * L;
    double* f = factors + static_cast<std::size_t>(k) * 2 * L;
    for (int lane = 0; lane < L; ++lane) {
      const TwistedHalf h{r, lane == 1};
      const int dof = r.w->w_dof + h.node(k);
      c[WireLanes::kDww * L + lane] = h.dww(k);
      c[WireLanes::kDwt * L + lane] = h.dwt(k);
      c[WireLanes::kEww * L + lane] = h.eww(k);
      c[WireLanes::kEwt * L + lane] = h.ewt(k);
      c[WireLanes::kEtw * L + lane] = h.etw(k);
      c[WireLanes::kLoad * L + lane] = m.load[dof];
      c[WireLanes::kDampingMass * L + lane] = m.alpha * m.mass[dof];
      c[WireLanes::kInvMass * L + lane] = m.inv_mass[dof];
      f[lane] = h.lower(k);
      f[L + lane] = h.inv_pivot(k);
    }
  }
}

std::shared_ptr<WirePacks> build_wire_packs(Model& m) {
  for (Wire& w : m.wires) {  // (chosen again below)
    w.twisted = false;
    w.twisted_meeting = -1;
  }
  if (m.implicit || m.wires.empty()) return nullptr;
  int catenary = 0;
  for (const Wire& w : m.wires) {
    if (w.theta_dof >= 0 || w.nodes() < 2) return nullptr;  // rotations as DOFs: the generic step
    catenary += w.nodes();
  }
  if (catenary != m.n_catenary_dof) return nullptr;
  auto packs = std::make_shared<WirePacks>();
  WirePacks& pk = *packs;
  pk.wire_pack.assign(m.wires.size(), -1);
  pk.wire_lane.assign(m.wires.size(), 0);
  for (std::size_t a = 0; a < m.wires.size(); ++a) {
    if (pk.wire_pack[a] >= 0) continue;
    WireLanes p;
    p.wire[0] = static_cast<int>(a);
    // A partner on the same stations: the same node range in a moving window, too. Without a
    // window the lanes need only as many nodes: two stitch wires of a section pair up (their
    // sweeps read no station), so the short wires around the supports do not run a lane idle.
    auto partners = [&](const Wire& wa, const Wire& wb) {
      if (wb.x == wa.x) return true;
      return !m.scene.numerics.windowed() && wa.is_clamped_wire && wb.is_clamped_wire && wa.nodes() == wb.nodes();
    };
    for (std::size_t b = a + 1; b < m.wires.size() && p.lanes == 1; ++b)
      if (pk.wire_pack[b] < 0 && partners(m.wires[a], m.wires[b])) {
        p.wire[1] = static_cast<int>(b);
        p.lanes = 2;
      }
    const int n = m.wires[a].nodes(), L = p.lanes;
    p.nodes = n;
    p.offset = pk.sweep_size;
    pk.sweep_size += static_cast<std::size_t>(n) * L;
    p.coef.assign(static_cast<std::size_t>(n) * WireLanes::kCoefficients * L, 0.0);
    p.factors.assign(static_cast<std::size_t>(n) * 2 * L, 0.0);
    for (int k = 0; k < L; ++k) {
      const Wire& w = m.wires[p.wire[k]];
      pk.wire_pack[p.wire[k]] = static_cast<int>(pk.packs.size());
      pk.wire_lane[p.wire[k]] = k;
      for (int i = 0; i < n; ++i) {
        double* c = p.coef.data() + static_cast<std::size_t>(i) * WireLanes::kCoefficients * L + k;
        c[WireLanes::kDww * L] = w.d_ww[i];
        c[WireLanes::kDwt * L] = w.d_wt[i];
        if (i + 1 < n) {
          c[WireLanes::kEww * L] = w.e_ww[i];
          c[WireLanes::kEwt * L] = w.e_wt[i];
          c[WireLanes::kEtw * L] = w.e_tw[i];
        }
        c[WireLanes::kLoad * L] = m.load[w.w_dof + i];
        c[WireLanes::kDampingMass * L] = m.alpha * m.mass[w.w_dof + i];  // the generic step's alpha * mass[i] * v[i]
        c[WireLanes::kInvMass * L] = m.inv_mass[w.w_dof + i];
        p.factors[(static_cast<std::size_t>(i) * 2 + 0) * L + k] = w.tt_lower[i];
        p.factors[(static_cast<std::size_t>(i) * 2 + 1) * L + k] = w.tt_inv_pivot[i];
      }
    }
    if (sweeps_from_both_ends(m, p)) {
      Wire& w = m.wires[p.wire[0]];
      w.twisted = true;
      if (!m.scene.numerics.windowed()) {
        twist_condensation(w);
        const TwistedRange r = whole_wire_range(w);
        p.twisted_coef.assign(static_cast<std::size_t>(r.meet + 1) * WireLanes::kCoefficients * 2, 0.0);
        p.twisted_factors.assign(static_cast<std::size_t>(r.meet + 1) * 2 * 2, 0.0);
        lay_out_twisted(m, r, p.twisted_coef.data(), p.twisted_factors.data());
        pk.sweep_size += 1;  // stations up to the meeting in both lanes: the meeting node twice
      }
    }
    pk.packs.push_back(std::move(p));
  }
  for (std::vector<int>* at : {&pk.dof_sweep_force, &pk.dof_joint_force}) at->assign(m.n_catenary_dof, 0);
  for (const WireLanes& p : pk.packs) {
    const int meet = m.wires[p.wire[0]].twisted_meeting;
    if (p.lanes == 1 && meet >= 0) {  // node i at station i in lane 0 up to the meeting, then mirrored in lane 1
      for (int i = 0; i < p.nodes; ++i) {
        const int lane = i > meet ? 1 : 0, station = lane ? p.nodes - 1 - i : i;
        const std::size_t f = kSweepRecord * p.offset + static_cast<std::size_t>(station) * kSweepRecord * 2 + kRecForce * 2 + lane;
        pk.dof_sweep_force[m.wires[p.wire[0]].w_dof + i] = static_cast<int>(f);
        pk.dof_joint_force[m.wires[p.wire[0]].w_dof + i] = -1;  // (no lateral plane)
      }
      continue;
    }
    for (int k = 0; k < p.lanes; ++k)
      for (int i = 0; i < p.nodes; ++i) {
        const int dof = m.wires[p.wire[k]].w_dof + i;
        // [node][value][lane] from the pack's offset; in the joint records [node][value][2 lanes
        // per wire] from twice that offset, the vertical plane's first: 2 r - k.
        const std::size_t r = kSweepRecord * p.offset + static_cast<std::size_t>(i) * kSweepRecord * p.lanes + k;
        const std::size_t f = r + kRecForce * p.lanes;
        pk.dof_sweep_force[dof] = static_cast<int>(f);
        pk.dof_joint_force[dof] = static_cast<int>(2 * f - k);
      }
  }
  return packs;
}

int wire_pack_count(const Model& m) { return m.wire_packs ? static_cast<int>(m.wire_packs->packs.size()) : 0; }

int wire_pack_lanes(const Model& m, int pack) {
  assert(pack >= 0 && pack < wire_pack_count(m));
  return m.wire_packs->packs[pack].lanes;
}

}  // namespace catenary_sim
