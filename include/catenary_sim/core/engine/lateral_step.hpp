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
#include "catenary_sim/core/engine/wire_window.hpp"

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

// Sets LateralState::dropper_stretch from the current y (after y was set by hand, or moved).
void set_dropper_stretch(const Model& model, State& state);

}  // namespace catenary_sim
