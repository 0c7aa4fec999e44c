// The wires packed for the fused explicit step (Model::wire_packs): the lane layout the engine's
// sweep kernels (engine/wire_lanes.hpp) and the centred damping step read. Private to the core:
// outside it a model shows only how many packs it has and their lanes (the public wire_packs.hpp).
#pragma once

#include <cstddef>
#include <memory>
#include <vector>

#include "catenary_sim/core/model/model.hpp"

namespace catenary_sim {

// Wires packed for the fused explicit step (condensed rotations): one wire, or two on the same node
// stations (a section's contact wire and messenger) side by side, so that their independent
// recurrences (the condensation's tridiagonal sweeps) run in the two lanes of one vector register.
// Node i of lane k is entry i * lanes + k. Copies of the wires' band, factors, load and masses.
struct WireLanes {
  int lanes = 1;
  int wire[2] = {-1, -1};  // indices into Model::wires
  int nodes = 0;
  std::size_t offset = 0;  // of this pack, in node-lanes: its records start at StepWorkspace::sweep[4 * offset]
  // One record per node: kCoefficients values, each for every lane ([node][value][lane]); the
  // element values (e_*) belong to the element from the node to the next.
  enum { kDww, kDwt, kEww, kEwt, kEtw, kLoad, kDampingMass, kInvMass, kCoefficients };  // kDampingMass: alpha m (eq. 5)
  std::vector<double> coef;
  std::vector<double> factors;  // LDL^T of K_theta_theta: [node][lower, inv_pivot][lane]
  // Centred damping: the factors of the step's block-tridiagonal solve for the lanes' wires in
  // the twisted order (src/core/model/centred_factors.hpp): [pair][value][2 lanes], and the meeting and
  // extra nodes' [value][lane]. Empty with the half-step damping.
  std::vector<double> centred_twin, centred_single;
  // A lone wire swept from both ends at once (Wire::twisted), so that it fills both lanes: the
  // condensation's factorisation runs up from node 0 in lane 0 and down from the last node in
  // lane 1 (the wire mirrored: its rotations negated), the two meeting at the middle node, which
  // takes both sides' eliminations (a twisted factorisation). Stepped whole (the wire's
  // Wire::twisted_meeting >= 0, an odd count): per station k, node k in lane 0 and node nodes - 1 - k
  // in lane 1, up to the meeting, lay_out_twisted's coefficients and factors; its records
  // [station][value][2 lanes], the meeting node's in lane 0. In a window the window's
  // (WireWindow::meet), its records in node order.
  std::vector<double> twisted_coef, twisted_factors;
};

// The fused step's record per node and lane (StepWorkspace::sweep, kSweepRecord values per node,
// each for every lane; the engine's sweep writes them, WirePacks::dof_sweep_force points into
// them): the rotation of the forward sweep, and the band force.
enum { kRecTheta, kRecForce, kSweepRecord };
// The centred-damping step's record per node and lane in the same scratch (c = S y, then u and v:
// engine/centred_damping.cpp): the scratch holds this many values per node-lane, room for either.
constexpr int kCentredRecord = 4;

struct WirePacks {
  std::vector<WireLanes> packs;
  std::vector<int> wire_pack, wire_lane;  // per wire (Model::wires): its pack and lane
  std::vector<int> centred_fixed_dofs;    // the wires' fixed vertical DOFs (centred damping step)
  double centred_v_ratio = 0.0;           // (2 / dt) / D_i per mass (centred damping step)
  // Per catenary DOF: where the sweep leaves its band force in StepWorkspace::sweep; and where the
  // vertical step's sweep with the lateral plane's taken along (sweep_pack_pair) leaves it, in the
  // joint records (2 kSweepRecord values per node-lane: the pack's at twice its offset, per node
  // [value][the vertical plane's lanes, then the lateral plane's]).
  std::vector<int> dof_sweep_force, dof_joint_force;
  std::size_t sweep_size = 0;  // node-lanes of all packs (StepWorkspace::sweep holds kCentredRecord values for each)
};

struct TwistedRange;
// The fused kernel's coefficients and factors of a range swept from both ends (TwistedLone in
// engine/wire_lanes.cpp): per station up to the meeting, [station][value][2 lanes] as `coef`, and
// [station][lower, inv_pivot][2 lanes].
void lay_out_twisted(const Model& m, const TwistedRange& r, double* coef, double* factors);

// Packs the wires for the fused step when the model is explicit with condensed rotations; null
// otherwise (the generic step). A lone wire that fills both lanes from its two ends has its
// condensation twisted (twist_condensation), the generic step's too.
std::shared_ptr<WirePacks> build_wire_packs(Model& model);

// The model's packs; empty without (the generic step).
inline const std::vector<WireLanes>& packs_of(const Model& model) {
  static const std::vector<WireLanes> none;
  return model.wire_packs ? model.wire_packs->packs : none;
}
// Node-lanes of the model's packs (0 without packs): sizes the sweep's records.
inline std::size_t sweep_size(const Model& model) { return model.wire_packs ? model.wire_packs->sweep_size : 0; }

}  // namespace catenary_sim
