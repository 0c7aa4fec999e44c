// Natural frequencies of a simply supported tensioned beam (validation.md section 4),
//   f_n = (n / 2L) sqrt(T/rhoA) sqrt(1 + (n pi / L)^2 EI / T),
// from the model's own operators: the dense stiffness K assembled column by column with
// catenary_sim::apply_stiffness and the lumped mass model.mass, restricted to the free DOFs
// (inv_mass > 0), solved as the generalized eigenproblem K phi = w^2 M phi with Eigen.
// Also: the power-iteration estimate of the highest eigenfrequency (stability.hpp) against the
// dense solve, and build_model's refusal of a time step above the stability limit.
#include <gtest/gtest.h>

// Eigen 3.4's SelfAdjointEigenSolver trips GCC's -Wmaybe-uninitialized inside Eigen's own
// headers when they are included with -I rather than as system headers (false positive).
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wmaybe-uninitialized"
#include <Eigen/Dense>
#pragma GCC diagnostic pop
#include <cmath>
#include <cstdlib>
#include <sstream>
#include <string>
#include <vector>

#include "catenary_sim/core/model/model.hpp"
#include "catenary_sim/core/scene/scene.hpp"
#include "catenary_sim/core/model/stability.hpp"

namespace cs = catenary_sim;

namespace {

struct BeamCase {
  const char* name;
  double span, rhoA, EI, T, h;
};

std::string beam_yaml(const BeamCase& c, const char* rotary, const std::string& dt = "auto") {
  std::ostringstream y;
  y.precision(17);
  y << "name: beam\n"
    << "line:\n  spans: [" << c.span << "]\n"
    << "contact_wire:\n  linear_mass: " << c.rhoA << "\n  bending_stiffness: " << c.EI << "\n  tension: " << c.T << "\n"
    << "numerics:\n  element_length: " << c.h << "\n  rotary_inertia: " << rotary << "\n  dt: " << dt << "\n";
  return y.str();
}

// Free-DOF dense K and diagonal M of the model.
struct Dense {
  Eigen::MatrixXd K;
  Eigen::VectorXd M;
};

Dense dense_system(const cs::Model& m) {
  std::vector<int> free;
  for (int i = 0; i < m.n_dof; ++i)
    if (m.inv_mass[i] > 0.0) free.push_back(i);
  const int nf = static_cast<int>(free.size());
  int max_nodes = 1;
  for (const cs::Wire& w : m.wires) max_nodes = std::max(max_nodes, w.nodes());
  std::vector<double> e(m.n_dof, 0.0), col(m.n_dof), scratch(max_nodes);
  Dense d{Eigen::MatrixXd(nf, nf), Eigen::VectorXd(nf)};
  for (int j = 0; j < nf; ++j) {
    e[free[j]] = 1.0;
    cs::apply_stiffness(m, m.train_start, e.data(), col.data(), scratch.data());
    e[free[j]] = 0.0;
    for (int i = 0; i < nf; ++i) d.K(i, j) = col[free[i]];
    d.M[j] = m.mass[free[j]];
  }
  return d;
}

// Angular eigenfrequencies (rad/s), ascending, of K phi = w^2 M phi via M^-1/2 K M^-1/2.
Eigen::VectorXd omegas(const Dense& d) {
  const Eigen::VectorXd s = d.M.cwiseSqrt().cwiseInverse();
  const Eigen::MatrixXd A = s.asDiagonal() * d.K * s.asDiagonal();
  Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> es(0.5 * (A + A.transpose()), Eigen::EigenvaluesOnly);
  EXPECT_EQ(es.info(), Eigen::Success);
  return es.eigenvalues().cwiseMax(0.0).cwiseSqrt();
}

double analytic_f(const BeamCase& c, int n) {
  const double kn = n * M_PI / c.span;
  return n / (2.0 * c.span) * std::sqrt(c.T / c.rhoA) * std::sqrt(1.0 + kn * kn * c.EI / c.T);
}

}  // namespace

// Two beams: the contact wire of validation.md section 2 on a 20 m span (tension-dominated, the
// bending term raises f_5 by 0.3 %), and a stiff beam (EI/T = 0.081 m^2 on 10 m) where bending
// raises f_1..f_5 by 0.4, 1.6, 3.5, 6.2 and 9.5 %, so that a missing or wrong EI term fails.
const BeamCase kCases[] = {{"contact_wire", 20.0, 1.35, 195.0, 22000.0, 0.25},
                           {"stiff_beam", 10.0, 1.0, 81.0, 1000.0, 0.1}};

// First five frequencies to 0.5 %. Discretisation error of a lumped-mass beam mesh: the lumped
// translational mass lowers mode n by about (n pi h / L)^2 / 24 (the string value), at most
// (5 pi 0.25/20)^2/24 = 0.16 % here, and the HRZ rotary inertia / condensed rotations change the
// bending part by less; 0.5 % leaves a 3x margin, and is 20x smaller than the EI effect on f_5 of
// the stiff beam.
TEST(Eigenfrequencies, FirstFiveMatchTensionedBeam) {
  for (const BeamCase& c : kCases)
    for (const char* rot : {"condensed", "lumped"}) {
      SCOPED_TRACE(std::string(c.name) + ", rotary_inertia " + rot);
      const cs::Model m = cs::build_model(cs::load_scene_string(beam_yaml(c, rot)));
      const Dense d = dense_system(m);
      // Free DOFs: the interior w (ends rigid) and, for lumped rotary inertia, every rotation
      // (pinned ends rotate freely).
      const int nodes = m.wires.at(0).nodes();
      ASSERT_EQ(d.M.size(), std::string(rot) == "lumped" ? 2 * nodes - 2 : nodes - 2);
      // K must be symmetric: it is the Hessian of the strain energy.
      EXPECT_LT((d.K - d.K.transpose()).cwiseAbs().maxCoeff(), 1e-9 * d.K.cwiseAbs().maxCoeff());
      const Eigen::VectorXd w = omegas(d);
      ASSERT_GT(w[0], 0.0);  // no rigid-body mode: both ends are held
      for (int n = 1; n <= 5; ++n) {
        const double f = w[n - 1] / (2.0 * M_PI), fa = analytic_f(c, n);
        EXPECT_NEAR(f / fa, 1.0, 0.005) << "mode " << n << ": " << f << " Hz vs analytic " << fa << " Hz";
      }
    }
}

// highest_eigenfrequency() is a power iteration on M^-1/2 K M^-1/2; it must find the top of the
// spectrum of the dense solve to 1 % (a converged Rayleigh quotient is exact to second order in
// the eigenvector error, so the bound is loose; underestimating it would make dt_critical unsafe).
TEST(Eigenfrequencies, PowerIterationFindsTheHighestMode) {
  for (const BeamCase& c : kCases)
    for (const char* rot : {"condensed", "lumped"}) {
      SCOPED_TRACE(std::string(c.name) + ", rotary_inertia " + rot);
      const cs::Model m = cs::build_model(cs::load_scene_string(beam_yaml(c, rot)));
      const Eigen::VectorXd w = omegas(dense_system(m));
      const double top = w[w.size() - 1];
      EXPECT_NEAR(cs::highest_eigenfrequency(m) / top, 1.0, 0.01);
      EXPECT_NEAR(m.omega_max / top, 1.0, 0.01);
      // The limit the model uses must be on the safe side: omega_max not below the true top.
      EXPECT_GE(m.omega_max, top);
      // Undamped: dt_crit = 2 / w_max (validation.md section 5), here from the dense w_max.
      EXPECT_NEAR(m.dt_critical * top / 2.0, 1.0, 0.01);
    }
}

namespace {

// Numbers in a message, in order (for reading the limit out of an error text without depending
// on its exact wording or formatting).
std::vector<double> numbers_in(const std::string& s) {
  std::vector<double> out;
  const char* p = s.c_str();
  while (*p) {
    char* end = nullptr;
    if ((*p >= '0' && *p <= '9') || (*p == '.' && p[1] >= '0' && p[1] <= '9')) {
      const double v = std::strtod(p, &end);
      if (end != p) {
        out.push_back(v);
        p = end;
        continue;
      }
    }
    ++p;
  }
  return out;
}

}  // namespace

// A dt above the stability limit is refused with a SceneError that states the limit; a dt just
// below it is accepted and used as given.
TEST(Eigenfrequencies, DtAboveStabilityLimitIsRefused) {
  const BeamCase& c = kCases[0];
  const cs::Model ref = cs::build_model(cs::load_scene_string(beam_yaml(c, "lumped")));
  const double limit = ref.dt_critical;
  ASSERT_GT(limit, 0.0);
  // dt auto: safety_factor (default 0.9) times the limit.
  EXPECT_NEAR(ref.dt, 0.9 * limit, 1e-12 * limit);

  std::ostringstream too_big;
  too_big.precision(17);
  too_big << 1.05 * limit;
  try {
    cs::build_model(cs::load_scene_string(beam_yaml(c, "lumped", too_big.str())));
    ADD_FAILURE() << "dt = " << too_big.str() << " s above the limit " << limit << " s was accepted";
  } catch (const cs::SceneError& e) {
    const std::string msg = e.what();
    bool states_limit = false;
    // The limit printed to at least 5 significant digits.
    for (double v : numbers_in(msg)) states_limit = states_limit || std::fabs(v - limit) <= 1e-5 * limit;
    EXPECT_TRUE(states_limit) << "message does not state the limit " << limit << " s: " << msg;
    EXPECT_NE(msg.find("dt"), std::string::npos) << msg;
  }

  std::ostringstream ok;
  ok.precision(17);
  ok << 0.99 * limit;
  cs::Model m;
  ASSERT_NO_THROW(m = cs::build_model(cs::load_scene_string(beam_yaml(c, "lumped", ok.str()))));
  EXPECT_DOUBLE_EQ(m.dt, 0.99 * limit);
}
