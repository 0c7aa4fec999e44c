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
    p.coef.assign(static_cast<std::size_t>(n) * WireLanes::kCoefficients * L, 0.0);
    p.factors.assign(static_cast<std::size_t>(n) * 2 * L, 0.0);
    for (int k = 0; k < L; ++k) {
      const Wire& w = m.wires[p.wire[k]];
      m.wire_pack[p.wire[k]] = static_cast<int>(m.wire_packs.size());
      m.wire_lane[p.wire[k]] = k;
      for (int i = 0; i < n; ++i) {
        double* c = p.coef.data() + static_cast<std::size_t>(i) * WireLanes::kCoefficients * L + k;
        c[WireLanes::kDww * L] = w.d_ww[i];
        c[WireLanes::kDwt * L] = w.d_wt[i];
        if (i + 1 < n) {
          c[WireLanes::kEww * L] = w.e_ww[i];
          c[WireLanes::kEwt * L] = w.e_wt[i];
          c[WireLanes::kEtw * L] = w.e_tw[i];
        }
        c[WireLanes::kLoad * L] = m.load[w.w_dof + i];
        c[WireLanes::kDampingMass * L] = m.alpha * m.mass[w.w_dof + i];  // the generic step's alpha * mass[i] * v[i]
        c[WireLanes::kInvMass * L] = m.inv_mass[w.w_dof + i];
        p.factors[(static_cast<std::size_t>(i) * 2 + 0) * L + k] = w.tt_lower[i];
        p.factors[(static_cast<std::size_t>(i) * 2 + 1) * L + k] = w.tt_inv_pivot[i];
      }
    }
    m.wire_packs.push_back(std::move(p));
  }
  m.dof_sweep_force.assign(m.n_catenary_dof, 0);
  m.dof_sweep_z.assign(m.n_catenary_dof, 0);
  for (const WireLanes& p : m.wire_packs)
    for (int k = 0; k < p.lanes; ++k)
      for (int i = 0; i < p.nodes; ++i) {
        const std::size_t r = kSweepRecord * p.offset + static_cast<std::size_t>(i) * kSweepRecord * p.lanes + k;
        m.dof_sweep_force[m.wires[p.wire[k]].w_dof + i] = static_cast<int>(r + kRecForce * p.lanes);
        m.dof_sweep_z[m.wires[p.wire[k]].w_dof + i] = static_cast<int>(r + kRecZ * p.lanes);
      }
}

namespace {

typedef double Double2 __attribute__((vector_size(16)));
typedef long Long2 __attribute__((vector_size(16)));

template <int L>
struct Lane;
// One wire: plain doubles.
template <>
struct Lane<1> {
  using T = double;
  static T at(const double* p, std::ptrdiff_t k) { return p[k]; }
  static void put(double* p, std::ptrdiff_t k, T x) { p[k] = x; }
  static T gather(const double* p, std::ptrdiff_t, int i) { return p[i]; }
  static void gather2(const double* p, std::ptrdiff_t, int i, T& x0, T& x1) {
    x0 = p[i];
    x1 = p[i + 1];
  }
  static T splat(double a) { return a; }
  static T pair(const double* a) { return a[0]; }
  static T abs(T x) { return std::fabs(x); }
  using Mask = bool;
  static Mask all() { return true; }
  // |x| <= limit, NaN outside: the generic step's !(fabs(un) <= limit) (limit >= 0).
  static Mask inside(Mask m, T x, T above, T below) { return m & (x <= above) & (x >= below); }
  static bool ok(Mask m) { return m; }
  // Eq. 20-21 at node i given its acceleration (the velocity first, then the displacement).
  template <bool Acc = true>  // Acc false: the acceleration is not kept (the lateral plane needs none)
  static void update(const double* u, const double* v, double* un, double* vn, double* acc, std::ptrdiff_t, int i,
                     T a, T dt, Mask& ok, T above, T below) {
    const T vi = v[i] + dt * a, ui = u[i] + dt * vi;
    ok = inside(ok, ui, above, below);
    if constexpr (Acc) acc[i] = a;
    vn[i] = vi;
    un[i] = ui;
  }
  template <bool Acc = true>
  static void update2(const double* u, const double* v, double* un, double* vn, double* acc, std::ptrdiff_t d, int i,
                      T a0, T a1, T dt, Mask& ok, T above, T below) {
    update<Acc>(u, v, un, vn, acc, d, i, a0, dt, ok, above, below);
    update<Acc>(u, v, un, vn, acc, d, i + 1, a1, dt, ok, above, below);
  }
};
// Two wires in the two lanes. Interleaved arrays (coefficients, factors, the sweep's record) load
// whole; the state's arrays hold each wire's nodes in a row, the second wire `d` entries after the
// first: they are read in blocks of two nodes and shuffled into lanes, and updated per wire, two
// nodes to a register, so that nothing is shuffled back.
template <>
struct Lane<2> {
  using T = Double2;
  static T at(const double* p, std::ptrdiff_t k) {
    T x;
    std::memcpy(&x, p + 2 * k, sizeof x);
    return x;
  }
  static void put(double* p, std::ptrdiff_t k, T x) { std::memcpy(p + 2 * k, &x, sizeof x); }
  static T gather(const double* p, std::ptrdiff_t d, int i) { return T{p[i], p[i + d]}; }
  // Nodes i and i + 1 of both wires: two loads and two shuffles instead of four scalar loads.
  static void gather2(const double* p, std::ptrdiff_t d, int i, T& x0, T& x1) {
    const T a = row(p + i), b = row(p + i + d);
    x0 = __builtin_shuffle(a, b, Long2{0, 2});
    x1 = __builtin_shuffle(a, b, Long2{1, 3});
  }
  static T splat(double a) { return T{a, a}; }
  static T pair(const double* a) { return T{a[0], a[1]}; }
  // |x| by clearing the sign bits: what fabs does, lane by lane.
  static T abs(T x) {
    Long2 b;
    std::memcpy(&b, &x, sizeof b);
    b &= Long2{0x7fffffffffffffffL, 0x7fffffffffffffffL};
    std::memcpy(&x, &b, sizeof x);
    return x;
  }
  using Mask = Long2;
  static Mask all() { return Long2{-1, -1}; }
  static Mask inside(Mask m, T x, T above, T below) { return m & (x <= above) & (x >= below); }
  static bool ok(Mask m) { return m[0] && m[1]; }
  static T row(const double* p) {
    T x;
    std::memcpy(&x, p, sizeof x);
    return x;
  }
  static void put_row(double* p, T x) { std::memcpy(p, &x, sizeof x); }
  template <bool Acc = true>  // Acc false: the acceleration is not kept (the lateral plane needs none)
  static void update(const double* u, const double* v, double* un, double* vn, double* acc, std::ptrdiff_t d, int i,
                     T a, T dt, Mask& ok, T above, T below) {
    const T vi = gather(v, d, i) + dt * a, ui = gather(u, d, i) + dt * vi;
    ok = inside(ok, ui, above, below);
    if constexpr (Acc) {
      acc[i] = a[0];
      acc[i + d] = a[1];
    }
    vn[i] = vi[0];
    vn[i + d] = vi[1];
    un[i] = ui[0];
    un[i + d] = ui[1];
  }
  // Nodes i and i + 1 given their accelerations (both wires in lanes): per wire, two nodes a register.
  template <bool Acc = true>
  static void update2(const double* u, const double* v, double* un, double* vn, double* acc, std::ptrdiff_t d, int i,
                      T a0, T a1, T dt, Mask& ok, T above, T below) {
    const T aa = __builtin_shuffle(a0, a1, Long2{0, 2}), ab = __builtin_shuffle(a0, a1, Long2{1, 3});
    const T va = row(v + i) + dt * aa, vb = row(v + i + d) + dt * ab;
    const T ua = row(u + i) + dt * va, ub = row(u + i + d) + dt * vb;
    ok = inside(inside(ok, ua, above, below), ub, above, below);
    if constexpr (Acc) {
      put_row(acc + i, aa);
      put_row(acc + i + d, ab);
    }
    put_row(vn + i, va);
    put_row(vn + i + d, vb);
    put_row(un + i, ua);
    put_row(un + i + d, ub);
  }
};

template <int L, bool Plane, bool Drag>
__attribute__((always_inline)) inline bool sweep(const PackSweep& a) {
  using V = Lane<L>;
  using T = typename V::T;
  using W = WireLanes;
  constexpr int NC = W::kCoefficients, NR = kSweepRecord;
  // Few base pointers (one coefficient record per node, one sweep record per node, the second
  // wire at an offset in the state's arrays), all in restrict locals, so that they stay in
  // registers and no store can be taken to change them.
  const double* __restrict coef = a.pack->coef.data();
  const double* __restrict fac = a.factors;
  double* __restrict rec = a.record;
  const double *__restrict u = a.u[0], *__restrict v = a.v[0];
  double *__restrict un = a.u_next[0], *__restrict vn = a.v_next[0], *__restrict acc = a.accel[0];
  const std::ptrdiff_t d = L == 2 ? a.u[1] - a.u[0] : 0;
  // The wind's arrays: second lanes as far from the first as the state's (per-wire rows of one
  // array of the lateral plane's DOFs).
  const double* __restrict wind = a.wind[0];
  const double* __restrict cw = a.drag_coefficient[0];
  const double* __restrict plane = a.plane;
  auto c = [&](int i, int k) __attribute__((always_inline)) { return V::at(coef, static_cast<std::ptrdiff_t>(i) * NC + k); };
  // The load, alpha m and 1/m of node i: the pack's, or the lateral plane's own.
  auto load = [&](int i) __attribute__((always_inline)) {
    if constexpr (Plane) return V::at(plane, static_cast<std::ptrdiff_t>(i) * 3 + 0);
    else return c(i, W::kLoad);
  };
  auto damping = [&](int i) __attribute__((always_inline)) {
    if constexpr (Plane) return V::at(plane, static_cast<std::ptrdiff_t>(i) * 3 + 1);
    else return c(i, W::kDampingMass);
  };
  auto inv_mass = [&](int i) __attribute__((always_inline)) {
    if constexpr (Plane) return V::at(plane, static_cast<std::ptrdiff_t>(i) * 3 + 2);
    else return c(i, W::kInvMass);
  };
  auto lower = [&](int i) __attribute__((always_inline)) { return V::at(fac, 2 * static_cast<std::ptrdiff_t>(i)); };
  auto ip = [&](int i) __attribute__((always_inline)) { return V::at(fac, 2 * static_cast<std::ptrdiff_t>(i) + 1); };
  auto get = [&](int i, int k) __attribute__((always_inline)) { return V::at(rec, static_cast<std::ptrdiff_t>(i) * NR + k); };
  auto set = [&](int i, int k, T x) __attribute__((always_inline)) { V::put(rec, static_cast<std::ptrdiff_t>(i) * NR + k, x); };
  const T beta = V::splat(a.beta), dt = V::splat(a.dt);
  const int lo = a.lo, hi = a.hi;
  const T ww_lo = V::pair(a.ww_lo), wt_lo = V::pair(a.wt_lo), ww_hi = V::pair(a.ww_hi), wt_hi = V::pair(a.wt_hi);

  // Forward: z = u + beta v and the load less the mass-proportional damping, load - alpha m v
  // (assemble_force's init), kept for the backward sweep; and K_tt theta = -K_tw z, the L of
  // LDL^T (condensed_band_force's first loop).
  auto start = [&](int i, T ui, T vi) __attribute__((always_inline)) {
    const T z = ui + beta * vi;
    set(i, kRecZ, z);
    if constexpr (Drag) {
      const T vr = V::gather(wind, d, i) - vi;
      set(i, kRecInit, (load(i) - damping(i) * vi) + V::gather(cw, d, i) * vr * V::abs(vr));
    } else {
      set(i, kRecInit, load(i) - damping(i) * vi);
    }
    return z;
  };
  T zp = start(lo, V::gather(u, d, lo), V::gather(v, d, lo));
  T zc = start(lo + 1, V::gather(u, d, lo + 1), V::gather(v, d, lo + 1));
  T y = -wt_lo * zp - c(lo, W::kEtw) * zc;
  set(lo, kRecTheta, y);
  auto forward = [&](int i, T zn) __attribute__((always_inline)) {
    const T r = (-c(i, W::kDwt) * zc - c(i, W::kEtw) * zn) - c(i - 1, W::kEwt) * zp;
    y = r - lower(i) * y;
    set(i, kRecTheta, y);
    zp = zc;
    zc = zn;
  };
  int i = lo + 1;
  for (; i + 1 < hi; i += 2) {  // two nodes a turn: u, v of both wires loaded as blocks
    T u0, u1, v0, v1;
    V::gather2(u, d, i + 1, u0, u1);
    V::gather2(v, d, i + 1, v0, v1);
    forward(i, start(i + 1, u0, v0));
    forward(i + 1, start(i + 2, u1, v1));
  }
  if (i < hi) forward(i, start(i + 1, V::gather(u, d, i + 1), V::gather(v, d, i + 1)));
  y = (-wt_hi * zc - c(hi - 1, W::kEwt) * zp) - lower(hi) * y;

  // Backward: D^-1 and L^T, and behind it node j = i + 1 is complete: its band force
  // f_j = (load - alpha m v - A_j) - B_j (band_w_rows' order), kept for the nodes with point
  // forces, its acceleration, and the update of eq. 20-21.
  typename V::Mask ok = V::all();
  const T above = V::splat(a.limit), below = V::splat(-a.limit);
  T th1 = y * ip(hi);  // theta_{i+1}, theta_{i+2}, z likewise
  set(hi, kRecTheta, th1);
  T z1 = get(hi, kRecZ), th2, z2;
  auto accel = [&](int j, T f) __attribute__((always_inline)) {
    set(j, kRecForce, f);
    return inv_mass(j) * f;
  };
  auto backward = [&](int i) __attribute__((always_inline)) {
    const T th0 = get(i, kRecTheta) * ip(i) - lower(i + 1) * th1;
    set(i, kRecTheta, th0);
    const T z0 = get(i, kRecZ);
    const int j = i + 1;
    const T A = ((c(j, W::kDww) * z1 + c(j, W::kDwt) * th1) + c(i, W::kEww) * z0) + c(i, W::kEtw) * th0;
    const T B = c(j, W::kEww) * z2 + c(j, W::kEwt) * th2;
    const T f = (get(j, kRecInit) - A) - B;
    th2 = th1;
    th1 = th0;
    z2 = z1;
    z1 = z0;
    return accel(j, f);
  };
  {
    const int i = hi - 1;
    const T th0 = get(i, kRecTheta) * ip(i) - lower(i + 1) * th1;
    set(i, kRecTheta, th0);
    const T z0 = get(i, kRecZ);
    const T A = ((ww_hi * z1 + wt_hi * th1) + c(i, W::kEww) * z0) + c(i, W::kEtw) * th0;
    V::template update<!Plane>(u, v, un, vn, acc, d, hi, accel(hi, get(hi, kRecInit) - A), dt, ok, above, below);
    th2 = th1;
    th1 = th0;
    z2 = z1;
    z1 = z0;
  }
  i = hi - 2;
  for (; i - 1 >= lo; i -= 2) {  // nodes i + 1 and i complete: updated as a block
    const T a1 = backward(i);
    const T a0 = backward(i - 1);
    V::template update2<!Plane>(u, v, un, vn, acc, d, i, a0, a1, dt, ok, above, below);
  }
  if (i == lo) V::template update<!Plane>(u, v, un, vn, acc, d, lo + 1, backward(lo), dt, ok, above, below);
  const T A = ww_lo * z1 + wt_lo * th1;
  const T B = c(lo, W::kEww) * z2 + c(lo, W::kEwt) * th2;
  V::template update<!Plane>(u, v, un, vn, acc, d, lo, accel(lo, (get(lo, kRecInit) - A) - B), dt, ok, above, below);
  return !V::ok(ok);
}

}  // namespace

#if defined(__x86_64__) && defined(__GNUC__) && !defined(__clang__)
#define CATENARY_SIM_CLONES __attribute__((target_clones("arch=x86-64-v4", "arch=x86-64-v3", "default")))
#else
#define CATENARY_SIM_CLONES
#endif

CATENARY_SIM_CLONES bool sweep_pack(const PackSweep& a) {
  if (a.plane) {
    if (a.wind[0]) return a.pack->lanes == 2 ? sweep<2, true, true>(a) : sweep<1, true, true>(a);
    return a.pack->lanes == 2 ? sweep<2, true, false>(a) : sweep<1, true, false>(a);
  }
  return a.pack->lanes == 2 ? sweep<2, false, false>(a) : sweep<1, false, false>(a);
}

// GCC's resolver takes the clone of the highest priority the CPU supports: x86-64-v4 (AVX-512
// with VL, BW, DQ, CD) over x86-64-v3 (AVX2) over the baseline; this asks the same question. The
// benchmark prints it beside the figures; gdb on sweep_pack shows the clone taken (BENCHMARKS.md).
const char* sweep_pack_isa() {
#if defined(__x86_64__) && defined(__GNUC__) && !defined(__clang__)
  __builtin_cpu_init();
  if (__builtin_cpu_supports("x86-64-v4")) return "x86-64-v4";
  if (__builtin_cpu_supports("x86-64-v3")) return "x86-64-v3";
#endif
  return "default";
}

bool setup_pack_sweep(const WireLanes& p, const std::vector<Wire>& wires, const std::vector<WireWindow>* windows,
                      const double* window_factors, double* records, const double* x, const double* v, double* x_next,
                      double* v_next, double* accel, PackSweep& a) {
  const bool windowed = windows != nullptr;
  const WireWindow none;
  const WireWindow& ww0 = windowed ? (*windows)[p.wire[0]] : none;
  a.pack = &p;
  a.lo = windowed ? ww0.lo : 0;
  a.hi = windowed ? ww0.hi : p.nodes - 1;
  if (a.hi < a.lo) return false;
  a.factors = windowed ? window_factors + 2 * p.offset : p.factors.data();
  for (int k = 0; k < p.lanes; ++k) {
    const Wire& w = wires[p.wire[k]];
    const WireWindow& ww = windowed ? (*windows)[p.wire[k]] : none;
    // condensed_band_force's dww_at/dwt_at at the ends (x - 0.0 is x: no change without a cut)
    a.ww_lo[k] = w.d_ww[a.lo] - (windowed ? ww.lo_ww : 0.0);
    a.wt_lo[k] = w.d_wt[a.lo] - (windowed ? ww.lo_wt : 0.0);
    a.ww_hi[k] = w.d_ww[a.hi] - (windowed ? ww.hi_ww : 0.0);
    a.wt_hi[k] = w.d_wt[a.hi] - (windowed ? ww.hi_wt : 0.0);
    a.u[k] = x + w.w_dof;
    a.v[k] = v + w.w_dof;
    a.u_next[k] = x_next + w.w_dof;
    a.v_next[k] = v_next + w.w_dof;
    a.accel[k] = accel + w.w_dof;
  }
  a.record = records + kSweepRecord * p.offset;
  return true;
}

}  // namespace catenary_sim
