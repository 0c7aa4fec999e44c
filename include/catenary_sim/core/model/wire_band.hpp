// The wires' banded stiffness (eq. 3) and its products (wire_band.cpp).
#pragma once

#include <vector>

namespace catenary_sim {

struct Model;
struct Scene;
struct Wire;

// Assembles the wire's K band and the LDL^T factors of its K_theta_theta. ei_factor: per element,
// a multiplier of EI (a worn contact wire); empty = the wire's EI.
void assemble_band(Wire& w, const std::vector<double>& ei_factor);

// A rail profile's EI factors along its transition pieces (SectionSpec::rail_transition_piece):
// per element, EI(s) / EI at its middle, s from the profile's end, rising linearly from
// end_bending_stiffness / EI at s = 0 to 1 at s = length; empty where the wire has none.
std::vector<double> transition_piece_factors(const Scene& scene, const Wire& w);

// y = K x for the linear part of the system with every dropper and contact active (the collectors
// at the train position `front`): used for the stability limit and by tests. x and y have n_dof
// entries; `scratch` must have room for the condensed rotations (max wire nodes). With
// `explicit_part`, the supports' springs, droppers and clamps taken at the step's middle
// (Model::support_at_middle, dropper_at_middle, clamp_at_middle) are left out: the explicit step's stability is
// that of the rest.
void apply_stiffness(const Model& model, double front, const double* x, double* y, double* scratch,
                     bool explicit_part = false);

// Has the wire's condensed rotations swept from both ends, meeting at its middle node (an odd
// count of nodes): the factors of Wire::twisted_meeting. A lone wire of the fused step is swept so
// (model/wire_packs.cpp), its two halves in the two lanes of a register; the same numbers to the
// bit wherever its band force is taken (wire_elastic_force).
void twist_condensation(Wire& w);

// Stiffness-only internal force of one wire: f(w) -= K z over the wire's nodes (rotations
// condensed, from both ends for a twisted wire, or taken from z). `theta` is scratch (nodes
// entries) and returns the rotations used.
void wire_elastic_force(const Wire& wire, const double* z, double* f, double* theta);

// The condensed band's force on nodes lo..hi of a wire (f -= K z), given the LDL^T factors of
// K_theta_theta over that range and the diagonal shares (ww, wt at lo, then at hi) of elements
// left out at the ends. Shared by the whole wire and the moving window.
void condensed_band_force(const Wire& wire, int lo, int hi, const double end_correction[4], const double* lower,
                          const double* inv_pivot, const double* z, double* f, double* theta);

}  // namespace catenary_sim
