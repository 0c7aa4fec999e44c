// Pantographs with heads (the paper's Section VI: "pantograph models with two head masses"): a
// frame chain topped by heads, each a mass on its own suspension carrying its strips, every strip
// switched on its own force against every wire under it (eq. 22, 25).
#include <gtest/gtest.h>
#include <yaml-cpp/yaml.h>

#include <nlohmann/json.hpp>

#include <cmath>
#include <sstream>
#include <utility>

#include "catenary_sim/core/simulation.hpp"
#include "catenary_sim/core/output/statistics.hpp"
#include "../support/scenes.hpp"

using namespace catenary_sim;

namespace {

YAML::Node calpe() { return YAML::LoadFile(test_scenes::kCalpeExample); }

Scene load(const YAML::Node& root) {
  std::stringstream s;
  s << root;
  return load_scene_string(s.str());
}

// The paper's pantograph (head 7.2 kg on 4200 N/m, 10 N s/m; frame 15 kg on 50 N/m, 100 N s/m)
// as two heads of half the head each, side by side at the same station (one strip each).
YAML::Node two_half_heads(double offset_a, double offset_b, double k_a, double k_b) {
  YAML::Node p = calpe()["pantographs"][0];
  p["masses"] = std::vector<double>{15.0};
  p["stiffness"] = std::vector<double>{50.0};
  p["damping"] = std::vector<double>{100.0};
  YAML::Node heads;
  for (auto [off, k] : {std::pair{offset_a, k_a}, std::pair{offset_b, k_b}}) {
    YAML::Node h;
    h["mass"] = 3.6;
    h["stiffness"] = k;
    h["damping"] = 5.0;
    h["offset"] = off;
    heads.push_back(h);
  }
  p["heads"] = heads;
  return p;
}

// The paper's scene twice: with its one-head pantograph carrying two strips at its station, and
// with that pantograph as two half heads at the same station (the same sum).
std::pair<YAML::Node, YAML::Node> one_head_and_two_halves() {
  YAML::Node one = calpe();
  YAML::Node strips;
  for (int i = 0; i < 2; ++i) strips.push_back(YAML::Load("{offset: 0.0}"));
  one["pantographs"][0]["collectors"] = strips;
  YAML::Node two = calpe();
  two["pantographs"][0] = two_half_heads(0.0, 0.0, 2100.0, 2100.0);
  return {one, two};
}

std::vector<PantographStatistics> run(const Scene& scene) {
  Simulation sim(scene);
  PassRecorder rec(sim.model());
  rec.record(sim.model(), sim.state());
  while (sim.step() == StepStatus::kOk) rec.record(sim.model(), sim.state());
  EXPECT_EQ(sim.state().status, StepStatus::kFinished) << sim.status_message();
  return rec.statistics(sim.model());
}

std::string error_of(const YAML::Node& root) {
  try {
    load(root);
  } catch (const SceneError& e) {
    return e.what();
  }
  return "(no error)";
}

}  // namespace

// Two identical heads at one station, each half the paper's head on half its suspension, move as
// one (same equations, same excitation): the pass equals the one-head chain with two strips at
// that station. The models are the same algebra summed in another order; round-off (1e-16 per
// operation) carried through ~1e5 steps of a stable system stays many orders below 1e-9.
TEST(PantographHeads, TwoIdenticalHeadsTogetherAreTheOneHeadModel) {
  auto [one, two] = one_head_and_two_halves();
  // The same step for both (the automatic one bounds each contact by its own head mass).
  one["numerics"]["dt"] = two["numerics"]["dt"] = 2e-5;
  const auto a = run(load(one)), b = run(load(two));
  ASSERT_EQ(a.size(), 1u);
  ASSERT_EQ(b.size(), 1u);
  EXPECT_NEAR(b[0].filtered.mean, a[0].filtered.mean, 1e-9 * a[0].filtered.mean);
  EXPECT_NEAR(b[0].filtered.std_dev, a[0].filtered.std_dev, 1e-9 * a[0].filtered.std_dev);
  EXPECT_NEAR(b[0].filtered.max, a[0].filtered.max, 1e-9 * a[0].filtered.max);
  EXPECT_NEAR(b[0].unfiltered.min, a[0].unfiltered.min, 1e-9 * a[0].filtered.max);
}

// The same with the implicit integrator (the heads' suspensions in its Newmark matrix, each strip
// a rank-1 correction): the same reduction, to the same round-off.
TEST(PantographHeads, ImplicitIntegratorReducesAlike) {
  auto [one, two] = one_head_and_two_halves();
  for (YAML::Node* r : {&one, &two}) (*r)["numerics"]["integrator"] = "implicit";
  const auto a = run(load(one)), b = run(load(two));
  EXPECT_NEAR(b[0].filtered.mean, a[0].filtered.mean, 1e-9 * a[0].filtered.mean);
  EXPECT_NEAR(b[0].filtered.std_dev, a[0].filtered.std_dev, 1e-9 * a[0].filtered.std_dev);
}

// Static load split (eq. 23): head h is the contact spring k0 in series with its suspension k_h,
// s_h = 1 / (1/k0 + 1/k_h), and carries f_h = s_h (c - y_h) + s_h p_h / k_h with y_h the wire
// height under its strip, p_h its suspension preload (half the uplift) and c the top frame mass's
// height plus its reference, common to both. The roof spring is relaxed there, so f_a + f_b = F,
// which fixes c. Strips 2 m apart on a sagging span see different wire heights, and the stiffer
// head takes more of the difference.
TEST(PantographHeads, StaticLoadSplitFollowsTheSuspensions) {
  YAML::Node root = calpe();
  const double ka = 2000.0, kb = 8000.0;
  root["pantographs"][0] = two_half_heads(-1.0, 1.0, ka, kb);
  root["train"]["start"] = 26.0;  // the heads at 25 and 27 m: the wire falls towards mid-span
  Simulation sim(load(root));
  const Model& m = sim.model();
  const State& s = sim.state();
  const Pantograph& p = m.pantographs[0];
  ASSERT_EQ(p.heads.size(), 2u);
  const double k0 = m.contact_stiffness, F = p.static_uplift;
  double f[2], y[2], sh[2];
  const int nw = static_cast<int>(m.contact_wires.size());
  for (int h = 0; h < 2; ++h) {
    const int ci = p.heads[h].collectors[0];
    int touching = 0;
    for (int w = 0; w < nw; ++w)
      if (s.contact_force_on(m, ci, w) > 0.0) {
        ++touching;
        f[h] = s.contact_force_on(m, ci, w);
        y[h] = s.wire_height_under(m, ci, w) - p.heads[h].reference_height;  // both measured from their reference
      }
    ASSERT_EQ(touching, 1) << "a current span: one wire under each strip";
    sh[h] = 1.0 / (1.0 / k0 + 1.0 / p.heads[h].stiffness);
    ASSERT_GT(f[h], 0.0);
  }
  EXPECT_NEAR(f[0] + f[1], F, 1e-6 * F);
  const double pre = F / 2;
  const double c = (F + sh[0] * y[0] + sh[1] * y[1] - sh[0] * pre / ka - sh[1] * pre / kb) / (sh[0] + sh[1]);
  const double fa = sh[0] * (c - y[0]) + sh[0] * pre / ka;
  // The static solve is a sparse direct solve: relative 1e-9 of the forces.
  EXPECT_NEAR(f[0], fa, 1e-9 * F);
  EXPECT_NEAR(f[1], F - fa, 1e-9 * F);
  EXPECT_GT(std::fabs(f[0] - f[1]), 0.05) << "the geometry must make a difference for the test to mean anything";
}

// Two heads with one strip each on a twin-wire overlap: at the crossing point Q both series'
// two contact wires are under each strip, the paper's eight constraint conditions (Section VI).
// During the pass every contact switches on its own force (eq. 25): it carries force exactly when
// its strip's head is above its wire, and the active set changes contact by contact.
TEST(PantographHeads, EightContactsOnATwinOverlapEachSwitchingOnItsOwn) {
  YAML::Node root = calpe();
  for (YAML::Node sec : root["sections"]) sec["contact_wire_count"] = 2;
  root["pantographs"][0] = two_half_heads(-0.01, 0.01, 2100.0, 2100.0);
  root["train"]["start"] = 50.0;
  Simulation sim(load(root));
  const Model& m = sim.model();
  ASSERT_EQ(m.contact_wires.size(), 4u);
  ASSERT_EQ(m.collectors.size(), 2u);
  const std::size_t nc = 8;
  int active = 0;
  for (std::size_t k = 0; k < nc; ++k) active += sim.state().contact_force[k] > 0.0;
  EXPECT_EQ(active, 8) << "eq. 23 at Q";
  const Pantograph& p = m.pantographs[0];
  int partial_steps = 0, mismatches = 0;
  while (sim.step() == StepStatus::kOk) {
    const State& s = sim.state();
    int on = 0;
    for (int ci = 0; ci < 2; ++ci)
      for (int w = 0; w < 4; ++w) {
        const double y = s.wire_height_under(m, ci, w);
        const double f = s.contact_force_on(m, ci, w);
        if (std::isnan(y)) continue;
        const Collector& col = m.collectors[ci];
        const double gap = p.contact_reference(col) + s.u[col.dof] - y;
        mismatches += (f > 0.0) != (gap > 0.0);
        if (f > 0.0) {
          EXPECT_NEAR(f, m.contact_stiffness * gap, 1e-9 * m.contact_stiffness * std::fabs(gap) + 1e-12);
        }
        on += f > 0.0;
      }
    // The two strips (on their own heads) touching different sets of wires: the contacts switch
    // strip by strip, not as one. (The twin wires of one series hang from the same droppers at
    // one height, so they switch as a pair: that is the geometry, eq. 15-16.)
    int pattern[2] = {0, 0};
    for (int ci = 0; ci < 2; ++ci)
      for (int w = 0; w < 4; ++w) pattern[ci] |= (s.contact_force_on(m, ci, w) > 0.0) << w;
    partial_steps += on > 0 && pattern[0] != pattern[1];
  }
  EXPECT_EQ(mismatches, 0);
  EXPECT_GT(partial_steps, 0) << "the strips must switch on their own somewhere in the overlap";
}

// Aerodynamic uplift per head and on the frame, for the knee's direction, and the target mean
// force curve. Momentum balance of the whole pantograph over the section: the mean contact force
// is the net uplift static_uplift + (frame + heads' aero) v^2 less the roof spring and damper's
// mean force and the masses' mean inertia force. On CALPE at 120 km/h the frame moves a few cm
// (roof spring 50 N/m: under 2.5 N; damper 100 N s/m over the 1.8 s section: under 3 N) and
// the masses' mean acceleration is their velocity change over the section (22 kg x under
// 0.3 m/s / 1.8 s: under 4 N): the mean is the net uplift within 10 N. The knee directions'
// aero terms here differ by 0.04112 x (33.3 m/s)^2 = 46 N, far outside that.
TEST(PantographHeads, MeanForceFollowsPerHeadAeroForTheKneeAndIsReportedAgainstTheTarget) {
  const double v = 120.0 / 3.6;  // m/s, the scene's speed
  auto scene = [&](const std::string& knee, bool with_target) {
    YAML::Node root = calpe();
    YAML::Node p = two_half_heads(-0.2, 0.2, 2100.0, 2100.0);
    p["aero_coefficient"] = 0.01888;  // frame, knee leading
    p["aero_coefficient_trailing"] = 0.0;
    for (YAML::Node h : p["heads"]) {
      h["aero_coefficient"] = 0.01;
      h["aero_coefficient_trailing"] = 0.04;
    }
    p["knee"] = knee;
    // The curve of the knee-leading uplift, written as EN 50367 writes it (v in km/h):
    // a = 0.003 N/(km/h)^2 = 0.003 x 3.6^2 = 0.03888 N s^2/m^2, b = the static uplift.
    if (with_target) p["target_mean_force"] = YAML::Load("{a: 0.003, b: 120, speed_unit: km/h, tolerance: 10}");
    root["pantographs"][0] = p;
    return load(root);
  };
  const double target = 0.003 * 120.0 * 120.0 + 120.0;           // Fm(120 km/h) = 163.2 N
  const double leading = 120.0 + (0.01888 + 2 * 0.01) * v * v;  // net uplift, knee leading: 163.2 N
  const double trailing = 120.0 + (0.0 + 2 * 0.04) * v * v;      // knee trailing: 208.9 N
  ASSERT_NEAR(target, leading, 1e-9);

  const Scene lead = scene("leading", true);
  Simulation sim(lead);
  PassRecorder rec(sim.model());
  rec.record(sim.model(), sim.state());
  while (sim.step() == StepStatus::kOk) rec.record(sim.model(), sim.state());
  const auto a = rec.statistics(sim.model());
  ASSERT_TRUE(a[0].target_mean.has_value());
  const auto& t = *a[0].target_mean;
  EXPECT_NEAR(t.speed_mps, v, 1e-9 * v);  // constant speed: distance over time
  EXPECT_NEAR(t.target, target, 1e-9 * target);
  EXPECT_NEAR(a[0].filtered.mean, leading, 10.0);
  EXPECT_DOUBLE_EQ(t.difference, a[0].filtered.mean - t.target);
  EXPECT_TRUE(t.within);
  const nlohmann::json j = nlohmann::json::parse(statistics_json(sim.model(), sim.state(), a, RunInfo{}));
  const nlohmann::json& tj = j["pantographs"][0]["target_mean_force"];
  EXPECT_NEAR(tj["target_N"].get<double>(), target, 1e-9 * target);
  EXPECT_NEAR(tj["speed_kmh"].get<double>(), 120.0, 1e-9 * 120.0);
  EXPECT_DOUBLE_EQ(tj["tolerance_N"].get<double>(), 10.0);
  EXPECT_TRUE(tj["within"].get<bool>());
  EXPECT_EQ(tj["curve"]["speed_unit"], "km/h");

  // Knee trailing, same curve: the trailing aero terms apply, 44 N above the target.
  const auto b = run(scene("trailing", true));
  ASSERT_TRUE(b[0].target_mean.has_value());
  EXPECT_NEAR(b[0].filtered.mean, trailing, 10.0);
  EXPECT_NEAR(b[0].target_mean->difference, trailing - target, 10.0);
  EXPECT_FALSE(b[0].target_mean->within);

  // Without a target nothing is reported.
  Simulation plain(scene("leading", false));
  PassRecorder none(plain.model());
  none.record(plain.model(), plain.state());
  for (int i = 0; i < 10; ++i) plain.step(), none.record(plain.model(), plain.state());
  EXPECT_FALSE(none.statistics(plain.model())[0].target_mean.has_value());
}

// The measuring pantograph (load cells under each head, an accelerometer on it) sums its heads:
// F_c = sum_h (suspension + damper + own aero - m_h a_h). Without head dampers the balance holds
// exactly at every step of the central-difference scheme (as for the one-head chain in
// test_pass_outputs): the reconstruction equals the true force to rounding; 1e-6 N is far above
// that and far below any slip (a missing head or aero term is tens of N).
TEST(PantographHeads, MeasuringPantographSumsItsHeads) {
  // The example two-head scene (heads' own aero 0.002 N s^2/m^2 each), its head dampers removed.
  YAML::Node root = YAML::LoadFile(test_scenes::kReferenceTwoHeads);
  for (YAML::Node h : root["pantographs"][0]["heads"]) h["damping"] = 0.0;
  const auto st = run(load(root));
  ASSERT_TRUE(st[0].measured.available);
  EXPECT_LT(st[0].measured.max_abs_difference, 1e-6);
  EXPECT_NEAR(st[0].measured.force.mean, st[0].filtered.mean, 1e-6);
}

// The pass runs from the rearmost strip at the line start to the foremost at its end, counting
// the heads' strips (offset of the head + offset of the strip): at the start both heads of the
// example scene (at +-0.25 m) are under the wire and pressed on it (eq. 23), none hanging off
// the line's end rising on its preload; a train.start with a head off the line is refused.
TEST(PantographHeads, EveryHeadsStripStartsAndEndsOnTheLine) {
  const YAML::Node root = YAML::LoadFile(test_scenes::kReferenceTwoHeads);
  Simulation sim(load(root));
  const Model& m = sim.model();
  EXPECT_NEAR(m.train_start, 0.25, 1e-12);
  EXPECT_NEAR(m.train_end, m.line_length - 0.25, 1e-12);
  for (const Head& h : m.pantographs[0].heads)
    for (int ci : h.collectors) EXPECT_GT(sim.state().contact_force_on(m, ci, 0), 0.0);
  YAML::Node r = YAML::Clone(root);
  r["train"]["start"] = 0.1;
  std::string e = "(no error)";
  try {
    Simulation off(load(r));
  } catch (const SceneError& x) {
    e = x.what();
  }
  EXPECT_NE(e.find("train.start"), std::string::npos) << e;
  EXPECT_NE(e.find("0.25"), std::string::npos) << e;
}

TEST(PantographHeads, BadInputNamesTheField) {
  YAML::Node root = calpe();
  root["pantographs"][0] = two_half_heads(0.0, 0.0, 2100.0, 2100.0);
  {
    YAML::Node r = YAML::Clone(root);
    r["pantographs"][0]["heads"][1].remove("stiffness");
    const std::string e = error_of(r);
    EXPECT_NE(e.find("pantographs[0].heads[1].stiffness"), std::string::npos) << e;
    EXPECT_NE(e.find("suspension"), std::string::npos) << e;
  }
  {
    YAML::Node r = YAML::Clone(root);
    r["pantographs"][0]["heads"][0]["length"] = 0.4;
    r["pantographs"][0]["heads"][0]["collectors"] = YAML::Load("[{offset: 0.3}]");
    const std::string e = error_of(r);
    EXPECT_NE(e.find("pantographs[0].heads[0].collectors[0].offset"), std::string::npos) << e;
    EXPECT_NE(e.find("0.2"), std::string::npos) << e;
  }
  {
    YAML::Node r = YAML::Clone(root);
    r["pantographs"][0]["heads"][1]["aero_coefficient"] = -0.5;  // -0.5 x 33.3^2 = -556 N against 120 N
    const std::string e = error_of(r);
    EXPECT_NE(e.find("pantographs[0].heads[1].aero_coefficient"), std::string::npos) << e;
  }
  {
    YAML::Node r = YAML::Clone(root);
    r["pantographs"][0]["target_mean_force"] = YAML::Load("{a: 0.001, b: 70, speed_unit: mph}");
    const std::string e = error_of(r);
    EXPECT_NE(e.find("pantographs[0].target_mean_force.speed_unit"), std::string::npos) << e;
    EXPECT_NE(e.find("km/h"), std::string::npos) << e;
  }
  {
    YAML::Node r = YAML::Clone(root);
    r["pantographs"][0]["target_mean_force"] = YAML::Load("{a: 0.001, b: 70, tolerance: -5}");
    EXPECT_NE(error_of(r).find("pantographs[0].target_mean_force.tolerance"), std::string::npos);
  }
  {
    YAML::Node r = YAML::Clone(root);
    r["pantographs"][0]["knee"] = "sideways";
    EXPECT_NE(error_of(r).find("pantographs[0].knee"), std::string::npos);
  }
  {
    YAML::Node r = YAML::Clone(root);
    r["pantographs"][0]["collectors"] = YAML::Load("[{offset: 0.0}]");
    EXPECT_NE(error_of(r).find("pantographs[0].collectors"), std::string::npos);
  }
}
