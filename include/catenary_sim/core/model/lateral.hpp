// The 3-D line: every wire's lateral (horizontal) plane, built from the same pre-stressed beam
// band as its vertical plane (same T, EI and nodes; a round wire bends alike both ways) and
// stepped with its own explicit central differences after the vertical step.
//
// Coordinates: y is the wire's lateral position from the track centre line (+ to the left in the
// direction of increasing station), in the track's own frame. A curve of curvature kappa then
// acts on a wire of tension T as the distributed lateral load T kappa (the wire is straight in
// plan, so in the curved frame T (y'' + kappa) + q = 0): the chords between supports come out of
// the statics, and the steady arms carry the pull-off T x (change of direction).
// Droppers are pendulums of stiffness S / l (tension over length) between the messenger and the
// contact wire; steady arms and messenger supports are lateral springs (or rigid) at the
// stagger; anchors are rigid. Wind pushes each node with 0.5 rho Cd d h V|V|, V the wind's
// speed normal to the wire less the node's lateral velocity (aerodynamic damping included).
//
// Two-way coupling through the droppers' geometry (docs/model_and_numerics.md, "Coupling"): a
// dropper of length l whose ends are dz apart vertically (from the design) and dy = y_m - y_c
// laterally is stretched by sqrt((l + dz)^2 + dy^2) - l ~ dz + dy^2 / (2 l). The built line holds
// the static lean dy0 (LateralModel::initial, under the mean wind), so the stretch is
// e = dz + (dy^2 - dy0^2) / (2 l) and one potential V(e) = S0 e + k e^2 / 2 (0 force when slack,
// S0 + k e <= 0) serves both planes: the vertical force is S = S0 + k e, the lateral one S dy / l
// (the pendulum). At the pass start e is the vertical plane's design stretch, so its static state
// stays the design statics'; the lean's change during the pass acts on the vertical plane.
// Order: the vertical step takes each dropper's lean stretch averaged over the previous lateral
// step's substeps (LateralState::dropper_stretch), which all read the u the vertical step starts
// from; every kick of V is then taken at one configuration for both planes, which makes the
// partitioned step symplectic (the undamped, windless energy line_energy stays bounded, no drift:
// Lateral.CoupledEnergyIsConserved). Reading the lean at one instant instead makes it drift.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <memory>
#include <vector>

#include "catenary_sim/core/model/model.hpp"
#include "catenary_sim/core/model/wind_field.hpp"
#include "catenary_sim/core/engine/wire_window.hpp"

namespace catenary_sim {

struct State;
enum class StepStatus;

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

struct LateralModel {
  std::vector<Wire> wires;  // per Model::wires: its band; w_dof indexes the lateral arrays; rotations condensed
  int n = 0;                // lateral DOFs (one per wire node)
  Eigen::VectorXd mass, inv_mass;  // kg; inv_mass 0 on rigidly held nodes
  Eigen::VectorXd load;            // N, constant: the curve's T kappa h and the springs' k stagger
  std::vector<LateralSpring> springs;
  std::vector<LateralPendulum> pendulums;
  std::vector<LateralSupport> supports;
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
  // s: in a turbulent wind, how long ahead of the vertical window's front the lateral window
  // reaches, as time of travel at the train's speed (numerics.gust_lead; 0 otherwise).
  double gust_lead = 0.0;
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
  // plane) and the wind's drag, the records in the vertical step's scratch (State::sweep, free
  // between steps, or LateralState::sweep when the vertical step takes it along); the nodes with
  // point forces (springs, pendulums) with where the sweep leaves their band force. No planes
  // (the vertical step not fused: implicit, or rotations as DOFs): the generic step.
  std::vector<std::vector<double>> planes;
  std::vector<int> point_nodes;
  std::vector<int> sweep_force_at;  // per lateral DOF: where the sweep leaves its band force (fused step)
  // Moving window (numerics.window; the vertical plane's window, State::window: the lateral waves
  // run at the same sqrt(T/rhoA)): -K initial over the whole line, so that the window's cut ends
  // get the force of the elements left out in the static state (outside, the wires stay there);
  // the springs in line order, for the window to find its own by bisection.
  Eigen::VectorXd static_elastic_force;
  std::vector<int> spring_order;
  std::vector<double> spring_order_x;
};

// s: how far ahead of the vertical window the lateral plane's window reaches, as time of travel
// (LateralModel::gust_lead): 0 without a turbulent wind or a window; numerics.gust_lead when given;
// auto on an endless line two decay times 1 / sigma of the slowest wire's lateral motion,
// sigma = rho Cd d U_n / (2 m') + alpha / 2 (the drag's aerodynamic damping and eq. 5's mass term),
// at most kAutoGustLeadMax; auto on a finite line 0 (its whole lateral plane is stepped).
double gust_lead_time(const Scene& scene);
constexpr double kGustLeadDecays = 2.0, kAutoGustLeadMax = 30.0;  // s

// Builds the lateral plane of a model whose scene asks for one (Scene::lateral()); throws SceneError.
std::shared_ptr<const LateralModel> build_lateral(const Model& model);

// Lateral static state of the wires (y: n entries) under the constant loads, the droppers at their
// static tension, with (mean wind) or without wind; `force_on_support` (optional, per
// LateralModel::supports) receives the lateral force of each wire on its supports.
void solve_lateral_statics(const Model& model, const LateralModel& lat, bool with_wind, Eigen::VectorXd* y,
                           std::vector<double>* force_on_support);

struct DewirementEvent {
  double time = 0.0;     // s
  double station = 0.0;  // m, of the collector along the line
  int pantograph = 0, collector = 0;
  double lateral = 0.0;  // m, contact point on the strip when it left the working width
};
constexpr std::size_t kMaxDewirementEvents = 1024;  // kept per pass; more are counted only

struct LateralState {
  Eigen::VectorXd y, v;      // m, m/s (v at the half step, eq. 20)
  // m, per dropper (Model::droppers): its lean's stretch averaged over the last lateral step's
  // substeps, which the next vertical step adds to the dropper's vertical stretch.
  std::vector<double> dropper_stretch;
  // Per dropper: 1 where the lean acts on its tension, 0 outside the vertical plane's window.
  std::vector<double> lean_weight;
  Eigen::VectorXd f, z;      // workspace
  Eigen::VectorXd y_next, v_next, accel;  // the fused step's new values
  // Both planes' sweep records when the vertical step takes the lateral sweep along
  // (step_both_planes, sweep_pack_pair's joint layout), and that hand-over: `join` while the
  // vertical step may take it, `joined` when it did, with the lateral sweep's divergence hint.
  std::vector<double> sweep;
  bool join = false, joined = false, joined_outside = false;
  std::int64_t joined_steps = 0;  // steps whose lateral sweep the vertical step took along
  std::vector<double> theta, wind_points;
  Eigen::VectorXd wind_speed;    // m/s, per node: the wind's speed normal to the wire now
  double next_wind_update = 0.0;  // s
  double wind_time = 0.0;         // s, of the last refresh (wind_points' time)
  // An endless line's turbulent field over its block: generated ahead as the block moves on,
  // in buffers sized once (wind_field.hpp). wind_points holds its points' values from first().
  WindFieldBuffer wind_field;
  std::vector<int> weight_node;
  std::vector<double> weight;
  // Per collector x contact wire: the contact point's lateral position on the strip (wire minus
  // pantograph), NaN where the collector is not under that wire.
  std::vector<double> contact_lateral;
  // Per collector: on the running wire (the one it touches, else the lowest), NaN if none.
  std::vector<double> collector_lateral;
  std::vector<double> pantograph_lateral;  // m, per pantograph (sway)
  std::vector<std::uint8_t> off_strip;     // per collector: outside the working width now
  std::vector<DewirementEvent> events;     // capacity reserved: never allocates in step
  std::int64_t events_total = 0;
  bool diverged = false, dewired_stop = false;
  // Moving window: the part of each wire the lateral plane steps, from the vertical plane's
  // window's first support to its last or, with a gust lead (LateralModel::gust_lead), a support
  // further ahead (outside, the nodes stay in the static state under the mean wind, at rest); the
  // factors interleaved for the fused step; the springs and the droppers' pendulums in it (first
  // *_count entries; pendulum k is dropper k), the static force of the left-out elements on the
  // nodes near the cuts, and the nodes with point forces for the fused step. Sized once: no
  // allocation.
  std::vector<WireWindow> window;
  int window_first_support = -1, window_last_support = -1;
  bool window_dirty = true;  // lists and factors to rebuild (the endless block moved)
  std::vector<double> sweep_factors;
  std::vector<int> window_springs, window_droppers;
  int window_spring_count = 0, window_dropper_count = 0;
  std::vector<int> cut_node;
  std::vector<double> cut_force;
  int cut_count = 0;
  std::vector<int> window_points;
  int window_point_count = 0;
  bool window_fused = false;  // the fused step can take the window (every wire's range two nodes or more)
};

LateralState make_lateral_state(const Model& model);
// State::head_wind of every pantograph: the wind's component against the direction of travel at
// its station, from the mean wind and `field_points` (the turbulent field's held points at one
// time, WindFieldBuffer::at_time; null: the mean wind alone). The lateral step calls it with its latest refresh.
void update_head_wind(const Model& model, State& state, const WindFieldBuffer* field, const double* field_points);
// Contact point positions of the current state (no step).
void lateral_observe(const Model& model, State& state);
// One lateral step of the model's dt (its substeps), after the vertical step moved the state to
// its new time. Never allocates. Returns kDiverged or kDewired (on_dewirement: stop), else kOk.
StepStatus lateral_step(const Model& model, State& state);
// The vertical step, then the lateral one (Simulation::step on a 3-D line). Where both planes
// sweep every node of the same two-wire packs (no window, one lateral substep, both fused), the
// vertical step runs the lateral step's band sweep with its own, both planes in four lanes
// (sweep_pack_pair: the band and its factors are the same both ways, loaded once, and each band
// operation does both planes). The lateral sweep reads nothing the vertical step changes (the
// lateral state, the wind of the step's start, the shared band and factors), and each lane does
// its own plane's operations, so the results are those of step then lateral_step, to the bit.
StepStatus step_both_planes(const Model& model, State& state);

// Endless line: moves the lateral state back Model::endless_shift_spans spans with the block
// (called by shift_endless_block before it moves the train); the spans entering at the far end
// start in the static state. No allocation.
void shift_lateral_block(const Model& model, State& state);

// Sets LateralState::dropper_stretch from the current y (after y was set by hand, or moved).
void set_dropper_stretch(const Model& model, State& state);

// Lateral energy without wind: 0.5 v M v + 0.5 y K y - load . y of the wires and lateral supports,
// plus what the lean adds to the droppers' potential at the current vertical state,
// V(e_z + e_lean) - V(e_z) (J); constant in an undamped, windless free motion of the lateral
// plane alone (the vertical one held).
double lateral_energy(const Model& model, const State& state);

// Energy of the whole line, both planes, the droppers' shared potential V(e) counted once:
// kinetic, the wires' and supports' strain, less the constant loads' work (J). Constant in an
// undamped, windless free motion of a line without pantographs on the full line (no window).
double line_energy(const Model& model, const State& state);

}  // namespace catenary_sim
