// One wire, or two on the same node stations, per pack: the fused step runs their independent
// condensation sweeps in the lanes of one vector register (engine/wire_lanes.cpp). The packs hold
// copies of the wires' band, factors, load and masses, laid out per node and lane.
#include "model/wire_packs.hpp"

namespace catenary_sim {

void build_wire_packs(Model& m) {
  m.wire_packs.clear();
  m.wire_pack.assign(m.wires.size(), -1);
  m.wire_lane.assign(m.wires.size(), 0);
  m.sweep_size = 0;
  if (m.implicit) return;
  int catenary = 0;
  for (const Wire& w : m.wires) {
    if (w.theta_dof >= 0 || w.nodes() < 2) return;  // rotations as DOFs: the generic step
    catenary += w.nodes();
  }
  if (catenary != m.n_catenary_dof) return;
  for (std::size_t a = 0; a < m.wires.size(); ++a) {
    if (m.wire_pack[a] >= 0) continue;
    WireLanes p;
    p.wire[0] = static_cast<int>(a);
    // A partner on the same stations: the same node range in a moving window, too.
    for (std::size_t b = a + 1; b < m.wires.size() && p.lanes == 1; ++b)
      if (m.wire_pack[b] < 0 && m.wires[b].x == m.wires[a].x) {
        p.wire[1] = static_cast<int>(b);
        p.lanes = 2;
      }
    const int n = m.wires[a].nodes(), L = p.lanes;
    p.nodes = n;
    p.offset = m.sweep_size;
    m.sweep_size += static_cast<std::size_t>(n) * L;
    p.coef.assign(static_cast<std::size_t>(n) * WireLanes::kCoefficients * L, 0.0);
    p.factors.assign(static_cast<std::size_t>(n) * 2 * L, 0.0);
    for (int k = 0; k < L; ++k) {
      const Wire& w = m.wires[p.wire[k]];
      m.wire_pack[p.wire[k]] = static_cast<int>(m.wire_packs.size());
      m.wire_lane[p.wire[k]] = k;
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
    m.wire_packs.push_back(std::move(p));
  }
  m.dof_sweep_force.assign(m.n_catenary_dof, 0);
  m.dof_sweep_z.assign(m.n_catenary_dof, 0);
  for (const WireLanes& p : m.wire_packs)
    for (int k = 0; k < p.lanes; ++k)
      for (int i = 0; i < p.nodes; ++i) {
        const std::size_t r = kSweepRecord * p.offset + static_cast<std::size_t>(i) * kSweepRecord * p.lanes + k;
        m.dof_sweep_force[m.wires[p.wire[k]].w_dof + i] = static_cast<int>(r + kRecForce * p.lanes);
        m.dof_sweep_z[m.wires[p.wire[k]].w_dof + i] = static_cast<int>(r + kRecZ * p.lanes);
      }
}

}  // namespace catenary_sim
