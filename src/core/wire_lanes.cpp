// The fused explicit step's kernel. The contact wire's and the messenger's rotations are two
// independent tridiagonal recurrences (eq. 3 condensed): run side by side in the two lanes of a
// vector register, each sweep's latency is paid once for both wires, and the band force, load,
// damping and update (eq. 19-21) ride along in the backward sweep instead of taking passes of their
// own. Reproducibility: only +, -, * of IEEE doubles, in the order of the generic step, no FMA
// contraction (-ffp-contract=off), no reassociation: packed lanes round exactly like scalars, so
// every clone (AVX-512, AVX2, x86-64 baseline) gives the generic step's bits.
#include "wire_lanes.hpp"

#include <cmath>
#include <cstring>

namespace catenary_sim {

void build_wire_packs(Model& m) {
  m.wire_packs.clear();
  m.wire_pack.assign(m.wires.size(), -1);
  m.wire_lane.assign(m.wires.size(), 0);
  m.sweep_size = 0;
  if (m.implicit) return;
  int catenary = 0;
  for (const Wire& w : m.wires) {
    if (w.theta_dof >= 0 || w.nodes() < 2) return;  // rotations as DOFs: the generic step
    catenary += w.nodes();
  }
  if (catenary != m.n_catenary_dof) return;
  for (std::size_t a = 0; a < m.wires.size(); ++a) {
    if (m.wire_pack[a] >= 0) continue;
    WireLanes p;
    p.wire[0] = static_cast<int>(a);
    // A partner on the same stations: the same node range in a moving window, too.
    for (std::size_t b = a + 1; b < m.wires.size() && p.lanes == 1; ++b)
      if (m.wire_pack[b] < 0 && m.wires[b].x == m.wires[a].x) {
        p.wire[1] = static_cast<int>(b);
        p.lanes = 2;
      }
    const int n = m.wires[a].nodes(), L = p.lanes;
    p.nodes = n;
    p.offset = m.sweep_size;
    m.sweep_size += static_cast<std::size_t>(n) * L;
    for (auto* v : {&p.d_ww, &p.d_wt, &p.e_ww, &p.e_wt, &p.e_tw, &p.tt_lower, &p.tt_inv_pivot, &p.load, &p.damping_mass,
                    &p.inv_mass})
      v->assign(static_cast<std::size_t>(n) * L, 0.0);
    for (int k = 0; k < L; ++k) {
      const Wire& w = m.wires[p.wire[k]];
      m.wire_pack[p.wire[k]] = static_cast<int>(m.wire_packs.size());
      m.wire_lane[p.wire[k]] = k;
      for (int i = 0; i < n; ++i) {
        const std::size_t j = static_cast<std::size_t>(i) * L + k;
        p.d_ww[j] = w.d_ww[i];
        p.d_wt[j] = w.d_wt[i];
        p.tt_lower[j] = w.tt_lower[i];
        p.tt_inv_pivot[j] = w.tt_inv_pivot[i];
        p.load[j] = m.load[w.w_dof + i];
        p.damping_mass[j] = m.alpha * m.mass[w.w_dof + i];  // the generic step's alpha * mass[i] * v[i]
        p.inv_mass[j] = m.inv_mass[w.w_dof + i];
        if (i + 1 < n) {
          p.e_ww[j] = w.e_ww[i];
          p.e_wt[j] = w.e_wt[i];
          p.e_tw[j] = w.e_tw[i];
        }
      }
    }
    m.wire_packs.push_back(std::move(p));
  }
}

namespace {

typedef double Double2 __attribute__((vector_size(16)));
typedef long Long2 __attribute__((vector_size(16)));

template <int L>
struct Lane;
template <>
struct Lane<1> {
  using T = double;
  static T load(const double* p, int i) { return p[i]; }
  static T gather(const double* const* p, int i) { return p[0][i]; }
  static void scatter(double* const* p, int i, T x) { p[0][i] = x; }
  static void store(double* p, int i, T x) { p[i] = x; }
  static T splat(double a) { return a; }
  static T pair(const double* a) { return a[0]; }
  struct Inside {
    bool all = true;
    void add(T x, double limit) { all &= std::fabs(x) <= limit; }
    bool ok() const { return all; }
  };
};
template <>
struct Lane<2> {
  using T = Double2;
  static T load(const double* p, int i) {
    T x;
    std::memcpy(&x, p + 2 * i, sizeof x);
    return x;
  }
  static T gather(const double* const* p, int i) { return T{p[0][i], p[1][i]}; }
  static void scatter(double* const* p, int i, T x) {
    p[0][i] = x[0];
    p[1][i] = x[1];
  }
  static void store(double* p, int i, T x) { std::memcpy(p + 2 * i, &x, sizeof x); }
  static T splat(double a) { return T{a, a}; }
  static T pair(const double* a) { return T{a[0], a[1]}; }
  struct Inside {
    Long2 all = {-1, -1};
    // |x| <= limit, NaN outside: as the generic step's !(fabs(un) <= limit).
    void add(T x, double limit) { all &= (x <= splat(limit)) & (x >= splat(-limit)); }
    bool ok() const { return all[0] && all[1]; }
  };
};

template <int L>
__attribute__((always_inline)) inline bool sweep(const PackSweep& a) {
  using V = Lane<L>;
  using T = typename V::T;
  const WireLanes& p = *a.pack;
  const double *dww = p.d_ww.data(), *dwt = p.d_wt.data(), *eww = p.e_ww.data(), *ewt = p.e_wt.data(),
               *etw = p.e_tw.data(), *load = p.load.data(), *am = p.damping_mass.data(), *im = p.inv_mass.data();
  const double *lower = a.lower, *ip = a.inv_pivot;
  double* th = a.theta;
  const T beta = V::splat(a.beta), dt = V::splat(a.dt);
  const int lo = a.lo, hi = a.hi;
  const T ww_lo = V::pair(a.ww_lo), wt_lo = V::pair(a.wt_lo), ww_hi = V::pair(a.ww_hi), wt_hi = V::pair(a.wt_hi);
  auto z_at = [&](int i) { return V::gather(a.u, i) + beta * V::gather(a.v, i); };

  // Forward sweep: K_tt theta = -K_tw z, the L of LDL^T (condensed_band_force's first loop).
  T zp = z_at(lo), zc = z_at(lo + 1);
  T y = -wt_lo * zp - V::load(etw, lo) * zc;
  V::store(th, lo, y);
  for (int i = lo + 1; i < hi; ++i) {
    const T zn = z_at(i + 1);
    const T r = (-V::load(dwt, i) * zc - V::load(etw, i) * zn) - V::load(ewt, i - 1) * zp;
    y = r - V::load(lower, i) * y;
    V::store(th, i, y);
    zp = zc;
    zc = zn;
  }
  y = (-wt_hi * zc - V::load(ewt, hi - 1) * zp) - V::load(lower, hi) * y;

  // Backward sweep: D^-1 and L^T, and behind it node j = i + 1 is complete: its band force
  // f_j = (load - alpha m v - A_j) - B_j (band_w_rows' order), and the update of eq. 20-21.
  typename V::Inside inside;
  auto update = [&](int j, T f, T u, T v) {
    const T acc = V::load(im, j) * f;
    const T vn = v + dt * acc;
    const T un = u + dt * vn;
    inside.add(un, a.limit);
    V::scatter(a.accel, j, acc);
    V::scatter(a.v_next, j, vn);
    V::scatter(a.u_next, j, un);
  };
  T th1 = y * V::load(ip, hi);  // theta_{i+1}
  V::store(th, hi, th1);
  T u1 = V::gather(a.u, hi), v1 = V::gather(a.v, hi);
  T z1 = u1 + beta * v1;
  T th2, z2;  // theta_{i+2}, z_{i+2}
  {
    const int i = hi - 1;
    const T th0 = V::load(th, i) * V::load(ip, i) - V::load(lower, i + 1) * th1;
    V::store(th, i, th0);
    const T u0 = V::gather(a.u, i), v0 = V::gather(a.v, i), z0 = u0 + beta * v0;
    const T A = ((ww_hi * z1 + wt_hi * th1) + V::load(eww, i) * z0) + V::load(etw, i) * th0;
    update(hi, (V::load(load, hi) - V::load(am, hi) * v1) - A, u1, v1);
    th2 = th1;
    th1 = th0;
    z2 = z1;
    z1 = z0;
    u1 = u0;
    v1 = v0;
  }
  for (int i = hi - 2; i >= lo; --i) {
    const T th0 = V::load(th, i) * V::load(ip, i) - V::load(lower, i + 1) * th1;
    V::store(th, i, th0);
    const T u0 = V::gather(a.u, i), v0 = V::gather(a.v, i), z0 = u0 + beta * v0;
    const int j = i + 1;
    const T A = ((V::load(dww, j) * z1 + V::load(dwt, j) * th1) + V::load(eww, i) * z0) + V::load(etw, i) * th0;
    const T B = V::load(eww, j) * z2 + V::load(ewt, j) * th2;
    update(j, ((V::load(load, j) - V::load(am, j) * v1) - A) - B, u1, v1);
    th2 = th1;
    th1 = th0;
    z2 = z1;
    z1 = z0;
    u1 = u0;
    v1 = v0;
  }
  const T A = ww_lo * z1 + wt_lo * th1;
  const T B = V::load(eww, lo) * z2 + V::load(ewt, lo) * th2;
  update(lo, ((V::load(load, lo) - V::load(am, lo) * v1) - A) - B, u1, v1);
  return !inside.ok();
}

}  // namespace

#if defined(__x86_64__) && defined(__GNUC__) && !defined(__clang__)
#define CATENARY_SIM_CLONES __attribute__((target_clones("avx512f", "avx2", "default")))
#else
#define CATENARY_SIM_CLONES
#endif

CATENARY_SIM_CLONES bool sweep_pack(const PackSweep& a) {
  return a.pack->lanes == 2 ? sweep<2>(a) : sweep<1>(a);
}

// GCC's resolver takes the clone of the highest priority the CPU supports: AVX-512F over AVX2 over
// the baseline. The benchmark prints this beside the figures; gdb on sweep_pack shows the symbol
// of the clone taken (BENCHMARKS.md).
const char* sweep_pack_isa() {
#if defined(__x86_64__) && defined(__GNUC__) && !defined(__clang__)
  __builtin_cpu_init();
  if (__builtin_cpu_supports("avx512f")) return "avx512f";
  if (__builtin_cpu_supports("avx2")) return "avx2";
#endif
  return "default";
}

}  // namespace catenary_sim
