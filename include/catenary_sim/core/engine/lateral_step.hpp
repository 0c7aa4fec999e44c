// The 3-D line's lateral plane in motion (the plane itself: model/lateral.hpp): its own explicit
// central differences after the vertical step, with substeps where its stability limit asks.
//
// Order: the vertical step takes each dropper's lean stretch averaged over the previous lateral
// step's substeps (LateralState::dropper_stretch), which all read the u the vertical step starts
// from; every kick of the droppers' potential V is then taken at one configuration for both
// planes, which makes the partitioned step symplectic (the undamped, windless energy line_energy
// stays bounded, no drift: Lateral.CoupledEnergyIsConserved). Reading the lean at one instant
// instead makes it drift.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <vector>

#include "catenary_sim/core/model/lateral.hpp"
#include "catenary_sim/core/model/model.hpp"
#include "catenary_sim/core/model/wind_field.hpp"
#include "catenary_sim/core/util/reserved_vector.hpp"
#include "catenary_sim/core/engine/wire_window.hpp"
#include "catenary_sim/core/util/deep_copied.hpp"

namespace catenary_sim {

struct State;
enum class StepStatus;

struct DewirementEvent {
  double time = 0.0;     // s
  double station = 0.0;  // m, of the collector along the line
  int pantograph = 0, collector = 0;
  double lateral = 0.0;  // m, contact point on the strip when it left the working width
};
constexpr std::size_t kMaxDewirementEvents = 1024;  // kept per pass; more are counted only

struct LateralWorkspace;
extern template class DeepCopied<LateralWorkspace>;  // (instantiated in lateral_step.cpp)

// The lateral plane's state: what a copy needs to step on exactly as its original (test_state),
// and its outputs. The step's buffers and lists live in `work`, private to the engine.
struct LateralState {
  Eigen::VectorXd y, v;      // m, m/s per lateral DOF (v at the half step, eq. 20)
  // m, per dropper (Model::droppers): its lean's stretch averaged over the last lateral step's
  // substeps, which the next vertical step adds to the dropper's vertical stretch.
  std::vector<double> dropper_stretch;
  // m, per hinged arm's registration (LateralModel::registrations): the arm's end's sideways
  // travel from the stagger (registration_travel) at the u the last lateral step read, where that
  // step put the registration point (a held node; a spring's anchor).
  std::vector<double> registration_travel;
  // N, per registration: the vertical force the wire's lateral force puts on its arm's end,
  // (F - F0) side tan(theta) (LateralRegistration), averaged over the last lateral step's
  // substeps; the next vertical step adds it on the registration's vertical DOF.
  std::vector<double> registration_force;

  // The wind held between its refreshes (a turbulent wind; steady: the mean wind throughout).
  Eigen::VectorXd wind_speed;     // m/s, per node: the wind's speed normal to the wire now
  double next_wind_update = 0.0;  // s, of the next refresh
  double wind_time = 0.0;         // s, of the last refresh (wind_points' time)
  std::vector<double> wind_points;  // m/s, the turbulent field's held points at wind_time
  // An endless line's turbulent field over its block: generated ahead as the block moves on,
  // in buffers sized once (wind_field.hpp). wind_points holds its points' values from first().
  WindFieldBuffer wind_field;

  // Moving window's placement, for observers (lateral_statistics counts the blow-off where it
  // steps): the part of each wire the lateral plane steps (node ranges, with their factors), from
  // the vertical plane's window's first support to its last or, with a gust lead stepped with the
  // window (LateralModel::gust_lead, lead_every 0), a support further ahead; outside (and in an
  // implicit lead, which has its own state below), the nodes stay in the static
  // state under the mean wind, at rest. Support indices into Model::support_x, -1: none yet. The
  // step derives it from State::window (sync_window; test_state: a copy without it steps the same).
  std::vector<WireWindow> window;
  int window_first_support = -1, window_last_support = -1;

  // The implicit gust lead (LateralModel::lead_every > 0, engine/lateral_lead.hpp): each wire from
  // the lateral window's front support to the lead's end, stepped on its own: positions (m) and
  // velocities (m/s) at lead_time and one lead step before it, between which the window takes a
  // node's state when it reaches it; the lead's placement as the window's (lead_first_support is
  // the window's last).
  Eigen::VectorXd lead_y, lead_v, lead_y_before, lead_v_before;
  double lead_time = 0.0;  // s
  std::vector<WireWindow> lead_window;
  int lead_first_support = -1, lead_last_support = -1;

  // Outputs of the last step. Per collector x contact wire: the contact point's lateral position
  // on the strip (m, wire minus pantograph), NaN where the collector is not under that wire.
  std::vector<double> contact_lateral;
  // m, per collector: on the running wire (the one it touches, else the lowest), NaN if none.
  std::vector<double> collector_lateral;
  std::vector<int> collector_wire;  // per collector: that wire (index into Model::contact_wires), -1 if none
  std::vector<double> pantograph_lateral;  // m, per pantograph (sway)
  // Per collector: outside the working width now (a dewirement is a change of it: state too).
  std::vector<std::uint8_t> off_strip;
  ReservedVector<DewirementEvent> events;  // the pass's first ones; room for all reserved, kept by copies
  std::int64_t events_total = 0;           // dewirements of the pass, kept or not
  bool diverged = false;                   // the lateral step left the divergence limit
  // Where: the first lateral DOF (LateralModel index) beyond the limit in the rejected substep,
  // and the position (m, or NaN) that substep gave it; the state keeps the last good substep.
  int diverged_node = -1;
  double diverged_position = 0.0;
  bool dewired_stop = false;               // a dewirement stopped the pass (on_dewirement: stop)

  // The step's buffers, lists and caches (engine/lateral_workspace.hpp, private to the engine),
  // sized once by make_lateral_state(); a copied state gets its own.
  DeepCopied<LateralWorkspace> work;
};

// The lateral plane of a state (make_state gives a 3-D line's state its own).
LateralState make_lateral_state(const Model& model);
// State::head_wind of every pantograph: the wind's component against the direction of travel at
// its station, from the mean wind and `field_points` (the turbulent field's held points at one
// time, WindFieldBuffer::at_time; null: the mean wind alone). The lateral step calls it with its latest refresh.
void update_head_wind(const Model& model, State& state, const WindFieldBuffer* field, const double* field_points);
// Contact point positions of the current state (no step).
void lateral_observe(const Model& model, State& state);
// One lateral step of the model's dt (its substeps), after the vertical step moved the state to
// its new time: step() takes both. Never allocates. Returns kDiverged or kDewired (on_dewirement: stop), else kOk.
StepStatus lateral_step(const Model& model, State& state);

// Endless line: moves the lateral state back Model::endless_shift_spans spans with the block
// (called by shift_endless_block before it moves the train); the spans entering at the far end
// start in the static state. No allocation.
void shift_lateral_block(const Model& model, State& state);

// Lateral position (m) of lateral DOF `dof` now, for skins that draw or publish the wires: the
// lateral state's, or where an implicit gust lead steps the node outside the window, the lead's
// (interpolated to the state's time).
double lateral_position(const Model& model, const State& state, int dof);

// A 3-D line's hinged arms with the vertical plane's u of a static state (the initial state's):
// each registration point where its arm's end is, the lateral plane at rest in its statics with
// them there (under the mean wind), and the wire's answer on each arm from it. Allocates.
void place_registrations(const Model& model, State& state);

// Sets LateralState::dropper_stretch from the current y (after y was set by hand, or moved).
void set_dropper_stretch(const Model& model, State& state);

}  // namespace catenary_sim
