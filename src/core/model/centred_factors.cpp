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

// One wire's twisted factorisation of D + K, kCdValues per node in line order: the elimination
// from node 0 down to the meeting node k, from node n - 1 up to it, then the meeting node.
class TwistedFactors {
 public:
  TwistedFactors(const Model& m, const Wire& w, double shift) : m_(m), w_(w), shift_(shift) {
    factors_.assign(static_cast<std::size_t>(w.nodes()) * kCdValues, 0.0);
  }

  void eliminate_from_first(int k) {
    for (int i = 0; i < k; ++i) {
      if (i > 0) {
        lower(i - 1, cpl_);
        upper(i - 1, back_);
      }
      Mat2 nx;
      upper(i, nx);
      side(i, i == 0, cpl_, back_, nx);
    }
    std::copy(a_prev_, a_prev_ + 4, top_a_);
    std::copy(s_prev_, s_prev_ + 4, top_s_);
  }

  void eliminate_from_last(int n, int k) {
    for (int i = n - 1; i > k; --i) {
      if (i < n - 1) {
        upper(i, cpl_);
        lower(i, back_);
      }
      Mat2 nx;
      lower(i - 1, nx);
      side(i, i == n - 1, cpl_, back_, nx);
    }
  }

  // The meeting node: Z = A_k - G_k U_{k-1} - H_k L_k (G_k = L_{k-1} S_{k-1}, H_k = U_k T_{k+1});
  // zeta_k = Z^-1 r_k - (Z^-1 G_k S~_{k-1}) c_{k-1} - (Z^-1 H_k T~_{k+1}) c'_{k+1}: in its G, P
  // and S places.
  void meet(int n, int k) {
    double* c = at(k);
    diag(k, a_);
    Mat2 g{}, h{}, zi{};
    if (k > 0) {
      lower(k - 1, cpl_);
      mul(cpl_, top_s_, g);
      upper(k - 1, back_);
      sub_mul(a_, g, back_);
    }
    if (k + 1 < n) {
      upper(k, cpl_);
      mul(cpl_, s_prev_, h);
      lower(k, back_);
      sub_mul(a_, h, back_);
    }
    invert(a_, zi);
    if (k > 0) {
      mul(zi, g, tmp_);
      mul(tmp_, top_a_, c + kCdG);
    }
    if (k + 1 < n) {
      mul(zi, h, tmp_);
      mul(tmp_, a_prev_, c + kCdP);
    }
    c[kCdS] = zi[0];
    c[kCdS + 1] = zi[2];
  }

  // The coefficient of u + ratio v in r per node; the fixed vertical DOFs appended to `fixed_dofs`.
  std::vector<double> finish(int n, std::vector<int>& fixed_dofs) {
    for (int i = 0; i < n; ++i) {
      const bool fx = fixed(i);
      if (fx) fixed_dofs.push_back(w_.w_dof + i);
      at(i)[kCdU] = fx ? 1.0 : shift_ * m_.mass[w_.w_dof + i];
    }
    return std::move(factors_);
  }

 private:
  bool fixed(int i) const { return m_.inv_mass[w_.w_dof + i] == 0.0; }
  double* at(int i) { return factors_.data() + static_cast<std::size_t>(i) * kCdValues; }
  // Blocks of D + K: A_i on node i (a fixed node's vertical row the identity), U_i from node i to
  // i + 1 and L_i from node i + 1 to i (the vertical row of a fixed node zero in both).
  void diag(int i, double* a) const {
    const bool fx = fixed(i);
    a[0] = fx ? 1.0 : shift_ * m_.mass[w_.w_dof + i] + w_.d_ww[i];
    a[1] = fx ? 0.0 : w_.d_wt[i];
    a[2] = w_.d_wt[i];
    a[3] = w_.d_tt[i];
  }
  void upper(int i, double* u) const {  // rows i, cols i + 1
    const bool fx = fixed(i);
    u[0] = fx ? 0.0 : w_.e_ww[i];
    u[1] = fx ? 0.0 : w_.e_wt[i];
    u[2] = w_.e_tw[i];
    u[3] = w_.e_tt[i];
  }
  void lower(int i, double* l) const {  // rows i + 1, cols i
    const bool fx = fixed(i + 1);
    l[0] = fx ? 0.0 : w_.e_ww[i];
    l[1] = fx ? 0.0 : w_.e_tw[i];
    l[2] = w_.e_wt[i];
    l[3] = w_.e_tt[i];
  }
  // One side's elimination toward k: pivot a_i = A_i - M_i B (M_i = C S_prev, the coupling C
  // into node i from its predecessor and B back), S_i = a_i^-1; in the node's places the
  // recurrence on c_i = S_i y_i: c_i = s_i r_i - (S_i M_i a_prev) c_prev (s_i: S_i's first
  // column, r's rotation entry being 0), and P_i = S_i N_i toward the next node (N_i its coupling).
  void side(int i, bool first, const double* into, const double* out_back, const double* next) {
    double* c = at(i);
    diag(i, a_);
    if (!first) {
      mul(into, s_prev_, mm_);  // M_i
      sub_mul(a_, mm_, out_back);
    }
    Mat2 si;
    invert(a_, si);
    if (!first) {
      mul(si, mm_, tmp_);
      mul(tmp_, a_prev_, c + kCdG);
    }
    c[kCdS] = si[0];
    c[kCdS + 1] = si[2];
    mul(si, next, c + kCdP);
    std::copy(a_, a_ + 4, a_prev_);
    std::copy(si, si + 4, s_prev_);
  }

  const Model& m_;
  const Wire& w_;
  double shift_;
  std::vector<double> factors_;
  Mat2 a_{}, a_prev_{}, s_prev_{}, mm_{}, tmp_{}, cpl_{}, back_{};
  Mat2 top_a_{}, top_s_{};  // S~_{k-1} and S_{k-1}
};

// One wire's factors, kCdValues per node in line order (the packs take them in the twisted order);
// its fixed vertical DOFs appended to `fixed_dofs`. D = shift M.
std::vector<double> wire_factors(const Model& m, const Wire& w, double shift, std::vector<int>& fixed_dofs) {
  const int n = w.nodes(), k = centred_meeting_node(n);
  TwistedFactors f(m, w, shift);
  f.eliminate_from_first(k);
  f.eliminate_from_last(n, k);
  f.meet(n, k);
  return f.finish(n, fixed_dofs);
}

}  // namespace

void factor_centred_damping(const Model& m, WirePacks& packs) {
  const double shift = 2.0 / (m.beta * m.dt) + m.alpha / m.beta;
  packs.centred_fixed_dofs.clear();
  packs.centred_v_ratio = (2.0 / m.dt) / shift;
  // The packs: pair j of the twisted order (top node j, bottom node n - 1 - (bottom - top) - j,
  // both eliminated at step j and substituted at step top - 1 - j) in 2L lanes, the top's lanes
  // first; the meeting node and the extra bottom node (when n is even) alone, in L lanes.
  for (WireLanes& p : packs.packs) {
    const int L = p.lanes, n = p.nodes, k = centred_meeting_node(n), top = k, extra = (n - 1 - k) - top;
    p.centred_twin.assign(static_cast<std::size_t>(top) * kCdValues * 2 * L, 0.0);
    p.centred_single.assign(2 * kCdValues * static_cast<std::size_t>(L), 0.0);
    for (int lane = 0; lane < L; ++lane) {
      const std::vector<double> factors = wire_factors(m, m.wires[p.wire[lane]], shift, packs.centred_fixed_dofs);
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
