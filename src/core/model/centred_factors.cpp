#include "model/centred_factors.hpp"

#include <algorithm>
#include <vector>

namespace catenary_sim {

namespace {

typedef double Mat2[4];  // row-major

void mul(const double* a, const double* b, double* out) {
  out[0] = a[0] * b[0] + a[1] * b[2];
  out[1] = a[0] * b[1] + a[1] * b[3];
  out[2] = a[2] * b[0] + a[3] * b[2];
  out[3] = a[2] * b[1] + a[3] * b[3];
}

void sub_mul(double* a, const double* b, const double* c) {  // a -= b c
  Mat2 bc;
  mul(b, c, bc);
  for (int k = 0; k < 4; ++k) a[k] -= bc[k];
}

void invert(const double* a, double* out) {
  const double det = a[0] * a[3] - a[1] * a[2];
  out[0] = a[3] / det;
  out[1] = -a[1] / det;
  out[2] = -a[2] / det;
  out[3] = a[0] / det;
}

}  // namespace

int centred_meeting_node(int nodes) { return (nodes - 1) / 2; }

namespace {

// One wire's factors, kCdValues per node in line order (the packs take them in the twisted order);
// its fixed vertical DOFs appended to `fixed_dofs`. D = shift M.
std::vector<double> wire_factors(const Model& m, const Wire& w, double shift, std::vector<int>& fixed_dofs) {
  std::vector<double> factors;
  const int n = w.nodes(), k = centred_meeting_node(n);
  factors.assign(static_cast<std::size_t>(n) * kCdValues, 0.0);
  auto fixed = [&](int i) { return m.inv_mass[w.w_dof + i] == 0.0; };
  auto at = [&](int i) { return factors.data() + static_cast<std::size_t>(i) * kCdValues; };
  // Blocks of D + K: A_i on node i (a fixed node's vertical row the identity), U_i from node i to
  // i + 1 and L_i from node i + 1 to i (the vertical row of a fixed node zero in both).
  auto diag = [&](int i, double* a) {
    const bool fx = fixed(i);
    a[0] = fx ? 1.0 : shift * m.mass[w.w_dof + i] + w.d_ww[i];
    a[1] = fx ? 0.0 : w.d_wt[i];
    a[2] = w.d_wt[i];
    a[3] = w.d_tt[i];
  };
  auto upper = [&](int i, double* u) {  // rows i, cols i + 1
    const bool fx = fixed(i);
    u[0] = fx ? 0.0 : w.e_ww[i];
    u[1] = fx ? 0.0 : w.e_wt[i];
    u[2] = w.e_tw[i];
    u[3] = w.e_tt[i];
  };
  auto lower = [&](int i, double* l) {  // rows i + 1, cols i
    const bool fx = fixed(i + 1);
    l[0] = fx ? 0.0 : w.e_ww[i];
    l[1] = fx ? 0.0 : w.e_tw[i];
    l[2] = w.e_wt[i];
    l[3] = w.e_tt[i];
  };
  // One side's elimination toward k: pivot a_i = A_i - M_i B (M_i = C S_prev, the coupling C
  // into node i from its predecessor and B back), S_i = a_i^-1; in the node's places the
  // recurrence on c_i = S_i y_i: c_i = s_i r_i - (S_i M_i a_prev) c_prev (s_i: S_i's first
  // column, r's rotation entry being 0), and P_i = S_i N_i toward the next node (N_i its coupling).
  Mat2 a{}, a_prev{}, s_prev{}, mm{}, tmp{}, cpl{}, back{};
  auto side = [&](int i, bool first, const double* into, const double* out_back, const double* next) {
    double* c = at(i);
    diag(i, a);
    if (!first) {
      mul(into, s_prev, mm);  // M_i
      sub_mul(a, mm, out_back);
    }
    Mat2 si;
    invert(a, si);
    if (!first) {
      mul(si, mm, tmp);
      mul(tmp, a_prev, c + kCdG);
    }
    c[kCdS] = si[0];
    c[kCdS + 1] = si[2];
    mul(si, next, c + kCdP);
    std::copy(a, a + 4, a_prev);
    std::copy(si, si + 4, s_prev);
  };
  for (int i = 0; i < k; ++i) {
    if (i > 0) {
      lower(i - 1, cpl);
      upper(i - 1, back);
    }
    Mat2 nx;
    upper(i, nx);
    side(i, i == 0, cpl, back, nx);
  }
  Mat2 top_a, top_s;  // S~_{k-1} and S_{k-1}
  std::copy(a_prev, a_prev + 4, top_a);
  std::copy(s_prev, s_prev + 4, top_s);
  for (int i = n - 1; i > k; --i) {
    if (i < n - 1) {
      upper(i, cpl);
      lower(i, back);
    }
    Mat2 nx;
    lower(i - 1, nx);
    side(i, i == n - 1, cpl, back, nx);
  }
  // The meeting node: Z = A_k - G_k U_{k-1} - H_k L_k (G_k = L_{k-1} S_{k-1}, H_k = U_k T_{k+1});
  // zeta_k = Z^-1 r_k - (Z^-1 G_k S~_{k-1}) c_{k-1} - (Z^-1 H_k T~_{k+1}) c'_{k+1}: in its G, P
  // and S places.
  double* c = at(k);
  diag(k, a);
  Mat2 g{}, h{}, zi{};
  if (k > 0) {
    lower(k - 1, cpl);
    mul(cpl, top_s, g);
    upper(k - 1, back);
    sub_mul(a, g, back);
  }
  if (k + 1 < n) {
    upper(k, cpl);
    mul(cpl, s_prev, h);
    lower(k, back);
    sub_mul(a, h, back);
  }
  invert(a, zi);
  if (k > 0) {
    mul(zi, g, tmp);
    mul(tmp, top_a, c + kCdG);
  }
  if (k + 1 < n) {
    mul(zi, h, tmp);
    mul(tmp, a_prev, c + kCdP);
  }
  c[kCdS] = zi[0];
  c[kCdS + 1] = zi[2];
  for (int i = 0; i < n; ++i) {
    const bool fx = fixed(i);
    if (fx) fixed_dofs.push_back(w.w_dof + i);
    at(i)[kCdU] = fx ? 1.0 : shift * m.mass[w.w_dof + i];
  }
  return factors;
}

}  // namespace

void factor_centred_damping(Model& m) {
  const double shift = 2.0 / (m.beta * m.dt) + m.alpha / m.beta;
  m.centred_fixed_dofs.clear();
  m.centred_v_ratio = (2.0 / m.dt) / shift;
  // The packs: pair j of the twisted order (top node j, bottom node n - 1 - (bottom - top) - j,
  // both eliminated at step j and substituted at step top - 1 - j) in 2L lanes, the top's lanes
  // first; the meeting node and the extra bottom node (when n is even) alone, in L lanes.
  for (WireLanes& p : m.wire_packs) {
    const int L = p.lanes, n = p.nodes, k = centred_meeting_node(n), top = k, extra = (n - 1 - k) - top;
    p.centred_twin.assign(static_cast<std::size_t>(top) * kCdValues * 2 * L, 0.0);
    p.centred_single.assign(2 * kCdValues * static_cast<std::size_t>(L), 0.0);
    for (int lane = 0; lane < L; ++lane) {
      const std::vector<double> factors = wire_factors(m, m.wires[p.wire[lane]], shift, m.centred_fixed_dofs);
      auto value = [&](int i, int v) { return factors[static_cast<std::size_t>(i) * kCdValues + v]; };
      for (int j = 0; j < top; ++j)
        for (int v = 0; v < kCdValues; ++v) {
          double* t = p.centred_twin.data() + (static_cast<std::size_t>(j) * kCdValues + v) * 2 * L;
          t[lane] = value(j, v);
          t[L + lane] = value(n - 1 - extra - j, v);
        }
      for (int v = 0; v < kCdValues; ++v) {
        p.centred_single[v * L + lane] = value(k, v);
        p.centred_single[(kCdValues + v) * L + lane] = extra ? value(n - 1, v) : 0.0;
      }
    }
  }
}

}  // namespace catenary_sim
