// Where a collector meets the contact wire: the nodes it touches and their weights (eq. 10-13),
// and the design height a rising head meets first.
#include "catenary_sim/core/model/contact_geometry.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

#include "catenary_sim/core/model/model.hpp"

namespace catenary_sim {

int contact_weights(const Wire& wire, double rub_length, double xc, int* node, double* weight) {
  const double x0 = wire.x.front(), x1 = wire.x.back();
  if (rub_length <= 0.0) {
    if (xc < x0 || xc > x1) return 0;
    const int e = wire.element_at(xc);
    const double xi = (xc - wire.x[e]) / (wire.x[e + 1] - wire.x[e]);
    node[0] = e;
    node[1] = e + 1;
    weight[0] = 1.0 - xi;
    weight[1] = xi;
    return 2;
  }
  const double a = xc - 0.5 * rub_length, b = xc + 0.5 * rub_length;
  if (b <= x0 || a >= x1) return 0;
  const int ea = wire.element_at(a), eb = wire.element_at(b);
  const int count = eb - ea + 2;
  for (int k = 0; k < count; ++k) {
    node[k] = ea + k;
    weight[k] = 0.0;
  }
  // Exact integrals of f(s) = (1 + cos(2 pi s / l)) / l (eq. 13) against the linear
  // interpolation of the wire between nodes.
  const double kw = 2.0 * M_PI / rub_length, il = 1.0 / rub_length;
  auto F0 = [&](double s) { return (s + std::sin(kw * s) / kw) * il; };
  auto F1 = [&](double s) { return (0.5 * s * s + s * std::sin(kw * s) / kw + std::cos(kw * s) / (kw * kw)) * il; };
  double total = 0.0;
  for (int e = ea; e <= eb; ++e) {
    const double xa = wire.x[e], xb = wire.x[e + 1];
    const double s1 = std::max(a, xa) - xc, s2 = std::min(b, xb) - xc;
    if (s2 <= s1) continue;
    const double i0 = F0(s2) - F0(s1), i1 = F1(s2) - F1(s1);
    const double right = (i1 + (xc - xa) * i0) / (xb - xa);
    weight[e - ea] += i0 - right;
    weight[e - ea + 1] += right;
    total += i0;
  }
  if (total <= 1e-12) return 0;
  // Renormalise where the rub zone hangs over the end of the wire, so that eq. 11 holds.
  for (int k = 0; k < count; ++k) weight[k] /= total;
  return count;
}

double lowest_design_height(const Model& m, double xc, int* wire) {
  std::vector<int> node(m.max_contact_nodes);
  std::vector<double> weight(m.max_contact_nodes);
  double lowest = std::numeric_limits<double>::infinity();
  for (std::size_t k = 0; k < m.contact_wires.size(); ++k) {
    const Wire& w = m.wires[m.contact_wires[k]];
    const int cnt = contact_weights(w, m.rub_length, xc, node.data(), weight.data());
    if (cnt == 0) continue;
    double y = 0.0;
    for (int a = 0; a < cnt; ++a) y += weight[a] * w.height[node[a]];
    if (y < lowest) {
      lowest = y;
      if (wire) *wire = static_cast<int>(k);
    }
  }
  return lowest;
}

}  // namespace catenary_sim
