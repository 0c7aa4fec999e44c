// The step: which integrator advances the vertical plane, and the lateral plane after it. Each
// path lives in its own file: explicit_step.cpp (eq. 19-21), centred_damping_step.cpp,
// implicit_step.cpp (Newmark), lateral_step.cpp (the 3-D line's lateral plane).
#include "catenary_sim/core/engine/step.hpp"

#include "catenary_sim/core/engine/lateral_step.hpp"
#include "catenary_sim/core/engine/state.hpp"
#include "engine/centred_damping_step.hpp"
#include "engine/explicit_step.hpp"
#include "engine/implicit_step.hpp"
#include "engine/lateral_wind.hpp"
#include "engine/lateral_workspace.hpp"
#include "engine/wire_lanes.hpp"

namespace catenary_sim {

StepStatus vertical_step(const Model& m, State& s) {
  if (s.status != StepStatus::kOk) return s.status;
  if (s.front + s.line_offset >= m.train_end) {
    s.status = StepStatus::kFinished;
    return s.status;
  }
  if (m.implicit) return implicit_step(m, s);
  if (m.scene.numerics.damping == DampingStep::kCentred) return centred_damping_step(m, s);
  return explicit_step(m, s);
}

namespace {

// The vertical step, then the lateral one. Where both planes sweep every node of the same packs
// (no window, one lateral substep, both fused), the vertical step runs the lateral step's band
// sweep with its own, both planes in twice a pack's lanes (sweep_pack_pair: the band and its
// factors are the same both ways, loaded once, and each band operation does both planes). The
// lateral sweep reads nothing the vertical step changes (the lateral state, the wind of the
// step's start, the shared band and factors), and each lane does its own plane's operations, so
// the results are those of the vertical step then lateral_step, to the bit. (Hinged arms'
// registrations, which the lateral step moves to the new u, are swept where the last step put
// them in either case; the point forces add the move: lateral_step.cpp.) With centred damping the
// solve of each lone wire (a rigid rail's profile) takes its lateral plane in a second lane, the
// lateral forces set before the vertical step (take_centred_solve_along): they read only the
// lateral state and the wind of the step's start, so the results are again those of the two
// steps one after the other, to the bit.
StepStatus step_both_planes(const Model& m, State& s) {
  const LateralModel& lat = *m.lateral;
  LateralState& ls = s.lateral;
  // Both planes sweep every node of the same packs: no window, one lateral step a vertical one,
  // both fused, and the step will be taken (not the pass's end).
  const bool taken = s.status == StepStatus::kOk && s.front + s.line_offset < m.train_end;
  if (m.scene.numerics.damping == DampingStep::kCentred) {
    // With centred damping the lateral forces go into the solve: set before the vertical step.
    ls.work->join = taken && take_centred_solve_along(m, s);
  } else {
    ls.work->join = !lat.planes.empty() && lat.substeps == 1 && !m.scene.numerics.windowed() && taken &&
                    !ls.dropper_stretch.empty();
    if (ls.work->join) refresh_wind_before_joint_step(m, s);
  }
  const StepStatus st = vertical_step(m, s);
  ls.work->join = false;
  if (st != StepStatus::kOk) {
    ls.work->joined = false;
    return st;
  }
  return lateral_step(m, s);
}

}  // namespace

// GCC's resolver takes the clone (engine/wire_lanes.cpp) of the highest priority the CPU supports:
// x86-64-v4 (AVX-512 with VL, BW, DQ, CD) over x86-64-v3 (AVX2) over the baseline; this asks the
// same question. The benchmark prints it beside the figures; gdb on sweep_pack shows the clone
// taken (BENCHMARKS.md).
const char* sweep_pack_isa() {
#if defined(__x86_64__) && defined(__GNUC__) && !defined(__clang__)
  __builtin_cpu_init();
  if (__builtin_cpu_supports("x86-64-v4")) return "x86-64-v4";
  if (__builtin_cpu_supports("x86-64-v3")) return "x86-64-v3";
#endif
  return "default";
}

StepStatus step(const Model& m, State& s) {
  // A 3-D line steps both planes (make_state gives its state the lateral one); a state whose
  // lateral plane was cleared by hand, the vertical plane alone.
  const bool lateral = m.lateral && s.lateral.y.size() == m.lateral->n;
  return lateral ? step_both_planes(m, s) : vertical_step(m, s);
}

}  // namespace catenary_sim
