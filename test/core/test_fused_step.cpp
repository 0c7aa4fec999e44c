// The fused explicit step (wire packs, runtime-dispatched vector kernel) against straightforward
// implementations of the same equations (eq. 19-22, 25, condensed rotations).
//
// The bound: zero. Each value is computed by the same sequence of IEEE-754 double operations
// (+, -, *, in the same order, the same rounding) as in the straightforward step: the fused kernel
// only changes which loop a node is in and packs the two wires' recurrences in the two lanes of a
// vector register (a lone wire's two halves, swept from both ends, whose twisted condensation the
// generic step takes too: twist_condensation), and packed lanes round exactly like scalar operations. There is no division in
// the step (the pivots' inverses are stored), no reassociation (no -ffast-math) and no FMA
// contraction (-ffp-contract=off, CMakeLists.txt), so whatever clone the dispatcher takes
// (AVX-512, AVX2, baseline), the results are the straightforward step's to the last bit; the
// statistics of a pass therefore equal those of 25f35a6, whose step was the straightforward one.
// A nonzero difference would mean a reordered operation, which the tests must catch: they compare
// bits, over whole passes (thousands of steps, where any round-off difference is amplified by the
// dynamics and would not stay hidden).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <string>
#include <vector>

#include "catenary_sim/core/simulation.hpp"
#include "catenary_sim/core/engine/initial_state.hpp"
#include "catenary_sim/core/model/wire_band.hpp"
#include "engine/window.hpp"
#include "../support/scenes.hpp"

using namespace catenary_sim;

namespace {

const std::string& kDir = test_scenes::kConfigDir;
using test_scenes::twin_contact_wire;

bool same_bits(const Eigen::VectorXd& a, const Eigen::VectorXd& b) {
  return a.size() == b.size() && std::memcmp(a.data(), b.data(), sizeof(double) * a.size()) == 0;
}

// The explicit step written out plainly for a full line (no window) with lumped pantographs:
// z = u + beta v, f = R - alpha M v - K z (wire by wire, condensed rotations), supports,
// tension-only droppers, pantograph chains with the uplift, the contact of eq. 12, 22, 25, then
// v += dt M^-1 f, u += dt v (eq. 20-21).
struct Plain {
  Eigen::VectorXd u, v, z, f;
  std::vector<double> theta;
};

void plain_step(const Model& m, const State& s, Plain& p) {
  const int n = m.n_dof, nc = m.n_catenary_dof;
  for (int i = 0; i < nc; ++i) {
    p.z[i] = p.u[i] + m.beta * p.v[i];
    p.f[i] = m.load[i] - m.alpha * m.mass[i] * p.v[i];
  }
  for (int i = nc; i < n; ++i) p.f[i] = 0.0;
  for (const Wire& w : m.wires) wire_elastic_force(w, p.z.data(), p.f.data(), p.theta.data());
  for (const SupportSpring& sp : m.springs) p.f[sp.dof] -= sp.stiffness * p.z[sp.dof];
  for (const Dropper& d : m.droppers) {
    if (!(d.static_tension + d.stiffness * (p.u[d.messenger_dof] - p.u[d.contact_dof]) > 0.0)) continue;
    const double t = std::max(0.0, d.static_tension + d.stiffness * (p.z[d.messenger_dof] - p.z[d.contact_dof]));
    p.f[d.contact_dof] += t;
    p.f[d.messenger_dof] -= t;
  }
  for (std::size_t pi = 0; pi < m.pantographs.size(); ++pi) {
    const Pantograph& pg = m.pantographs[pi];
    const int nm = pg.masses_count(), a0 = pg.first_dof;
    for (int i = 0; i < nm; ++i) {
      const int a = a0 + i;
      const bool roof = i + 1 == nm;
      const double c = pg.spring_preload[i] + pg.stiffness[i] * ((roof ? 0.0 : p.u[a + 1]) - p.u[a]) +
                       pg.damping[i] * ((roof ? 0.0 : p.v[a + 1]) - p.v[a]);
      p.f[a] += c;
      if (!roof) p.f[a + 1] -= c;
    }
    p.f[a0 + nm - 1] += s.uplift[pi] + pg.aero_coefficient * s.speed * s.speed;
  }
  std::vector<int> node(m.max_contact_nodes);
  std::vector<double> weight(m.max_contact_nodes);
  for (const Pantograph& pg : m.pantographs) {
    const double head = pg.reference_height + p.u[pg.first_dof];
    for (int ci : pg.collectors)
      for (int cw : m.contact_wires) {
        const Wire& w = m.wires[cw];
        const int cnt = contact_weights(w, m.rub_length, s.front - pg.position + m.collectors[ci].offset, node.data(),
                                        weight.data());
        if (!cnt) continue;
        double yw = 0.0;
        for (int a = 0; a < cnt; ++a) yw += weight[a] * (w.height[node[a]] + p.u[w.w_dof + node[a]]);
        const double fc = std::max(0.0, m.contact_stiffness * (head - yw));
        if (fc == 0.0) continue;
        p.f[pg.first_dof] -= fc;
        for (int a = 0; a < cnt; ++a) p.f[w.w_dof + node[a]] += fc * weight[a];
      }
  }
  for (int i = 0; i < n; ++i) {
    p.v[i] = p.v[i] + m.dt * (m.inv_mass[i] * p.f[i]);
    p.u[i] = p.u[i] + m.dt * p.v[i];
  }
}

}  // namespace

TEST(FusedStep, TakesTheWirePacks) {
  // Contact wire and messenger of the section share their stations: one pack of two lanes.
  const Model m = build_model(load_scene_file(kDir + "reference_55m.yaml"));
  ASSERT_EQ(wire_pack_count(m), 1);
  EXPECT_EQ(wire_pack_lanes(m, 0), 2);
  // Rotations as DOFs or the implicit scheme: no packs, the generic step.
  EXPECT_EQ(wire_pack_count(build_model(load_scene_file(kDir + "reference_55m.yaml", {"numerics.rotary_inertia=lumped"}))), 0);
  EXPECT_EQ(wire_pack_count(build_model(load_scene_file(kDir + "reference_55m.yaml", {"numerics.integrator=implicit"}))), 0);
  const std::string isa = sweep_pack_isa();
  EXPECT_TRUE(isa == "x86-64-v4" || isa == "x86-64-v3" || isa == "default") << isa;
}

// A lone wire of the fused step is swept from both ends (its two halves in the two lanes), its
// condensed rotations from a twisted factorisation meeting at its middle node: K_theta_theta
// theta = -K_theta_w z solved by another order of elimination. Both solve the same system, so the
// band forces and rotations agree to rounding. The bound: K_theta_theta of a tensioned beam is
// strictly diagonally dominant (8 EI / h on the diagonal against 2 EI / h either side, plus the
// tension's share), its condition number below 3, so each solve is within a few n eps of the exact
// one; 1e-12 of the largest force is 50x the 2001 nodes' n eps (4.4e-13) and far below what a
// wrong coefficient, sign or meeting row gives (the size of the forces themselves).
TEST(FusedStep, ALoneWireSweptFromBothEndsGivesTheWholeWiresForces) {
  struct Case {
    Scene scene;
    std::string wire;
  };
  const std::vector<Case> cases{{load_scene_file(kDir + "compound_catenary.yaml"), "auxiliary messenger"},
                                {twin_contact_wire({}), "lone contact wire"}};
  for (const Case& c : cases) {
    SCOPED_TRACE(c.wire);
    const Model m = build_model(c.scene);
    int twisted = 0;
    for (const Wire& w : m.wires) {
      if (w.twisted_meeting < 0) continue;
      ++twisted;
      EXPECT_EQ(w.twisted_meeting, (w.nodes() - 1) / 2);
      Wire whole = w;
      whole.twisted_meeting = -1;
      // A displacement with every wavelength (a random field) and a smooth sag.
      std::vector<double> z(m.n_dof, 0.0), f_twisted(m.n_dof, 0.0), f_whole(m.n_dof, 0.0);
      std::vector<double> th_twisted(w.nodes()), th_whole(w.nodes());
      unsigned long seed = 12345;
      for (int i = 0; i < w.nodes(); ++i) {
        seed = seed * 6364136223846793005ul + 1442695040888963407ul;
        const double x = (w.x[i] - w.x.front()) / (w.x.back() - w.x.front());
        z[w.w_dof + i] = 0.05 * std::sin(3.14159 * x) + 1e-3 * (static_cast<double>(seed >> 11) / 9007199254740992.0 - 0.5);
      }
      wire_elastic_force(w, z.data(), f_twisted.data(), th_twisted.data());
      wire_elastic_force(whole, z.data(), f_whole.data(), th_whole.data());
      double f_max = 0.0, f_diff = 0.0, th_max = 0.0, th_diff = 0.0;
      for (int i = 0; i < w.nodes(); ++i) {
        f_max = std::max(f_max, std::fabs(f_whole[w.w_dof + i]));
        f_diff = std::max(f_diff, std::fabs(f_twisted[w.w_dof + i] - f_whole[w.w_dof + i]));
        th_max = std::max(th_max, std::fabs(th_whole[i]));
        th_diff = std::max(th_diff, std::fabs(th_twisted[i] - th_whole[i]));
      }
      ASSERT_GT(f_max, 0.0);
      EXPECT_LE(f_diff, 1e-12 * f_max) << "largest force " << f_max;
      EXPECT_LE(th_diff, 1e-12 * th_max) << "largest rotation " << th_max;
    }
    EXPECT_EQ(twisted, 1);
  }
  // Short wires, down to three nodes (one station each side of the meeting): a bridle's 8 m at
  // 0.25 m elements is 33.
  for (const int n : {3, 5, 7, 33}) {
    Wire w;
    for (int i = 0; i < n; ++i) w.x.push_back(0.25 * i);
    w.spec.bending_stiffness = 195.0;
    w.spec.tension = 20000.0;
    assemble_band(w, {});
    Wire whole = w;
    twist_condensation(w);
    std::vector<double> z(n), f_twisted(n, 0.0), f_whole(n, 0.0), th(n);
    for (int i = 0; i < n; ++i) z[i] = 1e-3 * std::sin(1.0 + 2.3 * i);
    wire_elastic_force(w, z.data(), f_twisted.data(), th.data());
    wire_elastic_force(whole, z.data(), f_whole.data(), th.data());
    double f_max = 0.0;
    for (int i = 0; i < n; ++i) f_max = std::max(f_max, std::fabs(f_whole[i]));
    for (int i = 0; i < n; ++i) EXPECT_NEAR(f_twisted[i], f_whole[i], 1e-12 * f_max) << n << " nodes, node " << i;
  }
  // In a moving window the window's nodes meet in its middle (an odd count: windows end on
  // supports, 200 elements a span here), their factors those of the window's K_theta_theta with
  // the cut elements left out: against the window's own elimination, to the same bound.
  {
    const Model m = build_model(load_scene_file(kDir + "compound_catenary.yaml", {"numerics.window=auto"}));
    State s = make_state(m);
    solve_initial_state(m, s);
    for (int k = 0; k < 5000; ++k) ASSERT_EQ(step(m, s), StepStatus::kOk);  // 200 m on: the window cut at both ends
    int twisted = 0;
    for (std::size_t wi = 0; wi < m.wires.size(); ++wi) {
      const Wire& w = m.wires[wi];
      EXPECT_LT(w.twisted_meeting, 0);  // (the whole wire's: not in a window)
      if (!w.twisted) continue;
      ++twisted;
      const WireWindow& ww = s.window[wi];
      ASSERT_TRUE(ww.cut_lo && ww.cut_hi);
      ASSERT_EQ(ww.meet, (ww.hi - ww.lo) / 2);
      WireWindow one_lane = ww;
      one_lane.meet = -1;
      // A displacement on every node of the window, its ends too (the state is at rest ahead).
      std::vector<double> z(m.n_dof, 0.0), f_twisted(m.n_dof, 0.0), f_window(m.n_dof, 0.0), th(w.nodes());
      for (int i = ww.lo; i <= ww.hi; ++i) z[w.w_dof + i] = s.u[w.w_dof + i] + 1e-3 * std::sin(0.7 * i);
      wire_elastic_force_window(w, ww, z.data(), f_twisted.data(), th.data());
      wire_elastic_force_window(w, one_lane, z.data(), f_window.data(), th.data());
      double f_max = 0.0, f_diff = 0.0;
      for (int i = ww.lo; i <= ww.hi; ++i) {
        f_max = std::max(f_max, std::fabs(f_window[w.w_dof + i]));
        f_diff = std::max(f_diff, std::fabs(f_twisted[w.w_dof + i] - f_window[w.w_dof + i]));
      }
      ASSERT_GT(f_max, 0.0);
      EXPECT_LE(f_diff, 1e-12 * f_max) << "largest force " << f_max;
    }
    EXPECT_EQ(twisted, 1);
  }
  // The 3-D line and the centred step keep one lane per lone wire.
  for (const Wire& w : build_model(load_scene_file(kDir + "compound_catenary.yaml", {"numerics.damping=centred"})).wires)
    EXPECT_FALSE(w.twisted);
  for (const Wire& w : build_model(load_scene_file(kDir + "compound_catenary_3d.yaml")).wires) EXPECT_FALSE(w.twisted);
}

TEST(FusedStep, MatchesThePlainStepBitForBitOverAPass) {
  // The reference pass at 300 km/h (accurate preset): every step's displacements and velocities.
  Simulation sim(load_scene_file(kDir + "reference_55m.yaml"));
  const Model& m = sim.model();
  ASSERT_GT(wire_pack_count(m), 0);
  Plain p{sim.state().u, sim.state().v, Eigen::VectorXd::Zero(m.n_dof), Eigen::VectorXd::Zero(m.n_dof),
          std::vector<double>(m.n_catenary_dof)};
  long steps = 0;
  while (true) {
    const State before = sim.state();
    if (sim.step() != StepStatus::kOk) break;
    plain_step(m, before, p);
    ++steps;
    ASSERT_TRUE(same_bits(sim.state().u, p.u)) << "displacements differ at step " << steps;
    ASSERT_TRUE(same_bits(sim.state().v, p.v)) << "velocities differ at step " << steps;
  }
  EXPECT_GT(steps, 7000);  // the whole pass (550 m at 300 km/h, dt 0.87 ms)
  EXPECT_EQ(sim.state().status, StepStatus::kFinished);
}

// The fused step against the library's generic step (the same model with its packs removed) on
// the other ways a pass runs: the moving window, the endless line, two pantographs, two sections
// (an overlap: two packs), the coarsest rung and the half-step's finest (h = 0.1 m, the reference
// preset's rung where the centred step does not go, e.g. beta 0; the centred step has its own
// tests, test_centred_damping.cpp), a twin contact wire (a pack of one wire beside one of two), with
// and without a window, and a compound line (its auxiliary a pack of its own; hangers and droppers
// as point forces on three wires), with and without a window, and a trolley wire on bridles.
TEST(FusedStep, MatchesTheGenericStepBitForBit) {
  struct Case {
    std::string file;
    std::vector<std::string> overrides;
    long steps;
  };
  const std::vector<Case> cases{
      {"reference_55m.yaml", {"numerics.window=auto"}, 4000},
      {"reference_55m_endless.yaml", {}, 4000},
      {"reference_55m_two_pantographs.yaml", {}, 3000},
      {"reference_55m_two_sections.yaml", {}, 3000},
      // The window reaching the second section's wires (at about step 3200).
      {"reference_55m_two_sections.yaml", {"numerics.window=auto"}, 4500},
      {"reference_55m_stitched.yaml", {}, 3000},  // stitch wires: packs of one, clamps as point forces
      {"reference_55m_stitched.yaml", {"numerics.window=auto"}, 3000},  // the window's clamp lists
      {"reference_55m.yaml", {"numerics.preset=fast", "train.speed_kmh=250"}, 2000},
      // The supports at the step's middle, and their window lists.
      {"reference_55m.yaml", {"numerics.supports=implicit", "numerics.preset=fast"}, 2000},
      {"reference_55m.yaml", {"numerics.supports=implicit", "numerics.preset=fast", "numerics.window=auto"}, 2000},
      {"reference_55m_endless.yaml", {"numerics.supports=implicit", "numerics.preset=balanced"}, 3000},
      {"reference_55m_stitched.yaml", {"numerics.supports=implicit", "numerics.preset=balanced"}, 2000},
      {"twin", {"numerics.supports=implicit", "numerics.preset=fast"}, 2000},
      {"compound_catenary.yaml", {"numerics.supports=implicit", "numerics.preset=fast", "numerics.droppers=explicit"}, 2000},
      {"compound_catenary.yaml", {"numerics.preset=fast"}, 2000},
      // The droppers and clamps at the step's middle too (the fast preset on a 2-D line), and their
      // window lists; the stitched line's clamps; a compound line's droppers and hangers.
      {"reference_55m.yaml", {"numerics.preset=fast", "numerics.window=auto"}, 2000},
      {"reference_55m_endless.yaml", {"numerics.preset=fast"}, 2000},
      {"reference_55m_stitched.yaml", {"numerics.preset=fast"}, 2000},
      {"reference_55m_stitched.yaml", {"numerics.preset=fast", "numerics.window=auto"}, 2000},
      {"reference_55m_two_pantographs.yaml", {"numerics.preset=fast"}, 2000},
      {"reference_55m.yaml", {"numerics.droppers=implicit", "numerics.preset=balanced"}, 2000},
      {"twin", {"numerics.preset=fast"}, 2000},
      {"reference_55m.yaml", {"numerics.element_length=0.1"}, 1500},
      {"twin", {}, 2000},
      {"twin", {"numerics.window=auto", "train.speed_kmh=250"}, 3000},
      {"compound_catenary.yaml", {}, 3000},
      {"compound_catenary.yaml", {"numerics.window=auto"}, 3000},
      // A trolley wire on bridles: packs of one wire (the bridles pair up), clamps below them.
      {"trolley_wire_bridle.yaml", {"numerics.damping=half_step"}, 3000},
  };
  for (const Case& c : cases) {
    SCOPED_TRACE(c.file + (c.overrides.empty() ? "" : " " + c.overrides.front()));
    const Scene scene = c.file == "twin" ? twin_contact_wire(c.overrides) : load_scene_file(kDir + c.file, c.overrides);
    Model fused = build_model(scene);
    ASSERT_GT(wire_pack_count(fused), 0);
    if (c.file == "twin") {
      ASSERT_EQ(wire_pack_count(fused), 2);
      EXPECT_EQ(wire_pack_lanes(fused, 1), 1);
    }
    Model generic = fused;
    generic.wire_packs.reset();
    State a = make_state(fused), b = make_state(generic);
    solve_initial_state(fused, a);
    solve_initial_state(generic, b);
    ASSERT_TRUE(same_bits(a.u, b.u));
    for (long k = 0; k < c.steps; ++k) {
      const StepStatus sa = step(fused, a), sb = step(generic, b);
      ASSERT_EQ(sa, sb) << "step " << k;
      if (sa != StepStatus::kOk) break;
      ASSERT_TRUE(same_bits(a.u, b.u)) << "displacements differ at step " << k;
      ASSERT_TRUE(same_bits(a.v, b.v)) << "velocities differ at step " << k;
      ASSERT_TRUE(same_bits(a.accel, b.accel)) << "accelerations differ at step " << k;
      ASSERT_EQ(0, std::memcmp(a.contact_force.data(), b.contact_force.data(), sizeof(double) * a.contact_force.size()));
      ASSERT_EQ(a.line_offset, b.line_offset);
    }
  }
}

TEST(FusedStep, StopsAtTheSameDivergedDof) {
  // dt above the stability limit on purpose (the watchdog's case): both steps stop at the same
  // step and name the same DOF, and the state keeps the last good step; with the supports, and then
  // the droppers, at the step's middle too, whose corrected nodes both steps scan again.
  for (const char* springs : {"explicit", "supports", "droppers"}) {
    SCOPED_TRACE(springs);
    const std::string middle = springs == std::string("explicit") ? "explicit" : "implicit";
    const Scene scene = load_scene_file(kDir + "reference_55m.yaml",
                                        {"numerics.element_length=1.0", "numerics.supports=" + middle,
                                         std::string("numerics.droppers=") + (springs == std::string("droppers") ? "implicit" : "explicit")});
    Model fused = build_model(scene);
    fused.dt *= 2.5;  // beyond the limit: only a test may do this (build_model refuses it)
    Model generic = fused;
    generic.wire_packs.reset();
    State a = make_state(fused), b = make_state(generic);
    solve_initial_state(fused, a);
    solve_initial_state(generic, b);
    int k = 0;
    for (; k < 200000 && a.status == StepStatus::kOk; ++k) {
      const Eigen::VectorXd before = a.u;
      ASSERT_EQ(step(fused, a), step(generic, b));
      if (a.status == StepStatus::kDiverged) {
        EXPECT_TRUE(same_bits(a.u, before));
      }
    }
    ASSERT_EQ(a.status, StepStatus::kDiverged) << "did not diverge in " << k << " steps";
    EXPECT_EQ(a.diverged_dof, b.diverged_dof);
    EXPECT_TRUE(same_bits(a.u, b.u));
  }
}
