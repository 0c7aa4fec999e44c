// Sparse assembly shared by the static solves and the implicit integrator's matrix.
#include "model/assembly.hpp"

namespace catenary_sim {

// The wire's band in a sparse matrix, w of node i at w0 + i and theta at t0 + i.
void add_wire_band(Triplets& t, const Wire& w, int w0, int t0) {
  const int n = w.nodes();
  for (int i = 0; i < n; ++i) {
    t.emplace_back(w0 + i, w0 + i, w.d_ww[i]);
    t.emplace_back(w0 + i, t0 + i, w.d_wt[i]);
    t.emplace_back(t0 + i, w0 + i, w.d_wt[i]);
    t.emplace_back(t0 + i, t0 + i, w.d_tt[i]);
  }
  for (int e = 0; e + 1 < n; ++e) {
    const int a = e, b = e + 1;
    const double blk[2][2] = {{w.e_ww[e], w.e_wt[e]}, {w.e_tw[e], w.e_tt[e]}};
    const int ra[2] = {w0 + a, t0 + a}, cb[2] = {w0 + b, t0 + b};
    for (int r = 0; r < 2; ++r)
      for (int c = 0; c < 2; ++c) {
        t.emplace_back(ra[r], cb[c], blk[r][c]);
        t.emplace_back(cb[c], ra[r], blk[r][c]);
      }
  }
}

// A spring between DOF a (above) and b (below, -1 = ground) with compression C = P + k (x_b - x_a).
void add_spring(Triplets& t, Eigen::VectorXd& r, int a, int b, double k, double preload) {
  t.emplace_back(a, a, k);
  r[a] += preload;
  if (b >= 0) {
    t.emplace_back(a, b, -k);
    t.emplace_back(b, a, -k);
    t.emplace_back(b, b, k);
    r[b] -= preload;
  }
}

}  // namespace catenary_sim
