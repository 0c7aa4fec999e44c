#include "catenary_sim/core/simulation.hpp"

#include "util/format.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>

#include "catenary_sim/core/engine/initial_state.hpp"

namespace catenary_sim {

namespace {

// A Scene changed in code after loading (a tool's --speed-kmh) meets the same limit as a file.
const Scene& speed_checked(const Scene& scene) {
  const TrainSpeedLimit limit = train_speed_limit(scene);
  if (!limit.allows(scene.train_speed)) {
    std::ostringstream s;
    s.precision(10);
    s << "scene field 'train.speed_kmh' = " << scene.train_speed * 3.6 << " (" << scene.train_speed
      << " m/s): allowed " << limit.text();
    throw SceneError(s.str());
  }
  return scene;
}

// Where a DOF of a plane (its `wires`) is: "<wire> at x = <station> m", "" for a pantograph's.
std::string wire_at(const std::vector<Wire>& wires, int dof, double line_offset) {
  const int wi = wire_holding(wires, dof);
  if (wi < 0) return "";
  const Wire& w = wires[wi];
  return w.name + " at x = " + fmt(w.x[dof - w.w_dof] + line_offset) + " m";
}

}  // namespace

Simulation::Simulation(const Scene& scene) : model_(build_model(speed_checked(scene))) {
  initial_ = make_state(model_);
  if (model_.lateral && !model_.lateral->field.empty()) {
    // The pass starts in the wind of t = 0: the pantograph's aerodynamic uplift too (an endless
    // line's field: its first points, as its state's will be).
    const LateralModel& lat = *model_.lateral;
    WindFieldBuffer start;
    if (model_.endless) start.reset(lat.field);
    const WindFieldBuffer& values = model_.endless ? start : lat.field_values;
    std::vector<double> points(static_cast<std::size_t>(lat.field.held));
    values.at_time(lat.field, 0.0, points.data());
    update_head_wind(model_, initial_, &values, points.data());
  } else if (model_.lateral) {
    update_head_wind(model_, initial_, nullptr, nullptr);
  }
  solve_initial_state(model_, initial_);
  // A wire's static state already at the watchdog's limit would stop the pass at its first step
  // as a divergence: the scene's doing (a limit below the line's own sag, or loads that sag it
  // that far), refused as such. (A pantograph's, from a contact spring too soft to hold it, is
  // left to the watchdog, whose message names the contact's stiffness: divergence_cause.)
  const double limit = model_.scene.numerics.divergence_limit;
  double reach = 0.0;
  int at = -1;
  for (const Wire& w : model_.wires)
    for (int i = w.w_dof; i < w.w_dof + w.nodes() && !std::isnan(reach); ++i)
      if (!(std::fabs(initial_.u[i]) <= reach)) {  // (a NaN is kept, and refused below)
        reach = std::fabs(initial_.u[i]);
        at = i;
      }
  if (at >= 0 && !(reach < limit))
    throw SceneError("scene field 'numerics.divergence_limit' = " + fmt_given(limit) + " m: the line's static state " +
                     "already reaches " + fmt(reach) + " m (" + wire_at(model_.wires, at, initial_.line_offset) +
                     "); allowed above that (5 m by default), or lighten what sags the line so far (imperfections.point_masses, "
                     "a wire's weight against its tension)");
  observe(model_, initial_);
  if (model_.lateral) lateral_observe(model_, initial_);  // (make_state gave it its lateral plane)
  state_ = initial_;
}

std::string Simulation::status_message() const {
  std::ostringstream s;
  switch (state_.status) {
    case StepStatus::kOk:
      if (finished())
        s << "pass finished at t = " << state_.time << " s (train front at " << state_.front + state_.line_offset << " m)";
      else
        s << "running";
      break;
    case StepStatus::kDewired: {
      if (state_.lateral.events.empty()) {
        s << "stopped at t = " << state_.time << " s: dewirement (pantograph_head.on_dewirement: stop)";
        break;
      }
      const DewirementEvent& e = state_.lateral.events.back();
      s << "stopped at t = " << state_.time << " s: dewirement of pantograph " << model_.pantographs[e.pantograph].name
        << " at " << e.station << " m, contact point " << e.lateral << " m across the strip (working width +-"
        << model_.collectors[e.collector].half_working_width << " m; pantograph_head.on_dewirement: stop)";
      break;
    }
    case StepStatus::kFinished:
      s << "pass finished at t = " << state_.time << " s (train front at " << state_.front + state_.line_offset << " m)";
      break;
    case StepStatus::kDiverged: {
      if (state_.active_set_full) {
        s << "stopped at t = " << state_.time << " s: more than " << kSlackDropperCapacity
          << " droppers slack at once, beyond what the implicit integrator takes out of its matrix; "
             "use numerics.integrator explicit for this scene";
        break;
      }
      if (state_.lateral.diverged) {
        const int node = state_.lateral.diverged_node;
        std::string where = model_.lateral && node >= 0 ? wire_at(model_.lateral->wires, node, state_.line_offset) : "";
        if (where.empty()) where = "a wire";
        s << "diverged at t = " << state_.time << " s: the lateral position of " << where << " reached "
          << state_.lateral.diverged_position << " m (limit " << model_.scene.numerics.divergence_limit
          << " m); the run was stopped at the last step within it. ";
        const double limit = model_.scene.numerics.divergence_limit;
        if (model_.lateral && node >= 0 && !(std::fabs(model_.lateral->initial[node]) <= limit))
          s << "Likely cause: numerics.divergence_limit = " << limit << " m is below the line's own lateral positions "
            << "(the stagger, curves and the mean wind's blow-off put this node at " << model_.lateral->initial[node]
            << " m at rest); the limit bounds positions from the track centre: raise it";
        else
          s << "Check the lateral stiffnesses (stagger.steady_arm_stiffness, messenger_support_stiffness) and the wind";
        break;
      }
      const int d = state_.diverged_dof;
      std::string where = wire_at(model_.wires, d, state_.line_offset);
      if (where.empty()) where = "DOF " + std::to_string(d);
      for (const Pantograph& p : model_.pantographs)
        if (!p.moving_force && d >= p.first_dof && d < p.first_dof + p.masses_count())
          where = "pantograph " + p.name + " mass " + std::to_string(d - p.first_dof);
        else if (!p.moving_force && d >= p.first_dof && d < p.first_dof + p.dof_count())
          where = "pantograph " + p.name + " head " + std::to_string(d - p.first_dof - p.masses_count());
      // The step's rejected value: the state kept the last good one, within the limit.
      s << "diverged at t = " << state_.time << " s: displacement of " << where << " reached "
        << state_.diverged_displacement << " m (limit " << model_.scene.numerics.divergence_limit
        << " m); the run was stopped at the last step within it. " << divergence_cause();
      break;
    }
  }
  return s.str();
}

// The likeliest cause of a divergence, from what the scene asks: a contact spring so soft that
// the strips sink into the wire beyond the limit, a limit within the line's own displacements,
// or the time step; dt is blamed only when it was near the stability estimate.
std::string Simulation::divergence_cause() const {
  std::ostringstream s;
  s.precision(4);
  const Scene& sc = model_.scene;
  const double limit = sc.numerics.divergence_limit;
  // The penalty contact spring: under the net uplift F a strip sinks F / k0 into the wire.
  double sink = 0.0, force = 0.0;
  for (std::size_t i = 0; i < model_.pantographs.size() && i < sc.pantographs.size(); ++i)
    if (!model_.pantographs[i].moving_force) {
      const PantographSpec& p = sc.pantographs[i];
      const double static_uplift = i < state_.uplift.size() ? state_.uplift[i] : p.static_uplift;
      const double f = static_uplift + p.net_uplift(state_.speed) - p.static_uplift;
      if (f / model_.contact_stiffness > sink) sink = f / model_.contact_stiffness, force = f;
    }
  // A sink of centimetres is no contact (50000 N/m under 120 N: 2.4 mm).
  if (sink > 0.5 * limit && sink > 0.01) {
    s << "Likely cause: contact.stiffness = " << model_.contact_stiffness << " N/m is so low that the strips sink about "
      << sink << " m into the wire under the uplift of " << force << " N (uplift / stiffness), beyond the divergence "
      << "limit; the contact spring is a penalty that keeps them on the wire: use 1e4 to 1e5 N/m (50000 by default)";
    return s.str();
  }
  const double moved = initial_.u.size() ? initial_.u.cwiseAbs().maxCoeff() : 0.0;
  if (limit < 10.0 * moved) {
    s << "Likely cause: numerics.divergence_limit = " << limit << " m is within the line's own displacements (its static "
      << "state already reaches " << moved << " m): the limit stopped the run, not an instability; raise it (5 m by "
      << "default)";
    return s.str();
  }
  // A limit lowered to within the pass's own motion (the contact wire rises by centimetres to
  // decimetres under the pantographs): the step that stopped the run went past it by less than the
  // limit itself, as a smooth motion does (a NaN or a jump beyond twice the limit is not that).
  const double reached = std::fabs(state_.diverged_displacement);
  if (limit < NumericsSpec{}.divergence_limit && std::isfinite(reached) && reached < 2.0 * limit) {
    s << "Likely cause: numerics.divergence_limit = " << limit << " m, below its default of "
      << NumericsSpec{}.divergence_limit << " m, is within reach of the line's own motion under the pass: the "
      << "displacement passed it by " << reached - limit << " m in one step; raise it if the pass may move that far";
    return s.str();
  }
  const double ratio = model_.dt / model_.dt_critical;
  if (ratio > kStepNearEstimate) {
    s << "Likely cause: dt (" << model_.dt << " s) is " << ratio << " of the stability estimate (" << model_.dt_critical
      << " s), closer than the estimate guarantees; " << (sc.numerics.dt ? "reduce numerics.dt" : "reduce numerics.safety_factor")
      << " (dt at 0.9 of the estimate by default)";
    return s.str();
  }
  s << "dt (" << model_.dt << " s) was " << ratio << " of the stability estimate (" << model_.dt_critical
    << " s), so the scene is outside what the estimate covers: check its masses, stiffnesses and dampers, or use "
       "numerics.integrator implicit";
  return s.str();
}

void Simulation::reset(bool keep_time) {
  const double t = state_.time;
  const std::int64_t n = state_.steps;
  const double target = state_.target_speed, accel = state_.max_acceleration;
  const std::vector<double> uplift = state_.uplift, external = state_.external_force;
  state_ = initial_;
  state_.uplift = uplift;
  state_.external_force = external;  // the rig's latest measurement stays in effect
  state_.target_speed = state_.speed = target;
  state_.max_acceleration = accel;
  if (uplift != initial_.uplift || external != initial_.external_force) {
    solve_initial_state(model_, state_);
    observe(model_, state_);
  }
  if (keep_time) {
    state_.time = t;
    state_.steps = n;
    // The implicit gust lead's own clock with it: it goes on from the initial state at that time
    // (from 0 the next step would step it over the whole time since).
    state_.lateral.lead_time = t;
  }
}

bool Simulation::set_target_speed(double v, std::string* error) {
  const TrainSpeedLimit limit = train_speed_limit(model_.scene);
  if (!limit.allows(v)) {
    if (error) *error = "train speed " + fmt_given(v) + " m/s rejected: allowed " + limit.text();
    return false;
  }
  state_.target_speed = v;
  return true;
}

bool Simulation::set_max_acceleration(double a, std::string* error) {
  // The ceiling is about 2 g: several times what any train does (service braking about 1 m/s^2,
  // emergency braking 1.5 to 3 m/s^2), so every real ramp fits, while a value in the tens or
  // hundreds (a unit slip, km/h per s) is refused rather than taken as a jump.
  if (std::string e = max_acceleration_error(a); !e.empty()) {
    if (error) *error = std::move(e);
    return false;
  }
  state_.max_acceleration = a;
  return true;
}

std::string Simulation::max_acceleration_error(double a) {
  if (std::isfinite(a) && a >= 0.0 && a <= kMaxAcceleration) return std::string();
  return "max acceleration " + fmt_given(a) + " m/s^2 rejected: allowed 0 (no limit) to " + fmt(kMaxAcceleration) + " m/s^2";
}

bool Simulation::set_uplift(int p, double f, std::string* error) {
  const int np = static_cast<int>(model_.pantographs.size());
  if (p >= np) {
    if (error) *error = "pantograph index " + std::to_string(p) + " rejected: the scene has " + std::to_string(np);
    return false;
  }
  if (!std::isfinite(f) || f < 0.0 || f > kMaxUplift) {
    if (error) *error = "uplift force " + fmt_given(f) + " N rejected: allowed 0 to " + fmt(kMaxUplift) + " N";
    return false;
  }
  if (p < 0) {
    for (double& u : state_.uplift) u = f;
  } else {
    state_.uplift[p] = f;
  }
  return true;
}

bool Simulation::set_external_force(int p, double f, std::string* error) {
  const int np = static_cast<int>(model_.pantographs.size());
  if (p < 0 || p >= np || !model_.pantographs[p].external) {
    if (error) *error = "pantograph index " + std::to_string(p) + " rejected: not an external (hardware-in-the-loop) pantograph";
    return false;
  }
  if (std::string e = external_force_error(f); !e.empty()) {
    if (error) *error = std::move(e);
    return false;
  }
  state_.external_force[p] = std::max(0.0, f);
  return true;
}

std::string Simulation::external_force_error(double f) {
  if (std::isfinite(f) && f >= kMinExternalForce && f <= kMaxExternalForce) return std::string();
  std::ostringstream s;
  s << "external contact force " << fmt_given(f) << " N rejected: allowed " << kMinExternalForce << " to " << kMaxExternalForce
    << " N (negative readings are taken as 0)";
  return s.str();
}

}  // namespace catenary_sim
