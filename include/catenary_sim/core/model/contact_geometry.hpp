// Where a collector meets the contact wire (contact_geometry.cpp).
#pragma once

namespace catenary_sim {

struct Model;
struct Wire;

// Design height (m) of the lowest contact wire under station xc (eq. 12 weights), the wire a
// rising head meets first; +inf where no contact wire is. `wire` (if given) receives its index
// into Model::contact_wires.
double lowest_design_height(const Model& model, double xc, int* wire = nullptr);

// Weights of the contact wire's nodes for a distributed contact centred at xc (eq. 10-13): the
// collector height is sum w_i y_i (eq. 12) and its force is spread as F w_i. Returns the count,
// at most model.max_contact_nodes; 0 if xc is off the wire.
int contact_weights(const Wire& wire, double rub_length, double xc, int* node, double* weight);

}  // namespace catenary_sim
