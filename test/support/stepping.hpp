// Stepping shared by the tests of the explicit step's variants: a model run from its static state,
// a simulation run to its end, and a trace's rms difference from a finer one.
#pragma once

#include <cmath>
#include <vector>

#include "catenary_sim/core/engine/initial_state.hpp"
#include "catenary_sim/core/simulation.hpp"

namespace test_stepping {

// Steps a built model from its static state for at most `max_steps`; returns the status it stopped
// with (kOk if it ran them all). With `trace`, DOF `dof`'s displacement after every step.
inline catenary_sim::StepStatus run_from_static(const catenary_sim::Model& m, long max_steps,
                                                std::vector<double>* trace = nullptr, int dof = -1) {
  catenary_sim::State s = catenary_sim::make_state(m);
  catenary_sim::solve_initial_state(m, s);
  for (long k = 0; k < max_steps; ++k) {
    const catenary_sim::StepStatus st = catenary_sim::step(m, s);
    if (st != catenary_sim::StepStatus::kOk) return st;
    if (trace) trace->push_back(s.u[dof]);
  }
  return catenary_sim::StepStatus::kOk;
}

// Steps a simulation until it stops (at most `max_steps`); returns the status it stopped with.
inline catenary_sim::StepStatus run_to_end(catenary_sim::Simulation& sim, long max_steps = 2000000) {
  catenary_sim::StepStatus st = catenary_sim::StepStatus::kOk;
  for (long k = 0; k < max_steps && st == catenary_sim::StepStatus::kOk; ++k) st = sim.step();
  return st;
}

// The rms difference of trace `u` from `ref`, taken with a step `stride` times shorter, at their
// common instants (u's k-th value against ref's ((k + 1) stride)-th).
inline double rms_against(const std::vector<double>& u, const std::vector<double>& ref, int stride) {
  double sum = 0.0;
  int n = 0;
  for (std::size_t k = 0; k < u.size() && (k + 1) * stride <= ref.size(); ++k, ++n) {
    const double d = u[k] - ref[(k + 1) * stride - 1];
    sum += d * d;
  }
  return n > 0 ? std::sqrt(sum / n) : NAN;
}

}  // namespace test_stepping
