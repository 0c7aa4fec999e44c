// The 3-D line: every wire's lateral (horizontal) plane, built from the same pre-stressed beam
// band as its vertical plane (same T, EI and nodes; a round wire bends alike both ways). Its step,
// after the vertical one, is the engine's (engine/lateral_step.hpp).
//
// Coordinates: y is the wire's lateral position from the track centre line (+ to the left in the
// direction of increasing station), in the track's own frame. A curve of curvature kappa then
// acts on a wire of tension T as the distributed lateral load T kappa (the wire is straight in
// plan, so in the curved frame T (y'' + kappa) + q = 0): the chords between supports come out of
// the statics, and the steady arms carry the pull-off T x (change of direction).
// Droppers are pendulums of stiffness S / l (tension over length) between the messenger (or the
// stitch wire they hang from) and the contact wire; steady arms and messenger supports are
// lateral springs (or rigid) at the stagger; anchors are rigid; a stitch wire's clamps are
// springs between its ends and the messenger (LateralClamp). Wind pushes each node with 0.5 rho Cd d h V|V|, V the wind's
// speed normal to the wire less the node's lateral velocity (aerodynamic damping included).
//
// Two-way coupling through the droppers' geometry (docs/model_and_numerics.md, "Coupling"): a
// dropper of length l whose ends are dz apart vertically (from the design) and dy = y_m - y_c
// laterally is stretched by sqrt((l + dz)^2 + dy^2) - l ~ dz + dy^2 / (2 l). The built line holds
// the static lean dy0 (LateralModel::initial, under the mean wind), so the stretch is
// e = dz + (dy^2 - dy0^2) / (2 l) and one potential V(e) = S0 e + k e^2 / 2 (0 force when slack,
// S0 + k e <= 0) serves both planes: the vertical force is S = S0 + k e, the lateral one S dy / l
// (the pendulum). At the pass start e is the vertical plane's design stretch, so its static state
// stays the design statics'; the lean's change during the pass acts on the vertical plane (in
// which order the two planes take it: engine/lateral_step.hpp).
#pragma once

#include <Eigen/Core>
#include <algorithm>
#include <cmath>
#include <memory>
#include <vector>

#include "catenary_sim/core/model/model.hpp"
#include "catenary_sim/core/model/wind_field.hpp"

namespace catenary_sim {

struct LateralSpring {
  int dof = 0;             // lateral index
  double stiffness = 0.0;  // N/m
  double anchor = 0.0;     // m, the support's lateral position (the stagger)
};

struct LateralPendulum {
  int contact = 0, messenger = 0;  // lateral indices
  int dropper = 0;                 // index into Model::droppers (its tension now sets S)
  double inv_length = 0.0;         // 1/m
  double half_inv_length = 0.0;    // 1/m, 1 / (2 l): the lean's stretch (dy^2 - dy0^2) / (2 l)
  double lean0_sq = 0.0;           // m^2, dy0^2: the lean in the static state under the mean wind
};

// A stitch wire's end clamped to the messenger (Model::clamps, the same index): in plan the same
// stiff bilateral spring as in the vertical plane, between the two lateral nodes. The stitch wire
// has no support of its own: sideways it hangs from its two clamps (and its droppers' pendulums).
struct LateralClamp {
  int upper = 0, lower = 0;  // lateral indices: the upper wire's node, the lower wire's (WireClamp)
  double stiffness = 0.0;         // N/m
};

// The stretch a dropper gets from its lean (the header comment), y the lateral positions.
inline double lean_stretch(const LateralPendulum& p, const double* y) {
  const double dy = y[p.messenger] - y[p.contact];
  return (dy * dy - p.lean0_sq) * p.half_inv_length;
}

// A support of a wire in plan, with its static lateral force (pull-off).
struct LateralSupport {
  int wire = 0;          // index into Model::wires
  int node = 0;
  int line_support = 0;  // index into Model::support_x
  double x = 0.0;        // m
  double stagger = 0.0;  // m
  bool rigid = true, anchor = false;
  // N, lateral force of the wire on the support in the static state, + toward +y: without wind,
  // and under the mean wind.
  double pull_off = 0.0, pull_off_wind = 0.0;
};

// A hinged steady arm's registration on a 3-D line (SupportSpring::hinged_arm at an intermediate
// support of a contact wire, pulled to one side): as the arm's end rises by u it turns toward
// horizontal and moves out by registration_travel(u), away from its hinge, toward the side the
// wire pulls. Both ways: the lateral step moves the registration point (the held node, or its
// spring's anchor) with the arm's end, and the wire's lateral force F on it acts back on the arm,
// whose end it moves by d(travel)/du = side tan(theta) per metre of uplift: by virtual work a
// vertical force (F - F0) side tan(theta) on the registration's vertical DOF, F0 the force in the
// state the pass starts from (its static part F0 side tan(theta) is the design statics' f0 and
// F_h / (a cos^3 theta0) in k_A; quasi-statically F - F0 = -k_w travel, the k_w tan^2 theta0 a
// 2-D line puts in k_A, design_statics.cpp).
struct LateralRegistration {
  int dof = 0;          // lateral index of the registration node
  int vertical = 0;     // its vertical DOF (SupportSpring::dof): u there is the arm's uplift
  int spring = -1;      // index into LateralModel::springs; -1: held (inv_mass 0)
  int wire = 0, node = 0;  // the contact wire (Model::wires) and its node, for the moving window
  double length = 0.0;     // m, a
  double sin0 = 0.0, cos0 = 0.0;  // of the arm's inclination below the hinge at the assembly, theta0
  double side = 0.0;       // +1 / -1: the side the wire pulls (SupportSpring::arm_pull_side)
  std::vector<int> pendulums;  // the droppers' pendulums (LateralModel::pendulums) hung at the node
};

// m, the arm's end's sideways travel from the stagger with its end raised by u: side
// a (cos(theta) - cos(theta0)) (hinged_arm_travel, model.hpp).
inline double registration_travel(const LateralRegistration& r, double u) {
  return r.side * hinged_arm_travel(r.length, r.sin0, r.cos0, u);
}

// Nodes each side of a held registration over which the wire's band force at it is taken, its
// rotations condensed there (the engine's row, registration_pull): the rotations' coupling decays
// by about 0.2 per element (K_theta_theta's off-diagonal over its diagonal, 2 EI / h - T h / 30
// against 8 EI / h + 4 T h / 15 for a contact wire), so the rest of the wire would change that
// force by some 0.2^8, 3e-6 of it. The same row, K being symmetric, gives the force on each of
// those nodes when the registration moves.
constexpr int kRegistrationReach = 8;
constexpr int kRegistrationRow = 2 * kRegistrationReach + 1;

// The wire's nodes [*lo, *hi] of a held registration's row, on a wire of `nodes` nodes.
inline void registration_reach(const LateralRegistration& r, int nodes, int* lo, int* hi) {
  *lo = std::max(0, r.node - kRegistrationReach);
  *hi = std::min(nodes - 1, r.node + kRegistrationReach);
}

// The values per node and lane of LateralModel::planes ([node][value][lane]): the lateral plane's
// load, its mass-proportional damping alpha m, inverse mass and the wind drag coefficient
// cw = 0.5 rho Cd d h (the fused step reads them as PackSweep::plane).
enum { kPlaneLoad, kPlaneDamping, kPlaneInvMass, kPlaneDrag, kPlaneValues };

struct LateralModel {
  std::vector<Wire> wires;  // per Model::wires: its band; w_dof indexes the lateral arrays; rotations condensed
  int n = 0;                // lateral DOFs (one per wire node)
  Eigen::VectorXd mass, inv_mass;  // kg; inv_mass 0 on rigidly held nodes
  Eigen::VectorXd load;            // N, constant: the curve's T kappa h and the springs' k stagger
  std::vector<LateralSpring> springs;
  std::vector<LateralPendulum> pendulums;
  std::vector<LateralClamp> clamps;  // clamp k is Model::clamps[k]
  std::vector<LateralSupport> supports;
  // The hinged steady arms' registrations (empty without hinged arms, or on no 3-D line).
  std::vector<LateralRegistration> registrations;
  Eigen::VectorXd calm;     // m, static lateral positions without wind
  Eigen::VectorXd initial;  // m, static under the mean wind (the pass starts here)
  // Wind: per node 0.5 rho Cd d h (kg/m) and the sine of the wind's angle to the wire.
  bool windy = false;
  // The lateral plane steps only the moving window (numerics.window), except in a turbulent wind on
  // a finite line without numerics.gust_lead: there it steps the whole line, because a span
  // entering the window at rest in the mean wind would lack the motion the gusts built up over the
  // lateral modes' decay (about 9 s, against the window's lead of 1-2 s: 9-16 % less rms across the
  // strip, BENCHMARKS.md). An endless line is always windowed, with a gust lead in a turbulent wind.
  bool windowed = false;
  // s: in a turbulent wind, how long ahead of the vertical window's front the lateral plane is
  // stepped (the gust lead), as time of travel at the train's speed (numerics.gust_lead; 0
  // otherwise): by the lateral window itself, or on its own (lead_every below).
  double gust_lead = 0.0;
  // The implicit gust lead (NumericsSpec::gust_lead_step, engine/lateral_lead.hpp): 0 when the lead
  // is stepped with the window; else the vertical steps per lead step, whose dt is the wind's
  // refresh interval. The lead takes the trapezoidal rule: per wire (D + K) zeta = r, D = shift M,
  // shift = (2 / dt + alpha) / (dt / 2 + beta), lead_beta = dt / 2 + beta, lead_v_ratio =
  // (2 / dt) / shift; lead_mass is M with the springs' and the pendulums' own stiffness (at the
  // droppers' static tension) over shift on the diagonal, so that the solve takes them implicitly.
  int lead_every = 0;
  double lead_dt = 0.0, lead_shift = 0.0, lead_beta = 0.0, lead_v_ratio = 0.0;
  Eigen::VectorXd lead_mass;
  double wind_speed = 0.0;
  Eigen::VectorXd wind_coefficient, wind_normal;
  WindField field;                 // turbulence (empty: steady wind)
  // A finite line's field: every point's series, made with the model (an endless line's state
  // holds its block's points, LateralState::wind_field).
  WindFieldBuffer field_values;
  double field_block_end = 0.0;    // m, an endless line's last node in the block (before its offset)
  std::vector<int> field_index;    // per node: the field point at or before it
  std::vector<double> field_weight;  // per node: linear weight of the next point
  // The nodes between two field points as runs of DOFs [begin, end) at field point `point` (a
  // wire's nodes are in station order): the refresh interpolates a run with the two points' values
  // at hand, a loop that vectorises where a gather per node does not. Finite lines only.
  struct FieldRun {
    int begin = 0, end = 0, point = 0;
  };
  std::vector<FieldRun> field_runs;
  double omega_max = 0.0;          // rad/s, highest lateral eigenfrequency
  int substeps = 1;                // lateral steps per vertical step
  double dt = 0.0;                 // s, lateral step
  double half_working_width = 0.0, half_horn_width = 0.0;  // m
  std::vector<double> node_x;      // m, per lateral DOF: the node's station (an endless line's block station)
  std::vector<int> node_span;      // per lateral DOF: span along the line for contact-wire nodes, -1 otherwise
                                   // (and everywhere on an endless line, whose block spans are not the line's)
  int spans = 0;
  std::vector<double> static_blow_off;  // m, per span: largest |initial - calm| on the contact wire(s)
  // The fused step (wire_lanes.hpp): the vertical plane's packs (Model::wire_packs: the same
  // band and factors, a round wire bends alike both ways) swept with the lateral plane's own load,
  // damping, inverse mass and wind drag coefficient (per pack [node][value][lane]: PackSweep::
  // plane) and the wind's drag, the records in the vertical step's scratch (StepWorkspace::sweep, free
  // between steps, or LateralWorkspace::sweep when the vertical step takes it along); the nodes with
  // point forces (springs, pendulums) with where the sweep leaves their band force. No planes
  // (the vertical step not fused: implicit, or rotations as DOFs): the generic step.
  std::vector<std::vector<double>> planes;
  // The centred damping step (NumericsSpec::damping centred; empty otherwise): per pack the factors
  // of the lateral plane's solve at its own dt, laid out as WireLanes::centred_twin and
  // centred_single (the same band, the lateral masses and held nodes); the held DOFs (inv_mass 0),
  // whose row is zeta = y; (2 / dt) / D per mass.
  std::vector<std::vector<double>> centred_twin, centred_single;
  // The same solve taken along by the vertical step's (step.cpp), both planes of one wire in two
  // lanes, where wind loads the plane, nothing in the lateral forces reads the vertical step's
  // result (no droppers' pendulums, no hinged arms), the plane takes one substep a step at the
  // vertical dt and has no window: per pack of one wire its factors with the vertical plane's in lane 0 and the lateral
  // plane's in lane 1, laid out as centred_twin (empty for a pack of two wires); empty otherwise.
  std::vector<std::vector<double>> centred_joint_twin, centred_joint_single;
  std::vector<int> centred_held;
  double centred_v_ratio = 0.0;
  std::vector<int> point_nodes;
  // Per lateral DOF: where the sweep leaves its band force (fused step), in StepWorkspace::sweep's
  // layout and in the joint records of the vertical step's sweep (WirePacks::dof_joint_force).
  std::vector<int> sweep_force_at, joint_force_at;
  // Moving window (numerics.window; the vertical plane's window, State::window: the lateral waves
  // run at the same sqrt(T/rhoA)): -K initial over the whole line, so that the window's cut ends
  // get the force of the elements left out in the static state (outside, the wires stay there);
  // the springs in line order, for the window to find its own by bisection.
  Eigen::VectorXd static_elastic_force;
  std::vector<int> spring_order;
  std::vector<double> spring_order_x;
};

// s: how far ahead of the vertical window the lateral plane is stepped, as time of travel
// (LateralModel::gust_lead): 0 without a turbulent wind or a window; numerics.gust_lead when given;
// auto on an endless line two decay times 1 / sigma of the slowest wire's lateral motion,
// sigma = rho Cd d U_n / (2 m') + alpha / 2 (the drag's aerodynamic damping and eq. 5's mass term),
// at most kAutoGustLeadMax; auto on a finite line 0 (its whole lateral plane is stepped).
double gust_lead_time(const Scene& scene);
constexpr double kGustLeadDecays = 2.0, kAutoGustLeadMax = 30.0;  // s
// Share of the turbulent field's sample time (1 / (4 max_frequency)) between refreshes of the wind
// on the nodes: 0.01 s at 5 Hz, whose hold costs the field sinc^2(f 0.01 s), 0.8 % at 5 Hz. The
// implicit gust lead steps at this interval.
constexpr double kWindRefreshShare = 0.2;

// The implicit gust lead's step (LateralModel::lead_*): how many vertical steps a lead step takes
// where the scene steps its lead implicitly (a turbulent wind's lead, the fused packs, no stitch
// wires' clamps, whose stiffness joins two wires' solves), else 0: the wind's refresh interval in
// whole vertical steps. set_lead_step sets the lead's fields for `every` (0: no implicit lead).
int default_lead_every(const Model& model, const LateralModel& lat);
void set_lead_step(const Model& model, LateralModel& lat, int every);

// What a steady arm at a support node meets sideways (HingedArmSpec), for any line, 2-D ones too:
// `stiffness` (N/m), the wire's lateral stiffness there with that support alone let go and every
// other held (the tensioned wires with their bending, the droppers as pendulums at their design
// tension, as the lateral plane has them); `pull_off` (N), the wire's calm lateral force on the
// support in the lateral statics (0 on a 2-D line: no stagger, no curve).
struct RegistrationLateral {
  double stiffness = 0.0, pull_off = 0.0;
  double side = 0.0;  // the pull's direction: +1 toward + y, -1, 0 without one
};
// One per vertical DOF of `dofs` (support nodes of a contact wire).
std::vector<RegistrationLateral> registration_lateral(const Model& model, const std::vector<int>& dofs);

// The line in plan as designed: its wires, supports, registrations and wind, and its static
// states (calm and under the mean wind). No numerics: nothing here reads dt or the damping step.
// Throws SceneError.
std::shared_ptr<const LateralModel> design_lateral(const Model& model);
// Builds the lateral plane of a model whose scene asks for one (Scene::lateral()): `design`, the
// model's line in plan, with the numerics of the model's dt; throws SceneError.
std::shared_ptr<const LateralModel> build_lateral(const Model& model, const LateralModel& design);
std::shared_ptr<const LateralModel> build_lateral(const Model& model);  // designed here
// Highest eigenfrequency (rad/s, with the planes' 0.2 % margin) of both planes together with the
// droppers' lean coupling, of the K the explicit step takes at q_n: about the static state a
// dropper of stiffness k leaning by s = dy0 / l couples its ends' relative height and position
// across the track through [[k, k s], [k s, T0 / l + k s^2]] (its stretch takes s dy, its
// pendulum the tension's change), which neither plane's own estimate holds.
double lean_coupled_omega_max(const Model& model, const LateralModel& lateral);
// Designs the line in plan alone (the bridles' registrations, the wires inside the working
// width, the static states) and throws SceneError for what build_lateral would refuse there. For
// a model built without its numerics (BuildOptions::stability false), e.g. the elasticity's probe.
void check_lateral_design(const Model& model);

// Lateral static state of the wires (y: n entries) under the constant loads, the droppers at their
// static tension, with (mean wind) or without wind; `force_on_support` (optional, per
// LateralModel::supports) receives the lateral force of each wire on its supports;
// `registration_travel` (optional, per LateralModel::registrations) moves each hinged arm's
// registration point (its held node, or its spring's anchor) out by that much.
void solve_lateral_statics(const Model& model, const LateralModel& lat, bool with_wind, Eigen::VectorXd* y,
                           std::vector<double>* force_on_support, const std::vector<double>* registration_travel = nullptr);

}  // namespace catenary_sim
