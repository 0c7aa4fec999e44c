// The scene: everything a pass needs, as plain data in SI units, loaded from YAML and validated.
// A scene holds only what it needs: the messenger, droppers, steady arms and pantographs are
// optional, so a scene may be a single tensioned wire between two supports under a moving force.
#pragma once

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

namespace YAML {
class Node;
}

namespace catenary_sim {

// Thrown for any invalid scene input; the message names the field, the value and what is allowed.
class SceneError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// A tensioned wire modelled as a pre-stressed Euler-Bernoulli beam (paper eq. 3).
struct WireSpec {
  double linear_mass = 0.0;        // rhoA, kg/m
  double bending_stiffness = 0.0;  // EI, N m^2
  double tension = 0.0;            // T, N
};

struct ContactWireSpec : WireSpec {
  double presag = 0.0;  // m, sag prescribed at mid-span (parabolic over the span), set by the droppers
};

struct DropperSpec {
  std::vector<std::vector<double>> positions;  // per span of the section, m from the span's first support
  // Transition spans (overlaps): m from the support on the section's side of the span, mirrored
  // for a section's first span (the paper's 3.83 m and 5.83 m); empty = `positions`.
  std::vector<double> transition_positions;
  bool per_span = false;                       // positions were given per span (positions_per_span)
  double axial_stiffness = 0.0;                // EA, N
  double linear_mass = 0.0;                    // kg/m
  // kg, clamp on the wire it holds: the contact wire (a compound line's droppers: the auxiliary
  // messenger; its hangers: the contact wire)
  double clamp_mass_contact = 0.0;
  // kg, clamp on the wire it hangs from: the messenger (a compound line's hangers: the auxiliary)
  double clamp_mass_messenger = 0.0;
};

// A compound catenary's auxiliary messenger (Japanese high-speed lines): a tensioned wire between
// the messenger and the contact wire, anchored with its section and free through the intermediate
// supports. The droppers hang it from the messenger and the hangers (DropperSpec, more closely
// spaced) hang the contact wire from it, so that the contact wire's stiffness varies less along
// the span. Design rule: at each dropper it runs `height` above the contact wire's design shape;
// between droppers it sags under the hangers, which sets their lengths.
struct AuxiliaryMessengerSpec : WireSpec {
  double height = 0.0;  // m above the contact wire at each dropper
};

// A stitch wire (Y-wire): a short tensioned wire clamped to the messenger at length/2 on both sides
// of every intermediate support of its section, passing free under the messenger's support. The
// droppers strictly between its clamps hang from it instead of from the messenger, so the contact
// wire at the support is held by a soft string (elasticity ~ L/(4 T) at its middle) rather than
// by the messenger's support: the line is about as elastic at the supports as in mid-span.
struct StitchWireSpec {
  double length = 0.0;             // m between its two clamps on the messenger
  double tension = 0.0;            // N
  double linear_mass = 0.0;        // kg/m
  double bending_stiffness = 0.0;  // EI, N m^2
  double clamp_mass = 0.0;         // kg, each clamp on the messenger (lumped on the messenger node)
  // The section's intermediate supports that carry one (1: the support after its first span), in
  // increasing order; empty: every one. A support left out is held as on a simple line (e.g. the
  // last before a tunnel portal, to stiffen the line where a rigid rail takes over).
  std::vector<int> at_supports;
  // Each carrying support's own length, in the order of the supports that carry one (at_supports,
  // or every intermediate support); empty: `length` at every one (a shorter stitch wire where a
  // span shortens, at a portal or an overlap).
  std::vector<double> lengths;
  bool at(int support) const {
    return at_supports.empty() || std::find(at_supports.begin(), at_supports.end(), support) != at_supports.end();
  }
  // The entry of `lengths` for `support` (one that carries one): its place among the carrying supports.
  std::size_t length_index(int support) const {
    return at_supports.empty()
               ? static_cast<std::size_t>(support - 1)
               : static_cast<std::size_t>(std::find(at_supports.begin(), at_supports.end(), support) - at_supports.begin());
  }
  // The length of the stitch wire at `support` (one that carries one).
  double length_at(int support) const {
    const std::size_t k = length_index(support);
    return k < lengths.size() ? lengths[k] : length;
  }
};

// A trolley wire's elastic suspension (docs/trolley_wire.md): at each intermediate support a short
// wire, the bridle, hung at its middle from the support (`steady_arms`, or rigidly without) and
// clamped to the contact wire at its two ends, so that the support holds the contact wire through
// the bridle's two arms instead of at one point. No messenger: on a catenary a stitch wire does this.
struct BridleSpec {
  double length = 0.0;             // m between its two clamps on the contact wire
  double tension = 0.0;            // N
  double linear_mass = 0.0;        // kg/m
  double bending_stiffness = 0.0;  // EI, N m^2
  double clamp_mass = 0.0;         // kg, each clamp on the contact wire (lumped on the bridle's end)
};

// A steady (registration) arm as built: a bar hinged at the registration tube, its tip clamped to
// the contact wire, which pulls it along its axis with the horizontal pull-off of the stagger and
// the curve. The paper's eq. 4 takes k_A from "the linearization of the statics equations"; for
// this arm that is k_A = F_h / (a cos^3 theta0) + k_w tan^2 theta0, theta0 its inclination below
// the hinge at the assembly and k_w the wire's lateral stiffness it drags (model/design_statics.cpp).
struct HingedArmSpec {
  double length = 0.0;       // m, a: hinge to clamp
  double linear_mass = 0.0;  // kg/m
  double clamp_mass = 0.0;   // kg, at the tip
  // N, F_h: the wire's horizontal pull (4 T s / L on a straight zigzag); a 3-D line's comes from
  // its stagger and curves (the lateral statics) and is not given.
  std::optional<double> pull_off;
  // Its moment of inertia about the hinge as a mass at the tip: m a^2 / 3 / a^2, plus the clamp.
  double tip_mass() const { return linear_mass * length / 3.0 + clamp_mass; }
};

// An elastic support (steady arm, eq. 4, or messenger support); absent = rigid.
struct SupportSpec {
  double stiffness = 0.0;  // N/m (a hinged arm's: set by the design statics)
  double mass = 0.0;       // kg, lumped on the wire node (a hinged arm's: its tip mass, the design
                           // statics add its weightless sideways share)
  std::optional<HingedArmSpec> hinged_arm;  // steady arms only
};

struct CollectorSpec {
  double offset = 0.0;  // m along the track from the pantograph's reference point (+ = ahead);
                        // on a head: from the head's centre
  // m across the track that the contact point may use on a 3-D line (leaving it is a
  // dewirement); unset: pantograph_head.working_width.
  std::optional<double> working_width;
};

// A pantograph head: a mass on its own suspension (spring and damper) to the top frame mass,
// carrying one or more collector strips (modern pantographs: two heads, or two strips on
// independent suspensions; the paper's Section VI "two head masses").
struct HeadSpec {
  double mass = 0.0;        // kg
  double stiffness = 0.0;   // N/m, suspension to the top frame mass (> 0)
  double damping = 0.0;     // N s/m
  double offset = 0.0;      // m along the track from the pantograph's reference point, head centre
  double length = 0.5;      // m along the track: the strips sit within +-length/2 of the centre
  double aero_coefficient = 0.0;                   // N s^2/m^2 on this head, knee leading
  std::optional<double> aero_coefficient_trailing;  // knee trailing; empty: aero_coefficient
  std::vector<CollectorSpec> collectors;           // offsets from the head's centre
};

// Target mean contact force Fm(v) = a v^2 + b. EN 50367 writes it with v in km/h (e.g.
// 0.00097 v^2 + 70 N on AC lines), so the scene says which unit its a is for.
struct TargetMeanForce {
  double a = 0.0;              // N per (speed unit)^2
  double b = 0.0;              // N
  bool speed_kmh = false;      // a is for v in km/h (else m/s)
  std::optional<double> tolerance;  // N: the mean is within the target when |mean - Fm(v)| <= tolerance
  double at(double speed_mps) const {
    const double v = speed_kmh ? 3.6 * speed_mps : speed_mps;
    return a * v * v + b;
  }
};

struct PantographSpec {
  std::string name;
  double position = 0.0;  // m behind the train's front
  bool moving_force = false;  // true: a plain moving force, no masses
  bool external = false;      // true: hardware in the loop, the force is measured on a real pantograph
                              // (a moving force set by Simulation::set_external_force)
  // Lumped-mass chain, head first (paper Fig. 3 / eq. 9): masses[i] is joined to masses[i+1]
  // (the last to the roof) by stiffness[i] and damping[i]. With `heads` the chain is the frame,
  // its top mass first, and the heads sit on it.
  std::vector<double> masses;     // kg
  std::vector<double> stiffness;  // N/m
  std::vector<double> damping;    // N s/m
  double static_uplift = 0.0;     // N, static contact force at the working height
  double aero_coefficient = 0.0;  // N s^2/m^2, adds aero_coefficient * v^2 to the uplift (on the frame)
  std::optional<double> aero_coefficient_trailing;  // knee trailing; empty: aero_coefficient
  bool knee_trailing = false;     // direction of travel: the frame's knee leading (default) or trailing
  std::vector<CollectorSpec> collectors;  // without heads: on the chain's first mass
  std::vector<HeadSpec> heads;            // empty: the chain's first mass is the head
  // Target mean contact force Fm(v) = a v^2 + b (the standards' permissible mean force curve):
  // the statistics report the mean against it. Absent: not reported.
  std::optional<TargetMeanForce> target_mean_force;
  double frame_aero() const { return knee_trailing && aero_coefficient_trailing ? *aero_coefficient_trailing : aero_coefficient; }
  static double head_aero(const HeadSpec& h, bool trailing) {
    return trailing && h.aero_coefficient_trailing ? *h.aero_coefficient_trailing : h.aero_coefficient;
  }
  // Net uplift at speed v (m/s): static, frame and heads' aerodynamic terms.
  double net_uplift(double v) const {
    double a = frame_aero();
    for (const HeadSpec& h : heads) a += head_aero(h, knee_trailing);
    return static_uplift + a * v * v;
  }
};

struct ContactSpec {
  double stiffness = 50000.0;  // k0, N/m: collector spring of eq. 9, zeroed when contact is lost (eq. 25)
  double rub_length = 0.0;     // l, m: length of the cosine distribution (eq. 13); 0 = point contact
};

// One tension section: its spans, wires, droppers and supports, anchored at both ends. Consecutive
// sections overlap over `OverlapSpec::spans` transition spans (paper Figs. 1-2): in a section's
// transition span the contact wire rises from its last dropper to a support raised by d (eq. 8).
struct SectionSpec {
  std::vector<double> spans;   // m
  double start = 0.0;          // m, station of its first support (derived from the overlaps)
  int contact_wire_count = 1;  // 2: twin contact wire (DC lines), both hanging from the same droppers
  ContactWireSpec contact_wire;
  std::optional<WireSpec> messenger;
  std::optional<DropperSpec> droppers;
  std::optional<SupportSpec> steady_arms;
  std::optional<SupportSpec> messenger_supports;
  std::optional<StitchWireSpec> stitch_wire;  // at every intermediate support of the section
  std::optional<BridleSpec> bridle;           // a trolley wire's, at every intermediate support
  // Compound catenary: the auxiliary messenger and the hangers from it to the contact wire (the
  // droppers then hang the auxiliary from the messenger).
  std::optional<AuxiliaryMessengerSpec> auxiliary_messenger;
  std::optional<DropperSpec> hangers;
  // Rigid overhead conductor rail (docs/rigid_conductor_rail.md): the contact wire is the profile
  // with its clamped wire, a beam with no tension (contact_wire.tension 0), held at each
  // intermediate support by `steady_arms` (the supports' spring and mass); no messenger, droppers
  // or presag. Read from the section's `conductor_rail` fields.
  bool rigid = false;
  // The profile's bending stiffness across the track (conductor_rail.lateral_bending_stiffness),
  // N m^2: the lateral plane's EI on a 3-D line; empty: its vertical one (contact_wire's).
  std::optional<double> rail_lateral_bending_stiffness;
  // A flexible transition piece at each end of the rail section where a catenary section joins
  // it: over `length` from the profile's end its EI rises linearly from `end_bending_stiffness`
  // to the profile's (both planes in proportion), so that the pantograph meets a gradual, not a
  // sudden, change of stiffness.
  struct TransitionPiece {
    double length = 0.0;                 // m
    double end_bending_stiffness = 0.0;  // N m^2, at the profile's end
  };
  std::optional<TransitionPiece> rail_transition_piece;
  bool first_span_transition = false;  // default: true where a previous section overlaps it
  bool last_span_transition = false;   // default: true where a next section overlaps it
  // The keys the section's own entry in `sections` gives; a part it does not give is the top
  // level's, and is named there (Scene::section_field). Empty: all its own (a scene built in code).
  std::vector<std::string> given;
  double length() const;
  double end() const { return start + length(); }
};

struct OverlapSpec {
  int spans = 1;                       // transition spans shared by consecutive sections
  std::optional<double> support_rise;  // d of eq. 8, m; empty: eq. 6-8 with E measured on the model
  std::optional<double> design_force;  // F of eq. 6, N; empty: the mean static uplift of the pantographs (else 100 N)
  // On a 3-D line, m: at a support both sections share, each section's wires are held half of it
  // to either side of the stagger, the ending section's to the left (+) of it for a positive
  // value, so that through the transition spans the two contact wires run side by side.
  double lateral_separation = 0.0;
};

enum class RotaryInertia { kCondensed, kLumped };
enum class Integrator { kExplicit, kImplicit };
// The explicit scheme's Rayleigh damping of the wires' bending and tension (C = alpha M + beta K,
// eq. 5): kHalfStep takes it on v_{n-1/2} (eq. 19-21), so beta K on the shortest mesh modes sets
// dt; kCentred on (v_{n+1/2} + v_{n-1/2}) / 2, a banded solve per step and the undamped limit.
enum class DampingStep { kHalfStep, kCentred };

// The supports' springs (steady arms, messenger supports; NumericsSpec::supports) and the droppers
// (NumericsSpec::droppers) in the explicit step: kExplicit takes their force at q_n (eq. 19-21), so
// a stiff spring on its light nodes can set dt; kImplicit at the step's middle (the trapezoidal
// rule, their damping centred), which has no stability limit of its own: dt is then set by the
// rest. A dropper at the middle is slack where the tension the middle gives it would be
// compressive (explicit_step.cpp).
enum class SpringStep { kExplicit, kImplicit };

constexpr double kMaxGustLead = 60.0;  // s, numerics.gust_lead

// How the lateral plane's gust lead (NumericsSpec::gust_lead) is stepped: kExplicit with the
// lateral window, at its dt; kImplicit on its own, the trapezoidal rule at the wind's refresh
// interval, handed over to the window as the window reaches it (engine/lateral_lead.hpp).
enum class LeadStep { kImplicit, kExplicit };

// The centred step's dt estimate (stability.cpp) takes the supports' and droppers' explicit
// damping one node at a time, not coupled with the wires' band, so it is no bound at the estimate
// itself: the reference line diverged at 0.99 of it and ran at 0.98. Its dt stays below this share.
constexpr double kCentredMaxSafetyFactor = 0.95;

struct NumericsSpec {
  std::string preset;            // "", fast, balanced, accurate, reference: defaults for the fields below
  double element_length = 0.25;  // m, target; segments between supports and droppers are split evenly
  // explicit: the paper's central differences (eq. 19-21); implicit: Newmark average acceleration
  // with a matrix factorised once (rotations are then always DOFs with HRZ rotary inertia).
  Integrator integrator = Integrator::kExplicit;
  std::optional<double> dt;      // s; empty = automatic (safety_factor times the stability limit)
  double safety_factor = 0.9;    // for automatic dt
  RotaryInertia rotary_inertia = RotaryInertia::kCondensed;
  DampingStep damping = DampingStep::kHalfStep;
  SpringStep supports = SpringStep::kExplicit;
  SpringStep droppers = SpringStep::kExplicit;
  double divergence_limit = 5.0;  // m: any displacement beyond this stops the run as diverged
  // Moving window: only the spans from `window_behind` m behind the rearmost pantograph to
  // `window_ahead` m ahead of the foremost are integrated (snapped outward to supports); the rest
  // of the line stays at its static state. Off when window_ahead is 0 and window_auto is false.
  // window_auto: the lengths follow the train speed and the wave speed (window_lengths()).
  double window_ahead = 0.0, window_behind = 0.0;
  bool window_auto = false;
  bool windowed() const { return window_auto || window_ahead > 0.0; }
  // 3-D line in a turbulent wind with the window: the lateral plane is stepped this many
  // seconds of travel further ahead than the vertical one, so that a span has felt the gusts that
  // long when the pantograph reaches it (lateral.hpp, gust_lead_time). Empty: auto, which on an
  // endless line is two decay times of the slowest wire's lateral motion, and on a finite line
  // the whole line (no lateral window).
  std::optional<double> gust_lead;
  // How the gust lead is stepped. Empty: auto, implicit unless the line has stitch wires (their
  // stiff clamps join two wires' solves, which the lead's one solve per wire cannot take).
  std::optional<LeadStep> gust_lead_step;
  // A train faster than the contact wire's wave speed (train_speed_limit) runs only with this set.
  bool allow_supercritical = false;
};

struct OutputSpec {
  // Analysis section for the statistics, in span indices [first, last) counted from 0.
  // Default: all spans but the first two and the last two.
  std::optional<int> analysis_first_span;
  std::optional<int> analysis_last_span;
  double filter_cutoff = 20.0;  // Hz, low-pass for the filtered statistics
  double sample_rate = 0.0;     // Hz for the CSV time series; 0 = every step
  // Measuring pantograph's view (line_measures.hpp): bandwidth of its force measurement, Hz.
  double sensor_bandwidth = 20.0;
  bool dropper_series = false;  // also record every analysed dropper's force at the sample rate
  // Limits the report marks (absent: not checked). allowed_uplift: m, largest steady-arm uplift;
  // max_stat_force / min_stat_force: N, bounds on Fm + 3 sigma and Fm - 3 sigma of the filtered
  // force (EN 50367 asks Fm + 3 sigma below a maximum and Fm - 3 sigma above 0);
  // max_contact_loss_percent: share of time without contact.
  std::optional<double> allowed_uplift, max_stat_force, min_stat_force, max_contact_loss_percent;
};

// A line as built rather than as designed (design statics first, then these errors, as on a real
// line). Random errors are normal, drawn from one seeded generator in line order (reproducible on
// every machine: mt19937_64 and Box-Muller, no library-defined distribution).
struct PointMassSpec {
  double station = 0.0;  // m along the line
  double mass = 0.0;     // kg on the contact wire (a section insulator, a splice, a clamp: a hard spot)
};
// A profile along the line: values at increasing stations, linear between them, 0 outside
// (a measured record covers the stretch it was measured on).
struct LineProfile {
  std::vector<double> stations;  // m, strictly increasing
  std::vector<double> values;
  bool empty() const { return stations.empty(); }
  double at(double x) const;
};
// Contact-wire height irregularity: a stress-free deviation of the contact wire's height from the
// design (kinks, waviness, clamps set off height), + up. The contact sees it (eq. 12: the collector
// rides on design height + deviation + displacement); the beam does not (K acts on displacements
// from the design shape), as rail irregularities enter a vehicle model. A measured profile, or
// random from a one-sided power-law spectrum S(k) ~ k^-exponent between two wavelengths, scaled to
// an rms and drawn with random phases (spectral representation) from a seeded generator.
struct IrregularitySpec {
  LineProfile profile;                 // m of deviation at stations (measured)
  double rms = 0.0;                    // m, random irregularity (0: none)
  double wavelength_min = 0.0;         // m
  double wavelength_max = 0.0;         // m
  double exponent = 2.0;               // of S(k) ~ k^-exponent
  std::optional<std::uint64_t> seed;   // unset: drawn from imperfections.seed after the other classes
  bool any() const { return !profile.empty() || rms > 0.0; }
};
// Contact-wire wear: the share of the cross-section worn away along the line (0 new). The worn
// wire is lighter (rhoA (1 - loss)) and bends more easily (EI (1 - loss)^ei_exponent; 2 for a
// section that shrinks alike in every direction, assumed: a wire worn flat at the bottom loses
// more), while its tension stays (set by the tensioning device).
struct WearSpec {
  LineProfile section_loss;  // share at stations; a uniform wear is one value over the whole line
  double uniform = 0.0;      // share over the whole line (instead of the profile)
  double ei_exponent = 2.0;
  bool any() const { return uniform > 0.0 || !section_loss.empty(); }
  double at(double x) const { return section_loss.empty() ? uniform : section_loss.at(x); }
};
struct ImperfectionSpec {
  std::uint64_t seed = 0;
  // Per class (a study can vary one class's realisation alone, e.g. for grouped Sobol indices);
  // unset: each class draws from `seed` in the order droppers, then steady arms.
  std::optional<std::uint64_t> dropper_length_seed, support_height_seed;
  double dropper_length_std = 0.0;            // m: each dropper longer by a normal error (+: the wire hangs lower)
  std::vector<double> dropper_length_errors;  // m per dropper in line order (instead of the std)
  double support_height_std = 0.0;            // m: each steady arm's assembly height y0 of eq. 4 raised by a normal error
  std::vector<double> support_height_errors;  // m per steady arm in line order (instead of the std)
  // m: each support's contact-wire stagger (the steady arm's registration, 3-D line only) moved
  // sideways by a normal error, or per support in line order; drawn from stagger_seed, unset: from
  // a stream of `seed` of its own (SplitMix64 of seed; the dropper and arm draws stay as they were).
  double stagger_std = 0.0;
  std::vector<double> stagger_errors;
  std::optional<std::uint64_t> stagger_seed;
  std::vector<PointMassSpec> point_masses;
  IrregularitySpec contact_wire_irregularity;
  WearSpec contact_wire_wear;
  bool any() const {
    return dropper_length_std > 0.0 || !dropper_length_errors.empty() || support_height_std > 0.0 ||
           !support_height_errors.empty() || stagger_std > 0.0 || !stagger_errors.empty() || !point_masses.empty() ||
           contact_wire_irregularity.any() ||
           contact_wire_wear.any();
  }
};

// ---- The line in plan (3-D line, docs/model_and_numerics.md "The 3-D line") --------------------
// Any of stagger, alignment, wind or pantograph_head.sway gives every wire a lateral plane
// (lateral.hpp); a scene with none of them builds none and runs the 2-D model unchanged.

// Stagger: the wires' lateral offsets at the supports (m from the track centre line, + to the left
// seen in the direction of increasing station). A list is a pattern repeated over the supports in
// line order ([0.3, -0.3]: the zigzag); per_support: one value per support of the line.
struct StaggerSpec {
  std::vector<double> contact_wire;     // m, pattern over the supports
  std::vector<double> messenger;        // m; empty: the contact wire's (the messenger above it)
  bool per_support = false;
  // Lateral restraint at intermediate supports (N/m); empty: rigid. The anchors are always rigid.
  std::optional<double> steady_arm_stiffness, messenger_support_stiffness;
  double at(const std::vector<double>& pattern, std::size_t support) const {
    return pattern.empty() ? 0.0 : pattern[support % pattern.size()];
  }
};

// A circular curve of the track (the supports follow it; the wires are chords between them),
// with optional clothoid transitions inside [start, start + length] at both ends over which the
// curvature ramps linearly from 0 to 1/radius.
struct CurveSpec {
  double start = 0.0;       // m, station where the curve (its entry transition) begins
  double length = 0.0;      // m, total, transitions included
  double radius = 0.0;      // m, + curving to the left (centre on the + side), - to the right
  double transition = 0.0;  // m, each
};
struct AlignmentSpec {
  std::vector<CurveSpec> curves;  // in order of station, not overlapping
  // m, an endless line on one curve (0: none; a finite line's becomes one curve over the line).
  // The endless line has no station 0 to turn from: there the track's heading is taken as 0
  // everywhere, so the wind keeps its direction to the track (a steady cross wind on the curve).
  double radius = 0.0;
  bool any() const { return !curves.empty() || radius != 0.0; }
  double curvature(double x) const;  // 1/m at station x
  double heading(double x) const;    // rad, track direction at x relative to its direction at station 0
};

struct WireDragSpec {
  double diameter = 0.0;          // m, the width the wind meets (a round wire's diameter, a profile's height)
  double drag_coefficient = 1.0;  // Cd on that width (a round wire's in cross flow)
};
// Along-wind turbulence: von Karman spectrum with Davenport's exponential coherence along the
// line, generated by spectral representation on a grid of points (wind_field.hpp).
struct TurbulenceSpec {
  double intensity = 0.0;        // sigma_u / U
  double length_scale = 50.0;    // m, integral length scale L_u
  double coherence_decay = 10.0; // C of coh = exp(-C f dx / U)
  double max_frequency = 5.0;    // Hz, highest frequency generated
  double spacing = 5.0;          // m, between the field's points along the line
  std::uint64_t seed = 0;
};
struct WindSpec {
  double speed = 0.0;        // m/s, mean at the wires' height
  double direction = 90.0;   // deg, of the wind's velocity from the track direction at station 0, + counter-clockwise (90: toward +)
  double air_density = 1.225;  // kg/m^3
  WireDragSpec contact_wire{0.012, 1.0}, messenger{0.0105, 1.0};
  // A stitch wire's (StitchWireSpec): Bz II 35 mm^2, 7 strands of 2.5 mm (DIN 48201-2), 7.5 mm.
  WireDragSpec stitch_wire{0.0075, 1.0};
  // A compound line's auxiliary messenger (AuxiliaryMessengerSpec): 150 mm^2 stranded, 19 strands
  // of 3.17 mm, five strands across: 15.9 mm.
  WireDragSpec auxiliary_messenger{0.0159, 1.0};
  // A trolley wire's bridle (BridleSpec): the stitch wire's Bz II 35 mm^2, 7.5 mm.
  WireDragSpec bridle{0.0075, 1.0};
  // A rigid conductor rail's profile, the wind meeting its height (scene key `height`): the
  // 110 mm of the DSS and Sicat SR profiles (rigid_conductor_rail.yaml); Cd assumed, no measured
  // profile found: EN 1991-1-4 7.6 gives a sharp-cornered rectangle 2.0 for depth / height up to
  // 0.2, rising to 2.4 near 0.7 (a profile's claws and rounded top take it lower).
  WireDragSpec conductor_rail{0.11, 2.0};
  std::vector<std::string> drag_given;  // the drag blocks the scene gave (each needs its wire on the line)
  std::optional<TurbulenceSpec> turbulence;
  std::optional<double> blow_off_limit;  // m, largest lateral blow-off of the contact wire the report accepts
};

enum class DewirementAction { kContinue, kStop };
// The pantograph head across the track (all pantographs): its strips' working width and horn
// extent, centred on the pantograph, and the pantograph's lateral sway with the car body.
struct PantographHeadSpec {
  double working_width = 1.2;  // m, total: the contact point must stay within +-working_width/2
  double horn_width = 1.95;    // m, total extent of the head with its horns
  DewirementAction on_dewirement = DewirementAction::kContinue;
  double sway_amplitude = 0.0;  // m, lateral motion a sin(2 pi f t)
  double sway_frequency = 0.0;  // Hz
  // Or a measured sway (sway.times, sway.lateral): linear between the samples, held before the
  // first and after the last (s, increasing; m, + to the left).
  std::vector<double> sway_times, sway_lateral;
  bool sways() const { return sway_amplitude > 0.0 || !sway_times.empty(); }
  double sway(double t) const;  // m, the head's centre from the track centre line at time t
  double histogram_bin = 0.02;  // m, width of the bins of the lateral contact histogram
};

struct Scene {
  std::string name;
  std::string file;  // the YAML file it was read from (load_scene_file), named in refusals; "" otherwise
  double gravity = 9.81;               // m/s^2
  double contact_wire_height = 5.3;    // m above the rail at the supports
  double encumbrance = 1.2;            // m, messenger above contact wire at the supports
  std::vector<double> spans;           // m, the line's spans in order (overlapping spans counted once)
  // line.endless: one tension section of equal spans that goes on for ever (no anchors in reach).
  // `spans` holds one span here; build_model makes a block of them long enough for the moving
  // window (which it requires) and moves the state back a span at a time as the train runs on.
  // Stations along the line are then unbounded; train.end says where the pass ends.
  bool endless = false;
  std::vector<SectionSpec> sections;   // tension sections in series; at least one
  std::optional<OverlapSpec> overlap;  // present when there are two or more sections
  // Section defaults (the first section's, and the only section's in a one-section scene).
  ContactWireSpec contact_wire;
  std::optional<WireSpec> messenger;
  std::optional<DropperSpec> droppers;
  std::optional<SupportSpec> steady_arms;         // intermediate contact-wire supports
  std::optional<SupportSpec> messenger_supports;  // intermediate messenger supports
  std::optional<StitchWireSpec> stitch_wire;      // stitched catenary
  std::optional<BridleSpec> bridle;               // a trolley wire's elastic suspension
  std::optional<AuxiliaryMessengerSpec> auxiliary_messenger;  // compound catenary
  std::optional<DropperSpec> hangers;                         // compound catenary
  double rayleigh_alpha = 0.0;  // 1/s, eq. 5
  double rayleigh_beta = 0.0;   // s, eq. 5
  std::vector<PantographSpec> pantographs;
  ContactSpec contact;
  double train_speed = 0.0;                // m/s
  std::optional<double> train_start;      // m, train front at t = 0; default: rearmost pantograph at 0
  std::optional<double> train_end;        // m, the pass ends when the train front reaches it
  NumericsSpec numerics;
  OutputSpec output;
  ImperfectionSpec imperfections;
  // 3-D line (empty: the 2-D model). pantograph_head is read whenever given, used with a lateral plane.
  std::optional<StaggerSpec> stagger;
  AlignmentSpec alignment;
  std::optional<WindSpec> wind;
  PantographHeadSpec pantograph_head;
  bool lateral() const {
    return stagger.has_value() || alignment.any() || wind.has_value() || pantograph_head.sways();
  }

  double line_length() const;
  // A field of section i as messages name it: "sections[i].name", or "name" on a line of one section
  // and where the section takes that part from the top level.
  std::string section_field(std::size_t i, const std::string& name) const;
  // Span index [first, last) of the statistics section, resolved against the defaults.
  int analysis_first() const;
  int analysis_last() const;
};

// The train-speed limit, one definition for the scene files, the tools' --speed, Simulation's
// speed commands, the nodes and Python. Below the slowest contact wire's wave speed
// c = sqrt(T / rhoA): at c the wave ahead of the pantograph cannot run away from it and the
// steady uplift grows without bound; above it the pass is supercritical, outside what the model
// is built and checked for (numerics.allow_supercritical opts in). Never above kMaxTrainSpeed.
constexpr double kMaxTrainSpeed = 150.0;  // m/s (540 km/h)
struct TrainSpeedLimit {
  double wave_speed = 0.0;  // m/s, sqrt(T / rhoA) of the slowest contact wire
  double max = 0.0;         // m/s, the largest speed allowed (excluded when below_wave_speed)
  bool below_wave_speed = true;
  bool allows(double v) const { return v >= 0.0 && (below_wave_speed ? v < max : v <= max); }  // false for NaN
  std::string text() const;  // "0 to ... m/s (... km/h) ...", for messages
};
TrainSpeedLimit train_speed_limit(const Scene& scene);

// A rigid rail's profile's bending stiffness, vertical or lateral, at most (N m^2): several times
// the stiffest profiles in service (about 3e5), and the bound a span's length is checked against.
constexpr double kMaxRailBendingStiffness = 1e8;

// The lateral contact histogram has at most this many bins across pantograph_head.horn_width.
constexpr double kMaxHistogramBins = 10000.0;
// The turbulent wind field has at most this many points along the line (wind.turbulence.spacing).
constexpr double kMaxWindFieldPoints = 100000.0;
// Points of the turbulent wind field over the stretch of line the pass covers; 0 without turbulence.
double wind_field_points(const Scene& scene);

// Whether section i's conductor_rail.transition_piece lies at its start (end): where a catenary
// section joins the rail section there.
bool transition_piece_at_start(const Scene& scene, std::size_t i);
bool transition_piece_at_end(const Scene& scene, std::size_t i);

// A scene is a few kB of YAML: a file above this is refused before it is read whole.
constexpr std::size_t kMaxSceneFileBytes = std::size_t{16} << 20;

// Anchors and aliases may repeat a value; the nodes they add (an alias counts its anchor's whole
// subtree, nested aliases multiply) are limited to this many, and an alias inside its own anchor
// is refused: either would make every reader walk without end.
constexpr std::size_t kMaxAliasExpansion = 10000;

// Loads and validates; throws SceneError. `overrides` are "dotted.key=value" pairs applied to the
// YAML tree before validation (the same keys as the file, e.g. "numerics.element_length=0.125").
Scene load_scene_file(const std::string& path, const std::vector<std::string>& overrides = {});
// base_dir: where relative file names in the scene (profiles given as csv) are looked up;
// empty = the working directory. load_scene_file uses the scene file's directory.
Scene load_scene_string(const std::string& yaml, const std::vector<std::string>& overrides = {},
                        const std::string& base_dir = "");
Scene scene_from_yaml(const YAML::Node& root, const std::string& base_dir = "");
// Checks cross-field consistency; throws SceneError. Called by the loaders; call it again after
// changing a Scene in code.
void validate(const Scene& scene);

}  // namespace catenary_sim
