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

// One wire's twisted factorisation of D + K over its nodes lo..hi (the range's node i is the wire's
// lo + i), kCdValues per node in line order: the elimination from node 0 down to the meeting node
// k, from node n - 1 up to it, then the meeting node.
class TwistedFactors {
 public:
  TwistedFactors(const Wire& w, const double* mass, const double* inv_mass, double shift, int lo, int hi,
                 const double* end_share, double* factors)
      : w_(w), mass_(mass), inv_mass_(inv_mass), shift_(shift), lo_(lo), hi_(hi), share_(end_share), factors_(factors) {
    std::fill(factors_, factors_ + static_cast<std::size_t>(hi - lo + 1) * kCdValues, 0.0);
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

  // The coefficient of u + ratio v in r per node; the fixed vertical DOFs appended to `fixed_dofs`
  // (when given).
  void finish(int n, std::vector<int>* fixed_dofs) {
    for (int i = 0; i < n; ++i) {
      const bool fx = fixed(i);
      if (fx && fixed_dofs) fixed_dofs->push_back(dof(i));
      at(i)[kCdU] = fx ? 1.0 : shift_ * mass_[dof(i)];
    }
  }

 private:
  int node(int i) const { return lo_ + i; }
  int dof(int i) const { return w_.w_dof + lo_ + i; }
  bool fixed(int i) const { return inv_mass_[dof(i)] == 0.0; }
  double* at(int i) { return factors_ + static_cast<std::size_t>(i) * kCdValues; }
  // The diagonal block's band entry v (0: ww, 1: wt, 2: tt) at range node i, less the end shares.
  double band(int i, const std::vector<double>& entry, int v) const {
    double e = entry[node(i)];
    if (share_) {
      if (i == 0) e -= share_[v];
      if (node(i) == hi_) e -= share_[3 + v];
    }
    return e;
  }
  // Blocks of D + K: A_i on node i (a fixed node's vertical row the identity), U_i from node i to
  // i + 1 and L_i from node i + 1 to i (the vertical row of a fixed node zero in both).
  void diag(int i, double* a) const {
    const bool fx = fixed(i);
    const double wt = band(i, w_.d_wt, 1);
    a[0] = fx ? 1.0 : shift_ * mass_[dof(i)] + band(i, w_.d_ww, 0);
    a[1] = fx ? 0.0 : wt;
    a[2] = wt;
    a[3] = band(i, w_.d_tt, 2);
  }
  void upper(int i, double* u) const {  // rows i, cols i + 1
    const bool fx = fixed(i);
    const int g = node(i);
    u[0] = fx ? 0.0 : w_.e_ww[g];
    u[1] = fx ? 0.0 : w_.e_wt[g];
    u[2] = w_.e_tw[g];
    u[3] = w_.e_tt[g];
  }
  void lower(int i, double* l) const {  // rows i + 1, cols i
    const bool fx = fixed(i + 1);
    const int g = node(i);
    l[0] = fx ? 0.0 : w_.e_ww[g];
    l[1] = fx ? 0.0 : w_.e_tw[g];
    l[2] = w_.e_wt[g];
    l[3] = w_.e_tt[g];
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

  const Wire& w_;
  const double *mass_, *inv_mass_;  // per DOF of the plane w_.w_dof numbers
  double shift_;
  int lo_, hi_;
  const double* share_;  // null: no end shares (a whole wire)
  double* factors_;
  Mat2 a_{}, a_prev_{}, s_prev_{}, mm_{}, tmp_{}, cpl_{}, back_{};
  Mat2 top_a_{}, top_s_{};  // S~_{k-1} and S_{k-1}
};

// The factors of nodes lo..hi into `factors` (kCdValues per node in line order; the packs take
// them in the twisted order), less the end shares when given (factor_centred_range); its fixed
// vertical DOFs appended to `fixed_dofs` when given. D = shift M.
void range_factors(const Wire& w, const double* mass, const double* inv_mass, double shift, int lo, int hi,
                   const double* end_share, double* factors, std::vector<int>* fixed_dofs) {
  const int n = hi - lo + 1, k = centred_meeting_node(n);
  TwistedFactors f(w, mass, inv_mass, shift, lo, hi, end_share, factors);
  f.eliminate_from_first(k);
  f.eliminate_from_last(n, k);
  f.meet(n, k);
  f.finish(n, fixed_dofs);
}

// A lane's factors (line order, n nodes) laid out in the twisted order of a pack of `lanes`
// lanes: pair j (top node j, bottom node n - 1 - extra - j) in 2L lanes, the top's lanes first;
// the meeting node and the extra bottom node (when n is even) alone, in L lanes.
void lay_out_lane(const double* factors, int n, int lanes, int lane, double* twin, double* single) {
  const int L = lanes, k = centred_meeting_node(n), top = k, extra = (n - 1 - k) - top;
  auto value = [&](int i, int v) { return factors[static_cast<std::size_t>(i) * kCdValues + v]; };
  for (int j = 0; j < top; ++j)
    for (int v = 0; v < kCdValues; ++v) {
      double* t = twin + (static_cast<std::size_t>(j) * kCdValues + v) * 2 * L;
      t[lane] = value(j, v);
      t[L + lane] = value(n - 1 - extra - j, v);
    }
  for (int v = 0; v < kCdValues; ++v) {
    single[v * L + lane] = value(k, v);
    single[(kCdValues + v) * L + lane] = extra ? value(n - 1, v) : 0.0;
  }
}

}  // namespace

double centred_shift(const Model& m, double dt) { return 2.0 / (m.beta * dt) + m.alpha / m.beta; }

void factor_centred_damping(const Model& m, WirePacks& packs) {
  const double shift = centred_shift(m, m.dt);
  packs.centred_fixed_dofs.clear();
  packs.centred_v_ratio = (2.0 / m.dt) / shift;
  std::vector<double> factors;
  for (WireLanes& p : packs.packs) {
    const int L = p.lanes, n = p.nodes, top = centred_meeting_node(n);
    p.centred_twin.assign(static_cast<std::size_t>(top) * kCdValues * 2 * L, 0.0);
    p.centred_single.assign(2 * kCdValues * static_cast<std::size_t>(L), 0.0);
    factors.assign(static_cast<std::size_t>(n) * kCdValues, 0.0);
    for (int lane = 0; lane < L; ++lane) {
      range_factors(m.wires[p.wire[lane]], m.mass.data(), m.inv_mass.data(), shift, 0, n - 1, nullptr, factors.data(),
                    &packs.centred_fixed_dofs);
      lay_out_lane(factors.data(), n, L, lane, p.centred_twin.data(), p.centred_single.data());
    }
  }
}

void factor_centred_range(const CentredPlane& plane, const WireLanes& pack, int lane, int lo, int hi,
                          const double end_share[6], double* scratch, double* twin, double* single) {
  range_factors((*plane.wires)[pack.wire[lane]], plane.mass, plane.inv_mass, plane.shift, lo, hi, end_share, scratch,
                nullptr);
  lay_out_lane(scratch, hi - lo + 1, pack.lanes, lane, twin, single);
}

}  // namespace catenary_sim
