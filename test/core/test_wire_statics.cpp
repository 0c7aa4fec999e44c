// Design statics of a single tensioned wire between two rigid supports, checked against the exact
// static sag of a pre-stressed Euler-Bernoulli beam under its own weight (validation.md section 4).
//
// The wire (no messenger, droppers or pantographs) is held at line.contact_wire_height at both
// ends, rotations free (pinned). Under the uniform load p = rhoA g the exact sag, measured
// downward from the chord, is
//   y(x) = p/T [ x(L-x)/2 - (1/k^2) (1 - cosh(k(x-L/2)) / cosh(kL/2)) ],   k^2 = T/EI,
// and for EI = 0 the parabola y = p x(L-x)/(2T), mid-span sag p L^2/(8T).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <sstream>
#include <string>

#include "catenary_sim/core/model/model.hpp"
#include "catenary_sim/core/scene/scene.hpp"

namespace cs = catenary_sim;

namespace {

constexpr double kHeight = 5.3;  // m, contact_wire_height of the test scenes
constexpr double kGravity = 9.81;

struct WireCase {
  double span;     // m
  double rhoA;     // kg/m
  double EI;       // N m^2
  double T;        // N
  double h;        // m, element length
};

cs::Scene wire_scene(const WireCase& c) {
  std::ostringstream y;
  y.precision(17);
  y << "name: single_wire\n"
    << "gravity: " << kGravity << "\n"
    << "line:\n  contact_wire_height: " << kHeight << "\n  spans: [" << c.span << "]\n"
    << "contact_wire:\n  linear_mass: " << c.rhoA << "\n  bending_stiffness: " << c.EI
    << "\n  tension: " << c.T << "\n"
    << "numerics:\n  element_length: " << c.h << "\n";
  return cs::load_scene_string(y.str());
}

// Exact sag (m, downward positive) of the pinned tensioned beam; EI = 0 gives the string parabola.
double exact_sag(const WireCase& c, double x) {
  const double p = c.rhoA * kGravity, L = c.span, T = c.T;
  const double string = x * (L - x) / 2.0;
  if (c.EI == 0.0) return p / T * string;
  const double k = std::sqrt(T / c.EI);
  // cosh(k(x-L/2))/cosh(kL/2) written with exponentials of non-positive arguments so that it
  // stays finite for large kL.
  const double a = k * std::fabs(x - L / 2.0), b = k * L / 2.0;
  const double ratio = std::exp(a - b) * (1.0 + std::exp(-2.0 * a)) / (1.0 + std::exp(-2.0 * b));
  return p / T * (string - (1.0 - ratio) / (k * k));
}

// Largest |FE sag - exact sag| over all nodes of the wire.
double max_sag_error(const cs::Model& m, const WireCase& c) {
  const cs::Wire& w = m.wires.at(0);
  double err = 0.0;
  for (int i = 0; i < w.nodes(); ++i) err = std::max(err, std::fabs((kHeight - w.height[i]) - exact_sag(c, w.x[i])));
  return err;
}

double fe_sag_at(const cs::Model& m, double xs) {
  const cs::Wire& w = m.wires.at(0);
  for (int i = 0; i < w.nodes(); ++i)
    if (std::fabs(w.x[i] - xs) < 1e-9) return kHeight - w.height[i];
  ADD_FAILURE() << "no node at x = " << xs;
  return NAN;
}

// Discretisation error bound of the design statics. The wire's weight is lumped on the nodes
// (rhoA h / 2 per element end, no nodal moments), whereas the consistent load of a Hermite element
// also has end moments +-p h^2 / 12. With the consistent load the FE solution is nodally exact for
// a string (the parabola is a cubic) and very nearly so with bending; on a uniform mesh the interior
// moments cancel, so the lumped load differs from it only by the two end moments p h^2 / 12 at the
// pinned ends, whose effect on a tensioned wire is a deflection of order (p h^2 / 12) / T (the
// moment is carried by the tension over about one element). We allow 1.5 times that: small against
// the sag (2e-5 of it for the contact wire, 1.6e-4 for the stiff beams below), so that a wrong
// tension, weight, bending term or support height fails by orders of magnitude.
double sag_tolerance(const WireCase& c) { return 1.5 * c.rhoA * kGravity * c.h * c.h / (12.0 * c.T); }

}  // namespace

// EI = 0: a string; mid-span sag p L^2 / (8T) and the parabola p x (L - x) / (2T) at every node.
TEST(WireStatics, StringSagIsTheParabola) {
  const WireCase c{55.0, 1.35, 0.0, 22000.0, 0.25};
  const cs::Model m = cs::build_model(wire_scene(c));
  ASSERT_EQ(m.wires.size(), 1u);
  const cs::Wire& w = m.wires.at(0);
  ASSERT_EQ(w.nodes(), 221);
  const double p = c.rhoA * kGravity;
  const double mid = p * c.span * c.span / (8.0 * c.T);
  const double tol = sag_tolerance(c);
  EXPECT_NEAR(w.height.front(), kHeight, 1e-12);
  EXPECT_NEAR(w.height.back(), kHeight, 1e-12);
  EXPECT_NEAR(fe_sag_at(m, c.span / 2.0), mid, tol);
  for (int i = 0; i < w.nodes(); ++i) {
    const double x = w.x[i];
    ASSERT_NEAR(kHeight - w.height[i], p * x * (c.span - x) / (2.0 * c.T), tol) << "x = " << x;
  }
  // Support slope p L / (2T), down toward mid-span. A C1 cubic through a string loaded at the
  // nodes can only place the nodal rotation within the kink p h / T of each node: tolerance p h / T
  // (1.5e-4 rad, 0.9 % of the 0.0165 rad slope).
  const double slope0 = p * c.span / (2.0 * c.T);
  EXPECT_NEAR(w.slope.front(), -slope0, p * c.h / c.T);
  EXPECT_NEAR(w.slope.back(), slope0, p * c.h / c.T);
}

// A real contact wire (EI = 195 N m^2, T = 22 kN): the bending correction EI p / T^2 = 5e-6 m is
// invisible next to the 0.23 m sag (boundary layer 1/k = 0.094 m, shorter than an element), but the
// whole shape must follow the exact tensioned-beam solution within the bound above.
TEST(WireStatics, ContactWireSagMatchesTensionedBeam) {
  const WireCase c{55.0, 1.35, 195.0, 22000.0, 0.25};
  const cs::Model m = cs::build_model(wire_scene(c));
  EXPECT_NEAR(fe_sag_at(m, c.span / 2.0), exact_sag(c, c.span / 2.0), sag_tolerance(c));
  EXPECT_LT(max_sag_error(m, c), sag_tolerance(c));
}

// A stiff beam, kL = 4 and kL = 10: bending carries a large part of the weight, so the mid-span sag
// is well below p L^2 / (8T) (exactly by 8/(kL)^2 (1 - 1/cosh(kL/2)) = 36.7 % and 7.9 %), and the
// FE shape must follow the tensioned-beam formula at every node.
TEST(WireStatics, BendingStiffnessReducesTheSag) {
  for (const double kL : {4.0, 10.0}) {
    WireCase c{20.0, 1.0, 0.0, 1000.0, 0.25};
    c.EI = c.T / ((kL / c.span) * (kL / c.span));
    SCOPED_TRACE("kL = " + std::to_string(kL));
    const cs::Model m = cs::build_model(wire_scene(c));
    const double string_mid = c.rhoA * kGravity * c.span * c.span / (8.0 * c.T);
    const double exact_mid = exact_sag(c, c.span / 2.0);
    const double fe_mid = fe_sag_at(m, c.span / 2.0);
    const double reduction = 8.0 / (kL * kL) * (1.0 - 1.0 / std::cosh(kL / 2.0));
    ASSERT_NEAR(1.0 - exact_mid / string_mid, reduction, 1e-12);  // the formula itself
    // Visibly reduced: by more than half the exact reduction (the tolerance below is 50x smaller).
    EXPECT_LT(fe_mid, (1.0 - 0.5 * reduction) * string_mid) << "sag not reduced by bending";
    EXPECT_NEAR(fe_mid, exact_mid, sag_tolerance(c));
    EXPECT_LT(max_sag_error(m, c), sag_tolerance(c));
  }
}

// Refining the mesh converges to the exact shape at second order (the end-moment defect scales
// as h^2): halving h must divide the largest error by at least 3 (4 expected).
TEST(WireStatics, MeshRefinementConverges) {
  WireCase c{20.0, 1.0, 0.0, 1000.0, 1.0};
  c.EI = c.T / ((4.0 / c.span) * (4.0 / c.span));
  const double e1 = max_sag_error(cs::build_model(wire_scene(c)), c);
  c.h = 0.5;
  const double e2 = max_sag_error(cs::build_model(wire_scene(c)), c);
  c.h = 0.25;
  const double e3 = max_sag_error(cs::build_model(wire_scene(c)), c);
  RecordProperty("errors_m", std::to_string(e1) + " " + std::to_string(e2) + " " + std::to_string(e3));
  EXPECT_LT(e2, e1 / 3.0);
  EXPECT_LT(e3, e2 / 3.0);
}
