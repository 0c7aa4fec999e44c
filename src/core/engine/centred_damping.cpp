#include "engine/centred_damping.hpp"

#include "catenary_sim/core/engine/lateral_step.hpp"
#include "engine/lateral_workspace.hpp"
#include "engine/step_workspace.hpp"
#include "engine/wire_lanes.hpp"

#include <cmath>
#include <cstring>
#include <vector>

namespace catenary_sim {

namespace {

typedef double Double2 __attribute__((vector_size(16)));
typedef double Double4 __attribute__((vector_size(32)));

// L wires' lanes at one node (Lanes<L>), or at the two nodes of a twisted pair (Lanes<2 L>, the
// top node's lanes first): scalars or GCC vectors, the same IEEE operations per lane either way.
typedef long Long2 __attribute__((vector_size(16)));
typedef long Long4 __attribute__((vector_size(32)));

template <class T, class M, int W>
struct LaneOps {
  typedef M Mask;  // all bits set in a lane: that lane's new displacement is within the limit
  static T at(const double* p) {
    T x;
    std::memcpy(&x, p, sizeof x);
    return x;
  }
  static void put(double* p, T x) { std::memcpy(p, &x, sizeof x); }
  static M within(T x, T limit) {
    const M bits = reinterpret_cast<M>(x) & ~reinterpret_cast<M>(-T{});  // |x|: the sign bit (of -0.0) off
    return reinterpret_cast<T>(bits) <= limit;  // false for NaN
  }
  static bool all(M ok) {
    bool b = true;
    for (int k = 0; k < W; ++k) b &= ok[k] != 0;
    return b;
  }
};
template <int W>
struct Lanes;
template <>
struct Lanes<1> {
  typedef double T;
  typedef bool Mask;
  static T at(const double* p) { return *p; }
  static void put(double* p, T x) { *p = x; }
  static Mask within(T x, T limit) { return std::fabs(x) <= limit; }
  static bool all(Mask ok) { return ok; }
  // lanes of wires a[0..L) at node i (and, for a pair, at node ib)
  static T gather(const double* const* a, int i, int) { return a[0][i]; }
  static void scatter(double* const* a, int i, int, T x) { a[0][i] = x; }
};
template <>
struct Lanes<2> : LaneOps<Double2, Long2, 2> {
  typedef Double2 T;
  // Two wires at node i, or one wire at the pair's nodes i and ib (`pair`).
  template <bool pair>
  static T gather(const double* const* a, int i, int ib) {
    return pair ? T{a[0][i], a[0][ib]} : T{a[0][i], a[1][i]};
  }
  template <bool pair>
  static void scatter(double* const* a, int i, int ib, T x) {
    if (pair) {
      a[0][i] = x[0];
      a[0][ib] = x[1];
    } else {
      a[0][i] = x[0];
      a[1][i] = x[1];
    }
  }
};
template <>
struct Lanes<4> : LaneOps<Double4, Long4, 4> {
  typedef Double4 T;
  template <bool pair>
  static T gather(const double* const* a, int i, int ib) {
    return T{a[0][i], a[1][i], a[0][ib], a[1][ib]};
  }
  template <bool pair>
  static void scatter(double* const* a, int i, int ib, T x) {
    a[0][i] = x[0];
    a[1][i] = x[1];
    a[0][ib] = x[2];
    a[1][ib] = x[3];
  }
};

template <int W, bool pair, class T>
__attribute__((always_inline)) inline T gather(const double* const* a, int i, int ib) {
  if constexpr (W == 1) return Lanes<1>::gather(a, i, ib);
  else return Lanes<W>::template gather<pair>(a, i, ib);
}
template <int W, bool pair, class T>
__attribute__((always_inline)) inline void scatter(double* const* a, int i, int ib, T x) {
  if constexpr (W == 1) Lanes<1>::scatter(a, i, ib, x);
  else Lanes<W>::template scatter<pair>(a, i, ib, x);
}

struct CentredArgs {
  const double* const* u;
  const double* const* v;
  double* const* f;
  double* const* un;
  double* const* vn;
  double* const* acc;
  double dt, v_ratio, two_by_beta, limit;
};

// The elimination and substitution steps in W lanes: one node of L wires (W = L, pair false) or a
// twisted pair of nodes (W = 2 L, pair true), coefficients at `coef` ([value][W]); the record of a
// step (4 W values: c = S y, then u and v) at `rec`.
template <int W, bool pair>
struct Steps {
  typedef typename Lanes<W>::T T;
  typedef typename Lanes<W>::Mask Mask;
  const CentredArgs& a;
  T zero, step, inv_step, ratio, kb, limit;
  Mask ok;
  explicit Steps(const CentredArgs& args) : a(args) {
    zero = T{} * 0.0;
    step = zero + a.dt;
    inv_step = zero + 1.0 / a.dt;
    ratio = zero + a.v_ratio;
    kb = zero + a.two_by_beta;
    limit = zero + a.limit;
    ok = Lanes<W>::within(zero, limit);
  }
  static T c(const double* coef, int k) { return Lanes<W>::at(coef + k * W); }
  // r's vertical entry: load and point forces (f) + a (u + ratio v), a = D_i (1 on a fixed node,
  // where f and v are 0).
  __attribute__((always_inline)) T rhs(const double* coef, T ui, T vi, T fi) const {
    return fi + c(coef, kCdU) * (ui + ratio * vi);
  }
  // c = s r - G^ c_prev (G^ in place mplace).
  __attribute__((always_inline)) void eliminate(const double* coef, int i, int ib, int mplace, T& yw, T& yt, double* rec) {
    const T ui = gather<W, pair, T>(a.u, i, ib), vi = gather<W, pair, T>(a.v, i, ib), fi = gather<W, pair, T>(a.f, i, ib);
    const T rw = rhs(coef, ui, vi, fi);
    const T nw = c(coef, kCdS) * rw - (c(coef, mplace) * yw + c(coef, mplace + 1) * yt);
    const T nt = c(coef, kCdS + 1) * rw - (c(coef, mplace + 2) * yw + c(coef, mplace + 3) * yt);
    yw = nw;
    yt = nt;
    Lanes<W>::put(rec, yw);
    Lanes<W>::put(rec + W, yt);
    Lanes<W>::put(rec + 2 * W, ui);
    Lanes<W>::put(rec + 3 * W, vi);
  }
  // v_{n+1/2} = 2 (zeta - u) / beta - v_{n-1/2} and u_{n+1}.
  __attribute__((always_inline)) void update(int i, int ib, T zeta, T ui, T vi) {
    const T vnew = kb * (zeta - ui) - vi;
    const T unew = ui + step * vnew;
    ok &= Lanes<W>::within(unew, limit);
    scatter<W, pair, T>(a.vn, i, ib, vnew);
    scatter<W, pair, T>(a.un, i, ib, unew);
    scatter<W, pair, T>(a.acc, i, ib, (vnew - vi) * inv_step);
  }
  // zeta = c - P zeta_neighbour, then the update.
  __attribute__((always_inline)) void substitute(const double* coef, int i, int ib, T& xw, T& xt, const double* rec) {
    const T nw = Lanes<W>::at(rec) - (c(coef, kCdP) * xw + c(coef, kCdP + 1) * xt);
    const T nt = Lanes<W>::at(rec + W) - (c(coef, kCdP + 2) * xw + c(coef, kCdP + 3) * xt);
    xw = nw;
    xt = nt;
    update(i, ib, xw, Lanes<W>::at(rec + 2 * W), Lanes<W>::at(rec + 3 * W));
  }
};

// Lanes of the pair's top (0..L) and bottom (L..2L) halves, and back.
template <int L, class T2, class T>
__attribute__((always_inline)) inline T2 join(T top, T bottom) {
  if constexpr (L == 1) return T2{top, bottom};
  else return T2{top[0], top[1], bottom[0], bottom[1]};
}
template <int L, class T, class T2>
__attribute__((always_inline)) inline T half(T2 x, int h) {
  if constexpr (L == 1) return x[h];
  else return T{x[2 * h], x[2 * h + 1]};
}

// The pack's twisted block elimination: from both ends toward node k at once (pairs of nodes in
// 2L lanes), the meeting node k, then outward from k in pairs.
template <int L>
__attribute__((always_inline)) inline int sweep(int n, const double* twin, const double* single, const CentredArgs& args,
                                                 double* rec) {
  typedef typename Lanes<L>::T T;
  typedef typename Lanes<2 * L>::T T2;
  Steps<L, false> one(args);
  Steps<2 * L, true> two(args);
  const int k = centred_meeting_node(n), top = k, extra = (n - 1 - k) - top;
  double* rec_extra = rec + 8 * L * static_cast<std::size_t>(top);  // the extra bottom node's
  auto pair_coef = [&](int j) { return twin + static_cast<std::size_t>(j) * kCdValues * 2 * L; };
  auto pair_rec = [&](int j) { return rec + 8 * L * static_cast<std::size_t>(j); };
  T bw = one.zero, bt = one.zero;
  if (extra) one.eliminate(single + kCdValues * L, n - 1, n - 1, kCdG, bw, bt, rec_extra);
  T2 yw = join<L, T2>(one.zero, bw), yt = join<L, T2>(one.zero, bt);
  for (int j = 0; j < top; ++j) two.eliminate(pair_coef(j), j, n - 1 - extra - j, kCdG, yw, yt, pair_rec(j));
  // The meeting node: zeta_k = z r_k - A c_{k-1} - B c'_{k+1} (A, B in its G and P places).
  {
    const T tw = half<L, T>(yw, 0), tt = half<L, T>(yt, 0);
    bw = half<L, T>(yw, 1);
    bt = half<L, T>(yt, 1);
    const T ui = gather<L, false, T>(args.u, k, k), vi = gather<L, false, T>(args.v, k, k), fi = gather<L, false, T>(args.f, k, k);
    auto c = [&](int v) { return Steps<L, false>::c(single, v); };
    const T rw = one.rhs(single, ui, vi, fi);
    const T xw = (c(kCdS) * rw - (c(kCdG) * tw + c(kCdG + 1) * tt)) - (c(kCdP) * bw + c(kCdP + 1) * bt);
    const T xt = (c(kCdS + 1) * rw - (c(kCdG + 2) * tw + c(kCdG + 3) * tt)) - (c(kCdP + 2) * bw + c(kCdP + 3) * bt);
    one.update(k, k, xw, ui, vi);
    yw = join<L, T2>(xw, xw);
    yt = join<L, T2>(xt, xt);
  }
  for (int j = top - 1; j >= 0; --j) two.substitute(pair_coef(j), j, n - 1 - extra - j, yw, yt, pair_rec(j));
  if (extra) {
    T xw = half<L, T>(yw, 1), xt = half<L, T>(yt, 1);
    one.substitute(single + kCdValues * L, n - 1, n - 1, xw, xt, rec_extra);
  }
  // Bit k: lane k left the limit (at the meeting node, or in a pair's top or bottom half).
  int beyond = 0;
  for (int lane = 0; lane < L; ++lane) {
    bool ok = two.ok[lane] != 0 && two.ok[L + lane] != 0;
    if constexpr (L == 1) ok &= one.ok;
    else ok &= one.ok[lane] != 0;
    beyond |= static_cast<int>(!ok) << lane;
  }
  return beyond;
}

}  // namespace

// Runtime dispatch (GCC target_clones): the four lanes in one AVX2 register (x86-64-v3), or the
// portable baseline in two SSE2 halves; the same IEEE operations either way (no FMA contraction).
#if defined(__x86_64__) && defined(__GNUC__) && !defined(__clang__)
#define CATENARY_SIM_CLONES __attribute__((target_clones("arch=x86-64-v3", "default")))
#else
#define CATENARY_SIM_CLONES
#endif

CATENARY_SIM_CLONES int centred_sweep(const CentredSweep& c) {
  const double *u[2], *v[2];
  double *f[2], *un[2], *vn[2], *acc[2];
  for (int k = 0; k < c.lanes; ++k) {
    u[k] = c.lane[k].u;
    v[k] = c.lane[k].v;
    f[k] = c.lane[k].f;
    un[k] = c.lane[k].u_next;
    vn[k] = c.lane[k].v_next;
    acc[k] = c.lane[k].accel;
  }
  const CentredArgs args{u, v, f, un, vn, acc, c.dt, c.v_ratio, 2.0 / c.beta, c.limit};
  return c.lanes == 2 ? sweep<2>(c.nodes, c.twin, c.single, args, c.record)
                      : sweep<1>(c.nodes, c.twin, c.single, args, c.record);
}

bool centred_sweep_pack(const Model& m, const WireLanes& pack, State& s, int lo, int hi, const double* twin,
                        const double* single) {
  const CentredArrays plane{s.u.data(), s.v.data(), s.work->force.data(), s.work->u_next.data(), s.work->v_next.data(),
                            s.accel.data()};
  CentredSweep c;
  c.lanes = pack.lanes;
  for (int k = 0; k < pack.lanes; ++k) c.lane[k] = plane.at(m.wires[pack.wire[k]].w_dof + lo);  // the range's node 0
  c.nodes = hi - lo + 1;
  c.dt = m.dt;
  c.v_ratio = m.wire_packs->centred_v_ratio;
  c.beta = m.beta;
  c.limit = m.scene.numerics.divergence_limit;
  c.twin = twin;
  c.single = single;
  c.record = s.work->sweep.data() + kCentredRecord * pack.offset;
  return centred_sweep(c) != 0;
}

int centred_sweep_both_planes(const Model& m, std::size_t pk, State& s) {
  const WireLanes& pack = packs_of(m)[pk];
  const LateralModel& lat = *m.lateral;
  LateralState& ls = s.lateral;
  LateralWorkspace& lw = *ls.work;
  const CentredArrays vertical{s.u.data(), s.v.data(), s.work->force.data(), s.work->u_next.data(),
                               s.work->v_next.data(), s.accel.data()};
  const CentredArrays lateral{ls.y.data(), ls.v.data(), lw.f.data(), lw.y_next.data(), lw.v_next.data(),
                              lw.accel.data()};
  CentredSweep c;
  c.lanes = 2;
  c.lane[0] = vertical.at(m.wires[pack.wire[0]].w_dof);
  c.lane[1] = lateral.at(lat.wires[pack.wire[0]].w_dof);
  c.nodes = pack.nodes;
  c.dt = m.dt;  // the lateral plane's too: one substep (LateralModel::centred_joint_twin)
  c.v_ratio = m.wire_packs->centred_v_ratio;
  c.beta = m.beta;
  c.limit = m.scene.numerics.divergence_limit;
  c.twin = lat.centred_joint_twin[pk].data();
  c.single = lat.centred_joint_single[pk].data();
  c.record = lw.sweep.data() + 2 * kCentredRecord * pack.offset;  // (both planes' room: make_lateral_state)
  return centred_sweep(c);
}

bool centred_sweep_pack(const Model& m, const WireLanes& pack, State& s) {
  return centred_sweep_pack(m, pack, s, 0, pack.nodes - 1, pack.centred_twin.data(), pack.centred_single.data());
}

}  // namespace catenary_sim
