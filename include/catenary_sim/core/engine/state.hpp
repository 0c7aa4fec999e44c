// The mutable state of a pass (MuJoCo's mjData to the Model's mjModel): displacements, half-step
// velocities, train kinematics, commands in effect, the contact and dropper activity of the last
// step, and the step's preallocated workspace (opaque here) so that step() never allocates.
#pragma once

#include <Eigen/Core>
#include <cassert>
#include <cstddef>
#include <cstdint>
#include <vector>

#include "catenary_sim/core/engine/lateral_step.hpp"
#include "catenary_sim/core/model/model.hpp"
#include "catenary_sim/core/engine/step.hpp"
#include "catenary_sim/core/engine/wire_window.hpp"
#include "catenary_sim/core/util/deep_copied.hpp"

namespace catenary_sim {

enum class StepStatus {
  kOk = 0,
  kDiverged,   // a displacement would leave the divergence limit or become NaN/inf: the run is
               // stopped and the state keeps the last good step
  kFinished,   // the train front reached the end of the pass; step() does nothing more
  kDewired,    // a contact point left the strip's working width and the scene says stop (3-D line)
};

// Implicit integrator: slack droppers it can take out of its matrix at once (each keeps a column
// of n values); more stops the run with a message. Active-set passes per step at most.
constexpr std::size_t kSlackDropperCapacity = 64;
constexpr int kMaxActiveSetPasses = 4;

struct StepWorkspace;
extern template class DeepCopied<StepWorkspace>;  // (instantiated in state.cpp)

// Owns a State's step workspace (whose contents only the engine sees) and copies it deep.
using StepWorkspaceHandle = DeepCopied<StepWorkspace>;

struct State {
  double time = 0.0;       // s, simulation time since the pass started
  std::int64_t steps = 0;
  double front = 0.0;      // m, train front position (a block station on an endless line)
  double line_offset = 0.0;  // m, station along the line of the model's station 0 (endless line)
  double speed = 0.0;      // m/s, train speed now
  double target_speed = 0.0;      // m/s, commanded speed the train accelerates toward
  double max_acceleration = 0.0;  // m/s^2, |dv/dt| limit toward target_speed (0: jump)
  std::vector<double> uplift;     // N, static uplift in effect per pantograph (eq. 9 thrust F)
  std::vector<double> external_force;  // N, force of an external (hardware-in-the-loop) pantograph
  // m/s per pantograph, the wind against the direction of travel at the pantograph (3-D line with
  // wind: mean plus turbulence, set by the lateral step; else 0). The aerodynamic uplift a v^2 is
  // measured in still air: with wind it takes the speed through the air, v + head wind.
  std::vector<double> head_wind;

  // q of eq. 21 as displacements from the design state, and q_dot_{n-1/2} (eq. 20, 26); with the
  // implicit integrator v is the velocity at the state's time.
  Eigen::VectorXd u, v;
  Eigen::VectorXd accel;  // q'' of the last step (at its start, t_n), for observers

  // Uplift (m, + up, from the design state) of node `node` of wire `wire` (Model::wires).
  double wire_uplift(const Model& m, int wire, int node) const { return u[wire_dof(m, wire, node)]; }
  double& wire_uplift(const Model& m, int wire, int node) { return u[wire_dof(m, wire, node)]; }
  // Height (m, absolute) of that node: its design height plus its uplift.
  double wire_height(const Model& m, int wire, int node) const {
    return m.wires[wire].height[node] + u[wire_dof(m, wire, node)];
  }
  // Uplift (m) of a support spring's wire node (Model::springs: a steady arm or a messenger support).
  double support_uplift(const Model& m, int spring) const {
    assert(spring >= 0 && static_cast<std::size_t>(spring) < m.springs.size());
    return u[m.springs[spring].dof];
  }
  // Displacement (m) and velocity (m/s) of a pantograph's mass `mass`, 0 <= mass < dof_count():
  // the chain from the head down (Pantograph::masses), then its heads (Pantograph::heads).
  double pantograph_displacement(const Model& m, int pantograph, int mass) const { return u[pantograph_dof(m, pantograph, mass)]; }
  double& pantograph_displacement(const Model& m, int pantograph, int mass) { return u[pantograph_dof(m, pantograph, mass)]; }
  double pantograph_velocity(const Model& m, int pantograph, int mass) const { return v[pantograph_dof(m, pantograph, mass)]; }
  double& pantograph_velocity(const Model& m, int pantograph, int mass) { return v[pantograph_dof(m, pantograph, mass)]; }

  // Observations of this state (time, front, u): filled by step() and observe().
  std::vector<double> contact_force;     // N, >= 0, per collector x contact wire (eq. 22, 25)
  std::vector<double> collector_height;  // m, weighted wire height under each collector (eq. 12)
  std::vector<std::uint8_t> dropper_slack;  // 1 where the dropper carried no tension
  // N, per dropper taken at the step's middle (Model::dropper_at_middle): the tension it carried
  // over the last step, the trapezoidal rule's (NaN before the first step and where a moving
  // window has left it, where the elastic tension at u is the one); empty when every dropper is
  // taken at q_n.
  std::vector<double> dropper_tension;

  // Contact force (N) of collector `collector` (Model::collectors) on contact wire `wire`
  // (Model::contact_wires).
  double contact_force_on(const Model& m, int collector, int wire) const { return contact_force[contact_index(m, collector, wire)]; }
  double& contact_force_on(const Model& m, int collector, int wire) { return contact_force[contact_index(m, collector, wire)]; }
  // Weighted height (m, absolute) of contact wire `wire` under collector `collector` (eq. 12).
  double wire_height_under(const Model& m, int collector, int wire) const {
    return collector_height[contact_index(m, collector, wire)];
  }
  // Contact force (N) of one collector, summed over the contact wires (two in an overlap).
  double collector_force(const Model& m, int collector) const {
    double f = 0.0;
    for (std::size_t k = 0; k < m.contact_wires.size(); ++k) f += contact_force_on(m, collector, static_cast<int>(k));
    return f;
  }
  // Contact force (N) of one pantograph on one contact wire, summed over its collectors.
  double pantograph_force_on(const Model& m, int pantograph, int wire) const {
    double f = 0.0;
    for (int ci : m.pantographs[pantograph].collectors) f += contact_force_on(m, ci, wire);
    return f;
  }
  // Contact force (N) of head `head` of Pantograph::heads (its collectors, every contact wire);
  // head < 0 or a pantograph without heads: all its collectors (= total_contact_force). Summed
  // collector by collector and wire by wire, in the order total_contact_force sums.
  double head_contact_force(const Model& m, int pantograph, int head) const {
    const Pantograph& pg = m.pantographs[pantograph];
    double f = 0.0;
    for (int ci : pg.collectors)
      if (head < 0 || pg.heads.empty() || m.collectors[ci].head == head)
        for (std::size_t k = 0; k < m.contact_wires.size(); ++k) f += contact_force_on(m, ci, static_cast<int>(k));
    return f;
  }

  StepStatus status = StepStatus::kOk;
  int diverged_dof = -1;
  // m: what the rejected step gave diverged_dof (beyond numerics.divergence_limit, or NaN); the
  // state itself keeps the last good step.
  double diverged_displacement = 0.0;
  bool active_set_full = false;  // implicit: more droppers slack at once than it takes out (kDiverged)

  // Moving window (numerics.window): the supports it spans and what it integrates.
  int window_first_support = -1, window_last_support = -1;
  std::vector<WireWindow> window;
  std::vector<int> window_droppers, window_springs;  // the first *_count entries are in the window
  int window_dropper_count = 0, window_spring_count = 0;
  std::vector<int> window_clamps;  // stitch wires' clamps (Model::clamps) in the window
  int window_clamp_count = 0;

  // The step's buffers and caches (engine/step_workspace.hpp, private to the engine), sized once
  // by make_state(); a copied state gets its own, so it steps exactly as its original would.
  StepWorkspaceHandle work;

  // 3-D line (Model::lateral): the wires' lateral planes; empty without one.
  LateralState lateral;

 private:
  // The flat layouts of the vectors above (the step's hot loops index them directly). Checked
  // in debug builds only: the accessors stay as cheap as the index.
  static int wire_dof(const Model& m, int wire, int node) {
    assert(wire >= 0 && static_cast<std::size_t>(wire) < m.wires.size());
    assert(node >= 0 && node < m.wires[wire].nodes());
    return m.wires[wire].w_dof + node;
  }
  static int pantograph_dof(const Model& m, int pantograph, int mass) {
    assert(pantograph >= 0 && static_cast<std::size_t>(pantograph) < m.pantographs.size());
    assert(!m.pantographs[pantograph].moving_force && mass >= 0 && mass < m.pantographs[pantograph].dof_count());
    return m.pantographs[pantograph].first_dof + mass;
  }
  static std::size_t contact_index(const Model& m, int collector, int wire) {
    assert(collector >= 0 && static_cast<std::size_t>(collector) < m.collectors.size());
    assert(wire >= 0 && static_cast<std::size_t>(wire) < m.contact_wires.size());
    return static_cast<std::size_t>(collector) * m.contact_wires.size() + static_cast<std::size_t>(wire);
  }
};

// A state sized for the model with zero displacement (the design state, no pantograph force).
State make_state(const Model& model);

// Fills the observations (contact forces, collector heights) for the current state without
// advancing it, e.g. for the initial state.
void observe(const Model& model, State& state);

// Motion of the contact wire under one pantograph's collectors, per collector and contact wire:
// what a hardware-in-the-loop rig must impose on a real pantograph (eq. 12 weights).
struct ContactPointMotion {
  int collector = 0, wire = 0;   // indices into Model::collectors and Model::contact_wires
  bool on_wire = false;          // false: the collector is not under this wire
  double height = 0.0;           // m, absolute
  double velocity = 0.0;         // m/s, of the wire point under the collector, at the state's time
                                 // (half-step velocity + dt/2 acceleration)
  double acceleration = 0.0;     // m/s^2, of the wire point under the collector (last step)
  double path_velocity = 0.0;    // m/s, rate of change of `height` seen by the moving pantograph:
                                 // velocity + train speed x wire slope
  double force = 0.0;            // N, contact force on this wire
};
void contact_point_motion(const Model& model, const State& state, int pantograph, std::vector<ContactPointMotion>& out);
// The entry of contact_point_motion's `motion` for the pantograph's collector `j` (its place in
// Pantograph::collectors) and contact wire `wire` (Model::contact_wires).
inline const ContactPointMotion& motion_under(const Model& model, const std::vector<ContactPointMotion>& motion,
                                              std::size_t j, std::size_t wire) {
  assert(wire < model.contact_wires.size() && j * model.contact_wires.size() + wire < motion.size());
  return motion[j * model.contact_wires.size() + wire];
}

// Absolute height of a contact collector's pantograph head (m); NaN for a moving force. With
// several heads: their mean.
double head_height(const Model& model, const State& state, int pantograph);
// Heads of a pantograph: 0 for a moving force, 1 for a chain without `heads` (its first mass),
// else one per head on its own suspension.
int head_count(const Model& model, int pantograph);
// Absolute height (m) of one head, 0 <= head < head_count; NaN for a moving force.
double head_height(const Model& model, const State& state, int pantograph, int head);
// The pantograph's speed through the air, squared (m^2/s^2): (v + head wind)^2, the v^2 of every
// aerodynamic uplift a v^2.
inline double air_speed_squared(const State& state, std::size_t pantograph) {
  const double v = state.speed + state.head_wind[pantograph];
  return v * v;
}
// The head's own aerodynamic uplift at the state's air speed (N): a_h v^2 for the knee direction;
// 0 for a chain without `heads` (its aero acts on the frame) and for a moving force.
double head_aero_uplift(const Model& model, const State& state, int pantograph, int head);
// The aerodynamic uplift on the frame (N): a v^2 for the knee direction, at the state's air speed.
double frame_aero_uplift(const Model& model, const State& state, int pantograph);
// Position of a pantograph's reference point along the line (m).
double pantograph_position(const Model& model, const State& state, int pantograph);
// Sum of the contact forces of one pantograph over its collectors and the contact wires (N).
double total_contact_force(const Model& model, const State& state, int pantograph);

}  // namespace catenary_sim
