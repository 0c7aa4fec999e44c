// The elasticity's uniformity over each span: what a line's design aims at (a pantograph feels
// the elasticity's change along the span once per span), stated as EN 50119 does,
// U = (e_max - e_min) / (e_max + e_min). A pure function of a sampled elasticity curve
// (elasticity_curve, ElasticityProbe).
#pragma once

#include <vector>

namespace catenary_sim {

struct SpanElasticity {
  int span = 0;                    // index along the line (span i starts at support i)
  double start = 0.0, end = 0.0;   // m, its supports
  int samples = 0;                 // stations inside [start, end] with a value
  double min = 0.0, max = 0.0, mean = 0.0;  // m/N
  double uniformity = 0.0;         // (max - min) / (max + min), 0-1
};

// Per span between consecutive `supports` (m, increasing): the elasticity `e` (m/N, not a
// number where the probe did not touch the wire) sampled at stations `x`, every finite sample
// with x in [start, end] counted (the supports belong to both spans beside them). A span with
// fewer than two samples is left out.
std::vector<SpanElasticity> elasticity_by_span(const std::vector<double>& x, const std::vector<double>& e,
                                               const std::vector<double>& supports);

}  // namespace catenary_sim
