// The design state's balance (gtest). Header-only.
#pragma once

#include <gtest/gtest.h>

#include <Eigen/Core>

#include "catenary_sim/core/model/model.hpp"

namespace test_scenes {

// On every free wire node the constant load (weights, support preloads, -K y_design) is balanced
// by the droppers' (hangers') and stitch clamps' design forces alone, so the line hangs still
// until a pantograph comes. Round-off only: 1e-9 of the node's weight. A node on a support spring
// is left out: the spring's preload is its static reaction, in the load.
inline void expect_design_equilibrium(const catenary_sim::Model& m) {
  Eigen::VectorXd f = m.load;
  for (const catenary_sim::Dropper& d : m.droppers) {
    f[d.contact_dof] += d.static_tension;
    f[d.messenger_dof] -= d.static_tension;
  }
  for (const catenary_sim::WireClamp& c : m.clamps) {
    f[c.lower_dof] += c.static_force;
    f[c.upper_dof] -= c.static_force;
  }
  for (const catenary_sim::Wire& w : m.wires)
    for (int i = 0; i < w.nodes(); ++i) {
      const int dof = w.w_dof + i;
      if (m.inv_mass[dof] == 0.0) continue;  // held
      bool spring = false;
      for (const catenary_sim::SupportSpring& sp : m.springs) spring |= sp.dof == dof;
      if (spring) continue;
      EXPECT_NEAR(f[dof], 0.0, 1e-9 * m.mass[dof] * 9.81) << w.name << " node " << i;
    }
}

}  // namespace test_scenes
