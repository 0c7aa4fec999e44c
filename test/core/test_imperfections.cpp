// The line as built (scene `imperfections`): point masses, steady-arm height errors and dropper
// length errors act on the built line after the design statics; seeded and reproducible.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <sstream>
#include <string>

#include "catenary_sim/core/output/line_measures.hpp"
#include "catenary_sim/core/simulation.hpp"
#include "catenary_sim/core/output/statistics.hpp"
#include "../support/scenes.hpp"

using namespace catenary_sim;

namespace {

using test_scenes::kReference;

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
    if (std::fabs(w.x[i] - x) < 1e-9) return sim.state().wire_uplift(m, m.contact_wires.front(), i);
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
  EXPECT_NE(error_of({"imperfections.dropper_length_std=0.001"}, test_scenes::kReferenceEndless).find("imperfections"),
            std::string::npos);
}

// ---- Contact-wire irregularity and wear ----------------------------------------------------

namespace {

const std::string kIrregularity = "imperfections.contact_wire_irregularity=";

// Sum of the contact forces (N) at every step of a pass.
std::vector<double> force_history(const std::vector<std::string>& overrides) {
  Simulation sim(load_scene_file(kReference, overrides));
  std::vector<double> f;
  auto total = [&]() {
    double t = 0.0;
    for (double c : sim.state().contact_force) t += c;
    return t;
  };
  f.push_back(total());
  while (sim.step() == StepStatus::kOk) f.push_back(total());
  EXPECT_EQ(sim.state().status, StepStatus::kFinished);
  return f;
}

// Heights of the contact wire's nodes as built minus as designed.
std::vector<double> height_deviation(const std::vector<std::string>& overrides) {
  const Model built = build_model(load_scene_file(kReference, overrides));
  std::vector<std::string> perfect = overrides;
  perfect.erase(std::remove_if(perfect.begin(), perfect.end(),
                               [](const std::string& o) { return o.rfind("imperfections", 0) == 0; }),
                perfect.end());
  const Model design = build_model(load_scene_file(kReference, perfect));
  std::vector<double> d;
  const Wire& a = built.wires[built.contact_wires.front()];
  const Wire& b = design.wires[design.contact_wires.front()];
  for (int i = 0; i < a.nodes(); ++i) d.push_back(a.height[i] - b.height[i]);
  return d;
}

std::string sine_profile(double amplitude, double wavelength) {
  std::ostringstream s;
  s.precision(17);
  s << kIrregularity << "{stations: [";
  for (double x = -1.0; x <= 600.0; x += 0.125) s << (x > -1.0 ? ", " : "") << x;
  s << "], deviations: [";
  for (double x = -1.0; x <= 600.0; x += 0.125) s << (x > -1.0 ? ", " : "") << amplitude * std::sin(2.0 * M_PI * x / wavelength);
  s << "]}";
  return s.str();
}

}  // namespace

// A deviation that is the same everywhere only raises the wire: eq. 23 lifts the pantograph with
// it and the contact force is the perfect line's. Equal to rounding (heights of 5.3 m carry
// ~1e-15 m, times k0 = 5e4 N/m over 4e4 steps of a linear scheme: far below 1e-6 N), whereas a
// deviation the contact did not see, or the pantograph reference not following it, would move
// the force by at least the roof spring's 160 N/m x 10 mm = 1.6 N.
TEST(Imperfections, AUniformDeviationOnlyRaisesTheWire) {
  const auto perfect = force_history({});
  const auto raised = force_history({kIrregularity + "{stations: [-10, 1000], deviations: [0.01, 0.01]}"});
  ASSERT_EQ(perfect.size(), raised.size());
  double worst = 0.0;
  for (std::size_t i = 0; i < perfect.size(); ++i) worst = std::max(worst, std::fabs(perfect[i] - raised[i]));
  EXPECT_LT(worst, 1e-6);
}

// A sinusoidal irregularity of wavelength L passed at v excites the contact at v / L. The system
// is linear while contact holds and no dropper changes state, so the force's change from the
// perfect line is the irregularity's response alone: its spectrum peaks at v / L (within one
// Welch resolution, 0.5 Hz) and it doubles with the amplitude (1 and 2 mm at 200 km/h, contact
// never lost; within 5 %: the droppers' slackening, the one nonlinearity left, moves it by less).
TEST(Imperfections, SinusoidalIrregularityExcitesTheContactAtSpeedOverWavelength) {
  const double v = 200.0 / 3.6, wavelength = 7.0, f0 = v / wavelength;  // 7.94 Hz
  auto forces = [&](double amplitude, double* dt) {
    std::vector<std::string> o = {"train.speed_kmh=200"};
    if (amplitude > 0.0) o.push_back(sine_profile(amplitude, wavelength));
    Simulation sim(load_scene_file(kReference, o));
    const Model& m = sim.model();
    *dt = m.dt;
    double x0 = 0.0, x1 = 0.0;
    analysis_section(m, &x0, &x1);
    std::vector<double> f;
    while (sim.step() == StepStatus::kOk) {
      const double front = sim.state().front;
      if (front < x0 || front > x1) continue;
      double t = 0.0;
      for (double c : sim.state().contact_force) t += c;
      EXPECT_GT(t, 0.0) << "contact lost at " << front << " m: the linearity argument needs contact";
      f.push_back(t);
    }
    return f;
  };
  double dt = 0.0;
  const auto f0_line = forces(0.0, &dt), f1 = forces(0.001, &dt), f2 = forces(0.002, &dt);
  ASSERT_EQ(f0_line.size(), f1.size());
  ASSERT_EQ(f0_line.size(), f2.size());
  std::vector<double> d1(f1.size()), d2(f2.size());
  double ms1 = 0.0, ms2 = 0.0;
  for (std::size_t i = 0; i < f1.size(); ++i) {
    d1[i] = f1[i] - f0_line[i];
    d2[i] = f2[i] - f0_line[i];
    ms1 += d1[i] * d1[i];
    ms2 += d2[i] * d2[i];
  }
  const Spectrum s = welch_psd(d1, 1.0 / dt, static_cast<std::size_t>(2.0 / dt));  // 0.5 Hz resolution
  const auto peaks = spectral_peaks(s, 0.5, 40.0, 1);
  ASSERT_FALSE(peaks.empty());
  EXPECT_NEAR(peaks[0].frequency, f0, s.resolution);
  EXPECT_GT(peaks[0].amplitude, 1.0);  // N: the 1 mm irregularity is felt
  EXPECT_NEAR(std::sqrt(ms2 / ms1), 2.0, 0.1);
}

// A random irregularity has the rms asked for and the spectrum's slope. Over a 2.2 km line the
// spatial rms of one realisation scatters by ~3 % around the target (the longest wavelengths, 55 m,
// fit only 40 times), so the mean of four seeds is within 7 % (5 sigma); the log-log slope of
// the Welch PSD between 2/55 and 0.5 cycles/m scatters by ~0.04 around -exponent: within 0.25.
TEST(Imperfections, RandomIrregularityHasTheRequestedRmsAndSpectrum) {
  const double rms = 0.002;
  double mean_ratio = 0.0;
  for (int seed : {1, 2, 3, 4}) {
    const auto d = height_deviation({"line.span_count=40", kIrregularity + "{rms: 0.002, wavelength_min: 1.0, wavelength_max: 55.0, exponent: 2, seed: " +
                                                               std::to_string(seed) + "}"});
    double ms = 0.0;
    for (double r : d) ms += r * r;
    mean_ratio += std::sqrt(ms / d.size()) / rms / 4.0;
    const Spectrum s = welch_psd(d, 4.0, 1024);  // 0.25 m nodes: 4 samples per m
    double sx = 0, sy = 0, sxx = 0, sxy = 0;
    int n = 0;
    for (std::size_t i = 1; i < s.frequency.size(); ++i) {
      if (s.frequency[i] <= 2.0 / 55.0 || s.frequency[i] >= 0.5) continue;
      const double lx = std::log(s.frequency[i]), ly = std::log(s.psd[i]);
      sx += lx, sy += ly, sxx += lx * lx, sxy += lx * ly, ++n;
    }
    const double slope = (n * sxy - sx * sy) / (n * sxx - sx * sx);
    EXPECT_NEAR(slope, -2.0, 0.25) << "seed " << seed;
  }
  EXPECT_NEAR(mean_ratio, 1.0, 0.07);
  // Seeded: the same seed, the same line; its own seed leaves the dropper errors as they were.
  const std::string r = kIrregularity + "{rms: 0.002, wavelength_min: 1.0, wavelength_max: 55.0, seed: 9}";
  EXPECT_EQ(height_deviation({r}), height_deviation({r}));
  EXPECT_NE(height_deviation({r}), height_deviation({kIrregularity + "{rms: 0.002, wavelength_min: 1.0, wavelength_max: 55.0, seed: 10}"}));
  auto tensions = [](const std::vector<std::string>& o) {
    std::vector<double> t;
    for (const Dropper& d : build_model(load_scene_file(kReference, o)).droppers) t.push_back(d.static_tension);
    return t;
  };
  EXPECT_EQ(tensions({"imperfections.dropper_length_std=0.003", r}), tensions({"imperfections.dropper_length_std=0.003"}));
}

// A measured profile from CSV, found beside the scene, is the same as given inline; the
// deviation at each node is the linear interpolation of the profile (0 outside it).
TEST(Imperfections, MeasuredProfileFromCsvBesideTheScene) {
  const std::string dir = ::testing::TempDir() + "catenary_profile";
  std::system(("mkdir -p " + dir).c_str());
  {
    std::ofstream csv(dir + "/measured.csv");
    csv << "# measured with a laser rangefinder\nstation_m,deviation_m\n100,0\n110.5,0.004\n121,-0.002\n130,0\n";
    std::ifstream in(kReference);
    std::ofstream scene(dir + "/scene.yaml");
    scene << in.rdbuf() << "\nimperfections:\n  contact_wire_irregularity: {csv: measured.csv}\n";
  }
  const Model from_csv = build_model(load_scene_file(dir + "/scene.yaml"));
  const Model inline_profile = build_model(load_scene_file(
      kReference, {kIrregularity + "{stations: [100, 110.5, 121, 130], deviations: [0, 0.004, -0.002, 0]}"}));
  const Model design = build_model(load_scene_file(kReference));
  const Wire& a = from_csv.wires[from_csv.contact_wires.front()];
  const Wire& b = inline_profile.wires[inline_profile.contact_wires.front()];
  const Wire& c = design.wires[design.contact_wires.front()];
  EXPECT_EQ(a.height, b.height);
  for (int i = 0; i < a.nodes(); ++i) {
    const double x = a.x[i];
    const double expect = x < 100 || x > 130 ? 0.0
                          : x <= 110.5       ? 0.004 * (x - 100) / 10.5
                          : x <= 121         ? 0.004 - 0.006 * (x - 110.5) / 10.5
                                             : -0.002 + 0.002 * (x - 121) / 9.0;
    EXPECT_NEAR(a.height[i] - c.height[i], expect, 1e-12) << "x = " << x;  // heights of 5 m: rounding 1e-15
  }
}

// Uniform wear on a single wire between rigid supports: the worn wire is lighter (rhoA (1 - s))
// and softer in bending (EI (1 - s)^2), its tension held; as built it hangs at the exact sag of a
// pinned tensioned beam with those properties (test_wire_statics' formula). A stiff, slack wire
// (EI 2e4 N m^2, T 2000 N: k L = 16) makes the bending term 1.6 % of the 1.45 m sag (23 mm), so
// a wrong EI factor shows; the FE error at h = 0.05 m is below 1e-5 m there (test_wire_statics' bound).
TEST(Imperfections, WornWireHangsAsTheLighterSofterBeam) {
  const double L = 50.0, rhoA = 1.35, EI = 2.0e4, T = 2000.0, loss = 0.3, g = 9.81;
  std::ostringstream y;
  y << "name: worn\nline: {span_length: " << L << ", span_count: 1}\n"
    << "contact_wire: {linear_mass: " << rhoA << ", bending_stiffness: " << EI << ", tension: " << T << "}\n"
    << "train: {speed: 0.0}\nnumerics: {element_length: 0.05}\noutput: {analysis_spans: [0, 1]}\n"
    << "imperfections: {contact_wire_wear: {section_loss: " << loss << "}}\n";
  Simulation sim(load_scene_string(y.str()));
  const Model& m = sim.model();
  const Wire& w = m.wires[m.contact_wires.front()];
  const double p = (1.0 - loss) * rhoA * g, ei = EI * (1.0 - loss) * (1.0 - loss), k = std::sqrt(T / ei);
  auto exact_sag = [&](double x) {  // downward from the chord, pinned ends
    const double a = k * std::fabs(x - L / 2.0), b = k * L / 2.0;
    const double ratio = std::exp(a - b) * (1.0 + std::exp(-2.0 * a)) / (1.0 + std::exp(-2.0 * b));
    return p / T * (x * (L - x) / 2.0 - (1.0 - ratio) / (k * k));
  };
  const double h0 = w.height.front();
  double worst = 0.0, mass = 0.0;
  for (int i = 0; i < w.nodes(); ++i) {
    const double built = sim.state().wire_height(m, m.contact_wires.front(), i);
    worst = std::max(worst, std::fabs((h0 - built) - exact_sag(w.x[i])));
    mass += m.mass[w.w_dof + i];
  }
  EXPECT_LT(worst, 1e-5);
  // With the unworn EI the sag would differ by p (EI - EI') / T^2 = 2.4e-2 m at mid-span.
  EXPECT_NEAR(mass, (1.0 - loss) * rhoA * L, 1e-9 * rhoA * L);  // conservation of the lumped mass
}

TEST(Imperfections, IrregularityAndWearBadInputNamesTheField) {
  auto error_of = [](const std::vector<std::string>& o) -> std::string {
    try {
      Simulation s(load_scene_file(kReference, o));
    } catch (const SceneError& e) {
      return e.what();
    }
    return "";
  };
  const std::string f = "imperfections.contact_wire_irregularity";
  EXPECT_NE(error_of({kIrregularity + "{rms: 0.002, wavelength_min: 0.2, wavelength_max: 55}"}).find(f + ".wavelength_min"), std::string::npos);
  EXPECT_NE(error_of({kIrregularity + "{rms: 0.002, wavelength_min: 10, wavelength_max: 5}"}).find(f + ".wavelength_max"), std::string::npos);
  EXPECT_NE(error_of({kIrregularity + "{rms: -1, wavelength_min: 1, wavelength_max: 5}"}).find(f + ".rms"), std::string::npos);
  EXPECT_NE(error_of({kIrregularity + "{csv: /nonexistent/profile.csv}"}).find(f + ".csv"), std::string::npos);
  EXPECT_NE(error_of({kIrregularity + "{stations: [0, 10, 5], deviations: [0, 0, 0]}"}).find(f + ".stations[2]"), std::string::npos);
  EXPECT_NE(error_of({kIrregularity + "{stations: [0, 10], deviations: [0]}"}).find(f + ".deviations"), std::string::npos);
  EXPECT_NE(error_of({kIrregularity + "{stations: [0, 10], deviations: [0, 0.9]}"}).find(f + ".deviations[1]"), std::string::npos);
  EXPECT_NE(error_of({kIrregularity + "{stations: [0, 10], deviations: [0, 0], rms: 0.001}"}).find(f + ".rms"), std::string::npos);
  EXPECT_NE(error_of({"imperfections.contact_wire_wear={section_loss: 0.8}"}).find("imperfections.contact_wire_wear.section_loss"), std::string::npos);
  EXPECT_NE(error_of({"imperfections.contact_wire_wear={stations: [0, 10], section_loss: [0.1, -0.1]}"}).find("imperfections.contact_wire_wear.section_loss[1]"),
            std::string::npos);
  // A CSV that is not two numbers per line names the file and the line.
  const std::string dir = ::testing::TempDir();
  std::ofstream(dir + "bad_profile.csv") << "station,deviation\n0,0\n10,abc\n";
  const std::string e = error_of({kIrregularity + "{csv: " + dir + "bad_profile.csv}"});
  EXPECT_NE(e.find("line 3"), std::string::npos) << e;
}
