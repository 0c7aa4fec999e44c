// The constant model built from a scene: DOF layout, lumped masses, banded stiffness of the
// wires, supports, droppers, pantographs and collectors, the design (static) geometry and the
// stability limit. Like MuJoCo's mjModel it never changes during a pass; everything that
// changes lives in State (state.hpp).
#pragma once

#include <Eigen/Core>
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "catenary_sim/core/scene/scene.hpp"

namespace catenary_sim {

struct LateralModel;    // lateral.hpp: the 3-D line's lateral plane
struct ImplicitMatrix;  // model/newmark_matrix.hpp (private): the implicit integrator's factors
struct WirePacks;       // model/wire_packs.hpp (private): the wires' lane layout for the fused step

// One tensioned wire of a tension section, meshed with pre-stressed Euler-Bernoulli (Hermite)
// beam elements (eq. 3). Its stiffness is stored as a block-tridiagonal band of 2x2 blocks
// (w, theta per node): that is exactly the bandwidth of a beam, so a product costs O(nodes).
struct Wire {
  std::string name;
  int section = 0;               // tension section it belongs to
  bool is_contact_wire = false;
  bool is_clamped_wire = false;  // a short wire between two clamps: a stitch wire (StitchWireSpec), no supports,
                                 // clamped to the messenger; or a bridle (BridleSpec, is_bridle), held at its
                                 // middle, clamped to the contact wire
  bool is_bridle = false;        // a trolley wire's bridle; support_nodes: its middle, where the support holds it
  bool is_auxiliary_messenger = false;  // a compound line's (AuxiliaryMessengerSpec): held at its anchors only
  WireSpec spec;
  std::vector<double> x;         // m, node stations along the line
  std::vector<double> height;    // m, design height of each node (static shape, no pantograph)
  std::vector<double> slope;     // rad, design rotation of each node
  int w_dof = 0;                 // global index of node 0's vertical displacement
  int theta_dof = -1;            // global index of node 0's rotation; -1: rotations condensed
  // K band: diagonal blocks per node and the coupling block of element e (node e -> e+1).
  std::vector<double> d_ww, d_wt, d_tt;        // size nodes
  std::vector<double> e_ww, e_wt, e_tw, e_tt;  // size nodes-1; e_wt = K(w_e, theta_e+1), e_tw = K(theta_e, w_e+1)
  // Condensed rotations: LDL^T factors of the tridiagonal K_theta_theta, reused every step.
  std::vector<double> tt_inv_pivot, tt_lower;
  // Condensed rotations swept from both ends (twisted: a lone wire of the fused step), the whole
  // wire's (twisted_meeting >= 0; twist_condensation) or a moving window's part (WireWindow::meet):
  // the LDL^T of the wire mirrored (its rotations negated) from its last node to the meeting node,
  // station k being node nodes() - 1 - k, and 1 / gamma of the meeting row, where the two sides meet.
  bool twisted = false;
  int twisted_meeting = -1;
  std::vector<double> twisted_lower, twisted_inv_pivot;
  double twisted_inv_gamma = 0.0;
  std::vector<int> support_nodes;  // node index of each support of its section, in order

  int nodes() const { return static_cast<int>(x.size()); }
  // Index of the element containing station xs (clamped to the wire), by bisection.
  int element_at(double xs) const;
};

// Tension-only dropper between a contact-wire node and a messenger node. On a compound line the
// droppers hold the auxiliary messenger (contact_dof is its node) and the hangers the contact wire
// from the auxiliary (messenger_dof is the auxiliary's node).
struct Dropper {
  int contact_dof = 0, messenger_dof = 0;
  bool hanger = false;          // a compound line's hanger (Section::auxiliary to the contact wire)
  int section = 0, span = 0;    // tension section, span index within it
  double x = 0.0;               // m
  double stiffness = 0.0;       // N/m, EA / unstretched length
  double static_tension = 0.0;  // N, in the design state
  double length = 0.0;          // m, design (stretched) length
  double unstretched_length = 0.0;
};

// A clamp joining two wires' nodes: a stitch wire's end hung from the messenger, or a trolley wire
// hung from a bridle's end (upper_dof then the bridle's end, lower_dof the contact wire's node).
// A bilateral spring, stiff beside the line's own compliance (kWireClampStiffness), carrying the
// short wire's end reaction in the design state.
struct WireClamp {
  int upper_dof = 0, lower_dof = 0;  // the upper wire's node, the lower wire's node
  double stiffness = 0.0;     // N/m
  double static_force = 0.0;  // N: pulls the lower node up and the upper one down at u = 0
  double x = 0.0;             // m
};
// 5e-6 m/N, in series with a stitch wire's ~1e-3 m/N (L / (4 T) for 14-18 m at 3-3.5 kN): rigid to
// the line (the reference stitched line's elasticity is within 0.03 % of 1e8 N/m clamps'). Its
// frequency on the clamp's node masses stays below the wires' highest, so the line keeps its dt
// (1e6 N/m would set a smaller one through the half-step's beta K).
constexpr double kWireClampStiffness = 2e5;

// An elastic support: steady arm on the contact wire (eq. 4) or messenger support spring.
// m, a hinged arm's end's travel out, away from its hinge, with the end raised by u: a (cos(theta)
// - cos(theta0)), sin(theta) = sin(theta0) - u / a, to first order tan(theta0) u; a the length,
// sin0 and cos0 of theta0, its inclination below the hinge. Written as
// u (sin(theta0) + sin(theta)) / (cos(theta) + cos(theta0)) (the difference of the cosines without
// its cancellation): exactly 0 at u = 0.
inline double hinged_arm_travel(double a, double sin0, double cos0, double u) {
  const double s = std::clamp(sin0 - u / a, -1.0, 1.0);
  return ((sin0 - s) * a) * ((sin0 + s) / (std::sqrt(1.0 - s * s) + cos0));
}

struct SupportSpring {
  int dof = 0;
  double stiffness = 0.0;     // N/m
  double static_force = 0.0;  // N, f0 of eq. 4 (balanced in the constant load vector)
  double x = 0.0;
  int span_index = 0;         // index of the support along the line (Model::support_x); span i starts there
  bool steady_arm = false;
  int section_support = 0;    // index of the support within its tension section
  // A hinged steady arm (HingedArmSpec): its length and its inclination below the hinge at the
  // assembly (rad); 0 length for a spring given by its stiffness.
  double arm_length = 0.0, arm_inclination = 0.0;
  // N/m: the wire's lateral stiffness at the arm's end, which its sideways travel works against.
  double arm_wire_lateral_stiffness = 0.0;
  double arm_pull_off = 0.0;  // N, F_h: given, or a 3-D line's from its lateral statics
  double arm_tip_mass = 0.0;  // kg, its inertia on the wire's node (HingedArmSpec::tip_mass / cos^2)
  // The side the wire pulls the arm's end toward (+1: + y, to the left; -1), 0 on a 2-D line.
  double arm_pull_side = 0.0;
  // N/m: on a 3-D line, the share k_w tan^2 theta0 of the arm's k_A that the lateral plane gives
  // the vertical one through its registration (LateralRegistration) and `stiffness` leaves out;
  // 0 otherwise. Static solves, which have no lateral plane, take static_stiffness().
  double arm_lateral_share = 0.0;
  double static_stiffness() const { return stiffness + arm_lateral_share; }
  bool hinged_arm() const { return arm_length > 0.0; }
  // The arm's inclination with its tip raised by `uplift` (m): sin(theta) = sin(theta0) - u / a.
  double arm_inclination_at(double uplift) const {
    return std::asin(std::clamp(std::sin(arm_inclination) - uplift / arm_length, -1.0, 1.0));
  }
  // m, how far the arm's end has moved out, away from its hinge, with its tip raised by `uplift`
  // (on a 3-D line toward arm_pull_side): hinged_arm_travel below.
  double arm_end_travel(double uplift) const {
    return hinged_arm_travel(arm_length, std::sin(arm_inclination), std::cos(arm_inclination), uplift);
  }
};

// A tension section as built: its wires and the raised contact-wire supports of its transition
// spans (d of eq. 8, 0 where the span is a current span).
struct Section {
  double start = 0.0, end = 0.0;       // m
  double rise_first = 0.0, rise_last = 0.0;  // m, at its first and last support
  std::vector<int> wires;              // indices into Model::wires: contact wire(s), messenger
  int messenger = -1;                  // index into Model::wires, -1 without a messenger
  std::vector<int> clamped_wires;      // its stitch wires or bridles (Wire::is_clamped_wire), one per intermediate support
  int auxiliary = -1;                  // index into Model::wires of a compound line's auxiliary messenger
};

struct Collector {
  int pantograph = 0;
  double offset = 0.0;  // m along the track from the pantograph reference point
  int head = -1;        // index into Pantograph::heads; -1: on the chain's first mass
  int dof = -1;         // the mass it presses (eq. 22: k0 (y_dof - y_wire)); -1 for a moving force
  double half_working_width = 0.0;  // m, half the strip's working width (3-D line: beyond it, a dewirement)
};

// A head on its own suspension to the top frame mass (HeadSpec).
struct Head {
  int dof = 0;
  double mass = 0.0, stiffness = 0.0, damping = 0.0;
  double aero_coefficient = 0.0;  // N s^2/m^2, for the pantograph's knee direction
  double preload = 0.0;           // N: compression of the suspension at displacement 0 (its static share)
  double reference_height = 0.0;  // m: absolute height at displacement 0
  std::vector<int> collectors;    // indices into Model::collectors
};

struct Pantograph {
  std::string name;
  double position = 0.0;  // m behind the train front
  bool moving_force = false;  // no masses: the force is given (uplift, or the rig's for external)
  bool external = false;      // hardware-in-the-loop: the force comes from a real pantograph
  int first_dof = -1;     // head DOF; masses follow down the chain
  std::vector<double> masses, stiffness, damping;
  double static_uplift = 0.0, aero_coefficient = 0.0;  // aero: the frame's, for the knee direction
  std::vector<int> collectors;  // indices into Model::collectors
  std::vector<Head> heads;      // empty: the first chain mass is the head (DOFs after the chain's)
  double reference_height = 0.0;  // m: absolute head height at displacement 0
  std::vector<double> spring_preload;  // N: compression of each spring at displacement 0
  int masses_count() const { return static_cast<int>(masses.size()); }
  int dof_count() const { return masses_count() + static_cast<int>(heads.size()); }
  // Absolute height at displacement 0 of the mass collector `ci` presses.
  double contact_reference(const Collector& c) const { return c.head < 0 ? reference_height : heads[c.head].reference_height; }
};

struct Model {
  Scene scene;
  std::vector<Section> sections;
  // per section: contact wire(s), the messenger if any, its stitch wires or auxiliary messenger
  std::vector<Wire> wires;
  std::vector<int> contact_wires;     // indices into wires that collectors touch
  std::vector<Dropper> droppers;
  std::vector<SupportSpring> springs;
  std::vector<WireClamp> clamps;      // stitch wires' ends on the messenger
  std::vector<Pantograph> pantographs;
  std::vector<Collector> collectors;
  std::vector<double> support_x;      // m, station of every support along the line (all sections)

  int n_dof = 0;
  int n_catenary_dof = 0;       // catenary DOFs come first, pantograph DOFs after
  Eigen::VectorXd mass;         // lumped, kg (or kg m^2 for lumped rotations); 0 on fixed DOFs
  Eigen::VectorXd inv_mass;     // 0 on fixed (rigidly supported) DOFs, which therefore never move
  Eigen::VectorXd load;         // constant load: gravity, support preloads and -K y_design (N)
  double alpha = 0.0, beta = 0.0;  // Rayleigh, eq. 5 (catenary only)
  double contact_stiffness = 0.0, rub_length = 0.0;
  int max_contact_nodes = 2;    // nodes a distributed contact can touch (sizes the workspace)

  double omega_max = 0.0;       // rad/s, highest eigenfrequency of the assembled system
  double dt_critical = 0.0;     // s, explicit stability limit incl. the damping reduction (inf: implicit)
  double dt = 0.0;              // s, the step in use
  // numerics.supports implicit: the explicit step takes support springs at its middle, and
  // numerics.droppers implicit: links (droppers and clamps), each where its nodes allow
  // (explicit_step.cpp). Then 1 for each support spring (springs), dropper (droppers) and clamp
  // (clamps) it takes there, 0 for those it takes at q_n; otherwise the lists are empty.
  bool takes_supports_at_middle = false, takes_links_at_middle = false;
  std::vector<std::uint8_t> support_at_middle, dropper_at_middle, clamp_at_middle;
  std::shared_ptr<const ImplicitMatrix> implicit;  // set when the integrator is implicit
  // Explicit with condensed rotations: the wires packed side by side for the fused step, their
  // copies in SIMD lanes and where the sweep leaves each DOF's results (their layout is the
  // engine's business: model/wire_packs.hpp); null: the generic step.
  std::shared_ptr<const WirePacks> wire_packs;
  double train_start = 0.0, train_end = 0.0;  // m, front of the train
  double line_length = 0.0;
  double wave_speed = 0.0;      // m/s, sqrt(T/rhoA) of the contact wire (the slowest one)
  // The moving window holds whole tension sections (numerics.window auto on a line with a rigid
  // rail or bridles, whose waves run the whole section): those a pantograph is in.
  bool window_holds_sections = false;
  // Endless line (Scene::endless): the wires are a block of equal spans starting at station 0;
  // whenever the rearmost collector runs a span past endless_home, step() moves the state back a
  // span and adds it to State::line_offset (a station along the line = block station + offset).
  // train_start is then in block stations, train_end along the line.
  bool endless = false;
  double endless_span = 0.0, endless_home = 0.0;  // m
  double initial_line_offset = 0.0;               // m, a whole number of spans
  double rear_collector_offset = 0.0;             // m, rearmost collector station - train front
  std::vector<int> span_nodes;                    // per wire: nodes per span (endless)
  // Spans the block moves by: 1, or a 3-D line's stagger pattern (its supports repeat only after
  // a whole pattern), so that endless_home..endless_home + shift spans holds the rearmost collector.
  int endless_shift_spans = 1;
  double longest_span = 0.0;    // m
  std::vector<int> dropper_order, spring_order;       // indices in line order (stable)
  std::vector<double> dropper_order_x, spring_order_x;  // m, their stations
  std::vector<int> clamp_order;                       // the stitch wires' clamps in line order
  std::vector<double> clamp_order_x;                  // m
  std::vector<std::string> warnings;  // what the scene asks that is outside design practice
  // The wires' lateral planes (3-D line); null when the scene has no stagger, curve, wind or sway.
  std::shared_ptr<const LateralModel> lateral;
};

// The index in `wires` of the wire one of whose nodes is the DOF `dof` of their plane (Model::wires
// and the vertical DOFs, or LateralModel::wires and the lateral ones, which keep the same order);
// -1 for a pantograph's DOF. The wires are numbered in line order of their DOFs (w_dof
// ascending), so the search halves: a dropper's wires are found without walking a long line's
// stitch wires.
inline int wire_holding(const std::vector<Wire>& wires, int dof) {
  const auto after = std::upper_bound(wires.begin(), wires.end(), dof, [](int d, const Wire& w) { return d < w.w_dof; });
  if (after == wires.begin()) return -1;
  const Wire& w = *(after - 1);
  return dof < w.w_dof + w.nodes() ? static_cast<int>(after - 1 - wires.begin()) : -1;
}
inline int wire_holding(const Model& m, int dof) { return wire_holding(m.wires, dof); }

// The inertia (kg) a spring of stiffness k taken at the explicit step's middle adds to its nodes'
// update: k (dt^2/4 + beta dt/2), the trapezoidal rule's share of its stiffness and the centred
// share of its damping beta k (explicit_step.cpp).
inline double middle_inertia(const Model& m, double stiffness) {
  return stiffness * (0.25 * m.dt * m.dt + 0.5 * m.beta * m.dt);
}

}  // namespace catenary_sim

// The functions on the model, each declared beside its definition's file.
#include "catenary_sim/core/model/build_model.hpp"
#include "catenary_sim/core/model/contact_geometry.hpp"
#include "catenary_sim/core/model/model_memory.hpp"
#include "catenary_sim/core/model/window_lengths.hpp"
#include "catenary_sim/core/model/wire_packs.hpp"
#include "catenary_sim/core/model/wire_band.hpp"
