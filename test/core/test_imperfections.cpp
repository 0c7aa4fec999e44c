// The line as built (scene `imperfections`): point masses, steady-arm height errors and dropper
// length errors act on the built line after the design statics; seeded and reproducible.
#include <gtest/gtest.h>

#include <cmath>
#include <sstream>
#include <string>

#include "catenary_sim/core/simulation.hpp"

#ifndef CATENARY_SIM_SOURCE_DIR
#define CATENARY_SIM_SOURCE_DIR "."
#endif

using namespace catenary_sim;

namespace {

const std::string kReference = CATENARY_SIM_SOURCE_DIR "/config/reference_55m.yaml";

std::string beam_scene(double mass) {
  std::ostringstream s;
  s << "name: beam\nline: {span_length: 50.0, span_count: 1}\n"
    << "contact_wire: {linear_mass: 1.35, bending_stiffness: 195.0, tension: 20000.0}\n"
    << "train: {speed: 0.0}\nnumerics: {element_length: 0.05}\noutput: {analysis_spans: [0, 1]}\n";
  if (mass > 0.0) s << "imperfections: {point_masses: [{station: 25.0, mass: " << mass << "}]}\n";
  return s.str();
}

double contact_wire_u(const Simulation& sim, double x) {
  const Model& m = sim.model();
  const Wire& w = m.wires[m.contact_wires.front()];
  for (int i = 0; i < w.nodes(); ++i)
    if (std::fabs(w.x[i] - x) < 1e-9) return sim.state().u[w.w_dof + i];
  ADD_FAILURE() << "no node at " << x;
  return 0.0;
}

}  // namespace

// A point mass M at mid-span of a simply supported beam in tension T (EI) sags it by
// M g / (2 k T) (u - tanh u), k = sqrt(T / EI), u = k L / 2 (Timoshenko's beam-column in tension),
// on top of the sag under the wire's own weight (the design state, u = 0). At h = 0.05 m the
// Hermite elements are within 2e-7 of it (test_module.py's convergence study): 1e-6.
TEST(Imperfections, PointMassSagsATensionedBeamAsTheClosedForm) {
  const double mass = 10.0, g = 9.81, T = 20000.0, EI = 195.0, L = 50.0;
  Simulation sim(load_scene_string(beam_scene(mass)));
  const double k = std::sqrt(T / EI), u = k * L / 2.0;
  const double exact = -mass * g / (2.0 * k * T) * (u - std::tanh(u));
  EXPECT_NEAR(contact_wire_u(sim, 25.0), exact, 1e-6 * std::fabs(exact));
  Simulation perfect(load_scene_string(beam_scene(0.0)));
  // The design state is the static state, to the solve's round-off (cond(K) ~ 1e7, heights of 5 m).
  EXPECT_NEAR(contact_wire_u(perfect, 25.0), 0.0, 1e-9);
}

// Statics are linear while no dropper changes state: steady arms raised by 10 mm move the built
// line exactly twice as far as by 5 mm (27 N at 2673 N/m against dropper tensions of ~100 N: no
// dropper goes slack). Equal to round-off of the sparse solve: 1e-9 of the displacement.
TEST(Imperfections, SteadyArmHeightErrorsActLinearly) {
  Simulation s0(load_scene_file(kReference));
  Simulation s5(load_scene_file(kReference, {"imperfections.support_height_std=0", "imperfections.support_height_errors=[" +
                                                 std::string("0.005, 0.005, 0.005, 0.005, 0.005, 0.005, 0.005, 0.005, 0.005]")}));
  Simulation s10(load_scene_file(kReference, {"imperfections.support_height_errors=[0.01, 0.01, 0.01, 0.01, 0.01, 0.01, 0.01, 0.01, 0.01]"}));
  const Eigen::VectorXd d5 = s5.state().u - s0.state().u, d10 = s10.state().u - s0.state().u;
  ASSERT_GT(d5.cwiseAbs().maxCoeff(), 1e-3);  // the arms moved the line by millimetres
  EXPECT_LT((d10 - 2.0 * d5).cwiseAbs().maxCoeff(), 1e-9 * d10.cwiseAbs().maxCoeff() + 1e-12);
  // Each steady arm rises by less than its error (the wire and droppers pull it back) but rises.
  const Model& m = s5.model();
  for (const SupportSpring& sp : m.springs)
    if (sp.steady_arm) {
      EXPECT_GT(d5[sp.dof], 0.0) << sp.x;
      EXPECT_LT(d5[sp.dof], 0.005) << sp.x;
    }
}

// Seeded: the same seed builds the same line bit for bit, another seed another line; a longer
// dropper carries less at the design geometry (k e less).
TEST(Imperfections, DropperErrorsAreSeededAndReproducible) {
  auto tensions = [](const std::vector<std::string>& o) {
    Simulation s(load_scene_file(kReference, o));
    std::vector<double> t;
    for (const Dropper& d : s.model().droppers) t.push_back(d.static_tension);
    return t;
  };
  const auto perfect = tensions({});
  const auto a = tensions({"imperfections.dropper_length_std=0.003", "imperfections.seed=7"});
  const auto b = tensions({"imperfections.dropper_length_std=0.003", "imperfections.seed=7"});
  const auto c = tensions({"imperfections.dropper_length_std=0.003", "imperfections.seed=8"});
  EXPECT_EQ(a, b);
  EXPECT_NE(a, c);
  EXPECT_NE(a, perfect);
}

TEST(Imperfections, BadInputNamesTheField) {
  auto error_of = [](const std::vector<std::string>& o, const std::string& file = kReference) -> std::string {
    try {
      Simulation s(load_scene_file(file, o));
    } catch (const SceneError& e) {
      return e.what();
    }
    return "";
  };
  EXPECT_NE(error_of({"imperfections.dropper_length_errors=[0.01]"}).find("imperfections.dropper_length_errors"), std::string::npos);
  EXPECT_NE(error_of({"imperfections.support_height_errors=[0.01, 0.02]"}).find("imperfections.support_height_errors"), std::string::npos);
  EXPECT_NE(error_of({"imperfections.point_masses=[{station: 1000, mass: 5}]"}).find("imperfections.point_masses[0].station"), std::string::npos);
  EXPECT_NE(error_of({"imperfections.dropper_length_std=-1"}).find("imperfections.dropper_length_std"), std::string::npos);
  EXPECT_NE(error_of({"imperfections.spam=1"}).find("imperfections.spam"), std::string::npos);
  EXPECT_NE(error_of({"imperfections.dropper_length_std=0.001"}, CATENARY_SIM_SOURCE_DIR "/config/reference_55m_endless.yaml").find("imperfections"),
            std::string::npos);
}
