// The fused explicit step's kernel. The contact wire's and the messenger's rotations are two
// independent tridiagonal recurrences (eq. 3 condensed): run side by side in the two lanes of a
// vector register, each sweep's latency is paid once for both wires, and the band force, load,
// damping and update (eq. 19-21) ride along in the backward sweep instead of taking passes of their
// own. A wire with no partner fills both lanes on its own, swept from both ends at once
// (TwistedLone). Reproducibility: only +, -, * of IEEE doubles, in the order of the generic step, no FMA
// contraction (-ffp-contract=off), no reassociation: packed lanes round exactly like scalars, so
// every clone (AVX-512, AVX2, x86-64 baseline) gives the generic step's bits.
#include "engine/wire_lanes.hpp"

#include <cmath>
#include <cstring>

#include "catenary_sim/core/model/lateral.hpp"
#include "engine/lateral_workspace.hpp"
#include "engine/step_workspace.hpp"
#include "model/twisted_half.hpp"

namespace catenary_sim {

namespace {

typedef double Double2 __attribute__((vector_size(16)));
typedef long Long2 __attribute__((vector_size(16)));
typedef double Double4 __attribute__((vector_size(32)));

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

// Where one pack's sweep reads and writes: one plane, L lanes (PackSweep: the vertical plane's
// pack, or the lateral plane's on the same band with its own load, damping, inverse mass and wind).
template <int L, bool Plane, bool Drag>
struct OnePlane {
  using V = Lane<L>;
  using T = typename V::T;
  using Mask = typename V::Mask;
  static constexpr int NC = WireLanes::kCoefficients, NR = kSweepRecord;
  // Few base pointers (one coefficient record per node, one sweep record per node, the second
  // wire at an offset in the state's arrays), so that they stay in registers.
  const double* coef;
  const double* fac;
  double* rec;
  const double *u, *v;
  double *un, *vn, *acc;
  std::ptrdiff_t d;
  // The wind's speed: second lane as far from the first as the state's (per-wire rows of one
  // array of the lateral plane's DOFs).
  const double *wind, *plane;
  T beta, dt, ww_lo, wt_lo, ww_hi, wt_hi, above, below;
  int lo, hi;

  explicit OnePlane(const PackSweep& a)
      : coef(a.pack->coef.data()), fac(a.factors), rec(a.record), u(a.u[0]), v(a.v[0]), un(a.u_next[0]),
        vn(a.v_next[0]), acc(a.accel[0]), d(L == 2 ? a.u[1] - a.u[0] : 0), wind(a.wind[0]),
        plane(a.plane), beta(V::splat(a.beta)), dt(V::splat(a.dt)),
        ww_lo(V::pair(a.ww_lo)), wt_lo(V::pair(a.wt_lo)), ww_hi(V::pair(a.ww_hi)), wt_hi(V::pair(a.wt_hi)),
        above(V::splat(a.limit)), below(V::splat(-a.limit)), lo(a.lo), hi(a.hi) {}

  __attribute__((always_inline)) T c(int i, int k) const { return V::at(coef, static_cast<std::ptrdiff_t>(i) * NC + k); }
  __attribute__((always_inline)) T lower(int i) const { return V::at(fac, 2 * static_cast<std::ptrdiff_t>(i)); }
  __attribute__((always_inline)) T ip(int i) const { return V::at(fac, 2 * static_cast<std::ptrdiff_t>(i) + 1); }
  __attribute__((always_inline)) T get(int i, int k) const { return V::at(rec, static_cast<std::ptrdiff_t>(i) * NR + k); }
  __attribute__((always_inline)) void set(int i, int k, T x) { V::put(rec, static_cast<std::ptrdiff_t>(i) * NR + k, x); }
  // The load, alpha m and 1/m of node i: the pack's, or the lateral plane's own.
  __attribute__((always_inline)) T plane_value(int i, int k, int own) const {
    if constexpr (Plane) return V::at(plane, static_cast<std::ptrdiff_t>(i) * kPlaneValues + own);
    else return c(i, k);
  }
  __attribute__((always_inline)) T inv_mass(int i) const { return plane_value(i, WireLanes::kInvMass, kPlaneInvMass); }
  // The load less the mass-proportional damping, load - alpha m v (assemble_force's init), and
  // with wind its drag: (load - alpha m v) + (cw (W - v)) |W - v|.
  __attribute__((always_inline)) T init(int i, T vi) const {
    const T f = plane_value(i, WireLanes::kLoad, kPlaneLoad) - plane_value(i, WireLanes::kDampingMass, kPlaneDamping) * vi;
    if constexpr (Drag) {
      const T vr = V::gather(wind, d, i) - vi;
      return f + V::at(plane, static_cast<std::ptrdiff_t>(i) * kPlaneValues + kPlaneDrag) * vr * V::abs(vr);
    } else {
      return f;
    }
  }
  __attribute__((always_inline)) void state(int i, T& ui, T& vi) const {
    ui = V::gather(u, d, i);
    vi = V::gather(v, d, i);
  }
  // Nodes i and i + 1: u, v of both wires loaded as blocks.
  __attribute__((always_inline)) void state2(int i, T& u0, T& u1, T& v0, T& v1) const {
    V::gather2(u, d, i, u0, u1);
    V::gather2(v, d, i, v0, v1);
  }
  // Eq. 20-21 at node i, and at nodes i and i + 1 as a block.
  __attribute__((always_inline)) void update(int i, T a, Mask& ok) {
    V::template update<!Plane>(u, v, un, vn, acc, d, i, a, dt, ok, above, below);
  }
  __attribute__((always_inline)) void update2(int i, T a0, T a1, Mask& ok) {
    V::template update2<!Plane>(u, v, un, vn, acc, d, i, a0, a1, dt, ok, above, below);
  }
  static Mask all() { return V::all(); }
  static bool inside(Mask m) { return V::ok(m); }
};

// One pack's sweep (eq. 19-21 with the rotations condensed) on what Access reads and writes
// (OnePlane, TwoPlanes), as the steps the driver below takes along the nodes.
template <class Access>
struct Sweeper : Access {
  using T = typename Access::T;
  using W = WireLanes;
  using Access::c;
  using Access::get;
  using Access::ip;
  using Access::lower;
  using Access::set;
  T zp, zc, y;              // forward: z at the last two nodes, the L sweep's value
  T th1, th2, z1, z2, v1;   // backward: theta and z at the two nodes after the current one, v at the next
  typename Access::Mask ok;  // every new displacement inside the limit so far

  using Access::Access;

  // Forward: z = u + beta v, and K_tt theta = -K_tw z, the L of LDL^T (condensed_band_force's
  // first loop). z and the load less the damping (init) are not kept: the backward sweep computes
  // them again from the u and v its update reads anyway, the same operations on the same values
  // (the same bits), which is cheaper than a record's round trip through memory on a long line.
  __attribute__((always_inline)) T z_of(T ui, T vi) const { return ui + this->beta * vi; }
  __attribute__((always_inline)) T start(int, T ui, T vi) { return z_of(ui, vi); }
  __attribute__((always_inline)) void forward(int i, T zn) {
    const T r = (-c(i, W::kDwt) * zc - c(i, W::kEtw) * zn) - c(i - 1, W::kEwt) * zp;
    y = r - lower(i) * y;
    set(i, kRecTheta, y);
    zp = zc;
    zc = zn;
  }
  __attribute__((always_inline)) void forward_begin() {
    const int lo = this->lo;
    T u0, v0, u1, v1;
    this->state(lo, u0, v0);
    this->state(lo + 1, u1, v1);
    zp = start(lo, u0, v0);
    zc = start(lo + 1, u1, v1);
    y = -this->wt_lo * zp - c(lo, W::kEtw) * zc;
    set(lo, kRecTheta, y);
  }
  __attribute__((always_inline)) void forward_two(int i) {
    T u0, u1, v0, v1;
    this->state2(i + 1, u0, u1, v0, v1);
    forward(i, start(i + 1, u0, v0));
    forward(i + 1, start(i + 2, u1, v1));
  }
  __attribute__((always_inline)) void forward_one(int i) {
    T ui, vi;
    this->state(i + 1, ui, vi);
    forward(i, start(i + 1, ui, vi));
  }
  __attribute__((always_inline)) void forward_end() {
    y = (-this->wt_hi * zc - c(this->hi - 1, W::kEwt) * zp) - lower(this->hi) * y;
  }

  // Backward: D^-1 and L^T, and behind it node j = i + 1 is complete: its band force
  // f_j = (load - alpha m v - A_j) - B_j (band_w_rows' order), kept for the nodes with point
  // forces, its acceleration, and the update of eq. 20-21.
  __attribute__((always_inline)) T accel(int j, T f) {
    set(j, kRecForce, f);
    return this->inv_mass(j) * f;
  }
  // z at node i from the state, and v there kept for the node's init one node on.
  __attribute__((always_inline)) T z_at(int i, T& vi) const {
    T ui;
    this->state(i, ui, vi);
    return z_of(ui, vi);
  }
  __attribute__((always_inline)) T backward(int i) {
    T v0;
    const T z0 = z_at(i, v0);
    return backward(i, z0, v0);
  }
  // Node i's z0 and v0 given (loaded with a neighbour's as a block).
  __attribute__((always_inline)) T backward(int i, T z0, T v0) {
    const T th0 = get(i, kRecTheta) * ip(i) - lower(i + 1) * th1;
    const int j = i + 1;
    const T A = ((c(j, W::kDww) * z1 + c(j, W::kDwt) * th1) + c(i, W::kEww) * z0) + c(i, W::kEtw) * th0;
    const T B = c(j, W::kEww) * z2 + c(j, W::kEwt) * th2;
    const T f = (this->init(j, v1) - A) - B;
    th2 = th1;
    th1 = th0;
    z2 = z1;
    z1 = z0;
    v1 = v0;
    return accel(j, f);
  }
  __attribute__((always_inline)) void backward_begin() {
    const int hi = this->hi, i = hi - 1;
    ok = Access::all();
    th1 = y * ip(hi);  // theta_{i+1}, theta_{i+2}, z likewise
    T v_hi, v0;
    z1 = z_at(hi, v_hi);
    const T th0 = get(i, kRecTheta) * ip(i) - lower(i + 1) * th1;
    const T z0 = z_at(i, v0);
    const T A = ((this->ww_hi * z1 + this->wt_hi * th1) + c(i, W::kEww) * z0) + c(i, W::kEtw) * th0;
    this->update(hi, accel(hi, this->init(hi, v_hi) - A), ok);
    th2 = th1;
    th1 = th0;
    z2 = z1;
    z1 = z0;
    v1 = v0;
  }
  // Nodes i + 1 and i complete: updated as a block.
  __attribute__((always_inline)) void backward_two(int i) {
    T u0, u1, v0, v1;  // nodes i - 1 and i, loaded as blocks
    this->state2(i - 1, u0, u1, v0, v1);
    const T a1 = backward(i, z_of(u1, v1), v1);
    const T a0 = backward(i - 1, z_of(u0, v0), v0);
    this->update2(i, a0, a1, ok);
  }
  __attribute__((always_inline)) void backward_one() { this->update(this->lo + 1, backward(this->lo), ok); }
  // Node lo (then `ok` tells whether every new displacement is inside the limit).
  __attribute__((always_inline)) void backward_end() {
    const int lo = this->lo;
    const T A = this->ww_lo * z1 + this->wt_lo * th1;
    const T B = c(lo, W::kEww) * z2 + c(lo, W::kEwt) * th2;
    this->update(lo, accel(lo, (this->init(lo, v1) - A) - B), ok);
  }
};

// Runs a sweep over nodes lo..hi (hi >= lo + 1).
template <class S>
__attribute__((always_inline)) inline void drive(S& s) {
  const int lo = s.lo, hi = s.hi;
  s.forward_begin();
  int i = lo + 1;
  for (; i + 1 < hi; i += 2) s.forward_two(i);
  if (i < hi) s.forward_one(i);
  s.forward_end();
  s.backward_begin();
  i = hi - 2;
  for (; i - 1 >= lo; i -= 2) s.backward_two(i);
  if (i == lo) s.backward_one();
  s.backward_end();
}

template <int L, bool Plane, bool Drag>
__attribute__((always_inline)) inline bool sweep(const PackSweep& a) {
  Sweeper<OnePlane<L, Plane, Drag>> s(a);
  drive(s);
  return !OnePlane<L, Plane, Drag>::inside(s.ok);  // some new displacement beyond the limit or NaN
}

// A lone wire in both lanes (Wire::twisted): station k is node k in lane 0 and node
// top - k in lane 1, whose coefficients are the mirrored wire's (its rotations negated), so that
// the sweeps above run unchanged on stations 0..meeting; the state is read and written per lane.
// NodeRecords: the records in the wire's node order (a window's), else by station.
template <bool NodeRecords>
struct TwistedLone : OnePlane<2, false, false> {
  using V = Lane<2>;
  using T = Double2;
  using Mask = Long2;
  int top;  // the range's last node, from its first (the state's pointers are at the first)

  // The pack's two-lane sweep on the range's twisted coefficients, over stations 0..the meeting.
  explicit TwistedLone(const PackSweep& a) : OnePlane(a), top(a.hi - a.lo) {
    coef = a.twisted_coef;
    lo = 0;
    hi = a.twisted_meet;
  }

  __attribute__((always_inline)) T get(int i, int k) const {
    if constexpr (NodeRecords) return T{rec[i * NR + k], rec[(top - i) * NR + k]};
    else return OnePlane::get(i, k);
  }
  __attribute__((always_inline)) void set(int i, int k, T x) {
    if constexpr (NodeRecords) {
      rec[(top - i) * NR + k] = x[1];
      rec[i * NR + k] = x[0];  // (last: at the meeting both lanes are its node, lane 0's holds)
    } else {
      OnePlane::set(i, k, x);
    }
  }

  __attribute__((always_inline)) void state(int i, T& ui, T& vi) const {
    ui = T{u[i], u[top - i]};
    vi = T{v[i], v[top - i]};
  }
  // Stations i and i + 1: lane 0's nodes i, i + 1 and lane 1's top - i - 1, top - i as blocks.
  __attribute__((always_inline)) static void split(const double* p, int i, int j, T& x0, T& x1) {
    const T a = V::row(p + i), b = V::row(p + j);
    x0 = __builtin_shuffle(a, b, Long2{0, 3});
    x1 = __builtin_shuffle(a, b, Long2{1, 2});
  }
  __attribute__((always_inline)) void state2(int i, T& u0, T& u1, T& v0, T& v1) const {
    split(u, i, top - i - 1, u0, u1);
    split(v, i, top - i - 1, v0, v1);
  }
  __attribute__((always_inline)) void update(int i, T a, Mask& ok) {
    const T vi = T{v[i], v[top - i]} + dt * a, ui = T{u[i], u[top - i]} + dt * vi;
    ok = V::inside(ok, ui, above, below);
    acc[i] = a[0];
    acc[top - i] = a[1];
    vn[i] = vi[0];
    vn[top - i] = vi[1];
    un[i] = ui[0];
    un[top - i] = ui[1];
  }
  __attribute__((always_inline)) void update2(int i, T a0, T a1, Mask& ok) {
    const int j = top - i - 1;
    const T aa = __builtin_shuffle(a0, a1, Long2{0, 2}), ab = __builtin_shuffle(a0, a1, Long2{3, 1});
    const T va = V::row(v + i) + dt * aa, vb = V::row(v + j) + dt * ab;
    const T ua = V::row(u + i) + dt * va, ub = V::row(u + j) + dt * vb;
    ok = V::inside(V::inside(ok, ua, above, below), ub, above, below);
    V::put_row(acc + i, aa);
    V::put_row(acc + j, ab);
    V::put_row(vn + i, va);
    V::put_row(vn + j, vb);
    V::put_row(un + i, ua);
    V::put_row(un + j, ub);
  }
  // The meeting node alone (lane 0; lane 1 holds the same node, mirrored).
  __attribute__((always_inline)) void update_meeting(T a, Mask& ok) {
    const int i = hi;
    const double vi = v[i] + dt[0] * a[0], ui = u[i] + dt[0] * vi;
    ok = V::inside(ok, T{ui, ui}, above, below);
    acc[i] = a[0];
    vn[i] = vi;
    un[i] = ui;
  }
};

// The sweeps of a lone wire from both ends (TwistedLone): stations 0..meeting - 1 as any pack's,
// then the meeting node. Its forward row r and both sides' eliminations give its rotation,
// theta = (y+ + y- - r) / gamma (y- is lane 1's, of the mirrored wire: -y there); the first step
// back gives both neighbours' rotations, and with them the meeting node's band force.
template <class S>
__attribute__((always_inline)) inline void drive_twisted(S& s, double inv_gamma) {
  using T = Double2;
  using W = WireLanes;
  const int meet = s.hi;
  s.forward_begin();
  int i = 1;
  for (; i + 1 < meet; i += 2) s.forward_two(i);
  if (i < meet) s.forward_one(i);
  // Station meet: lane 0's node meet + 1 and lane 1's node meet - 1 are the stations beyond it.
  T un_, vn_;
  s.state(meet + 1, un_, vn_);
  const T zn = s.z_of(un_, vn_);
  const T r = (-s.c(meet, W::kDwt) * s.zc - s.c(meet, W::kEtw) * zn) - s.c(meet - 1, W::kEwt) * s.zp;
  const T y = r - s.lower(meet) * s.y;
  const double theta = ((y[0] - y[1]) - r[0]) * inv_gamma;
  // Back from the meeting: station meet - 1 in both lanes (nodes meet - 1 and meet + 1).
  s.ok = S::all();
  s.th1 = T{theta, -theta};
  s.z1 = s.zc;
  T u_meet, v_meet, u0, v0;
  s.state(meet, u_meet, v_meet);
  s.state(meet - 1, u0, v0);
  const T z0 = s.z_of(u0, v0);
  const T th0 = s.get(meet - 1, kRecTheta) * s.ip(meet - 1) - s.lower(meet) * s.th1;
  // Beyond the meeting node in each lane: the other lane's neighbour (its rotation negated).
  const T th2 = -__builtin_shuffle(th0, Long2{1, 0});
  const T z2 = zn;
  const T A = ((s.c(meet, W::kDww) * s.z1 + s.c(meet, W::kDwt) * s.th1) + s.c(meet - 1, W::kEww) * z0) +
              s.c(meet - 1, W::kEtw) * th0;
  const T B = s.c(meet, W::kEww) * z2 + s.c(meet, W::kEwt) * th2;
  const T f = (s.init(meet, v_meet) - A) - B;
  s.update_meeting(s.accel(meet, f), s.ok);
  s.th2 = s.th1;
  s.th1 = th0;
  s.z2 = s.z1;
  s.z1 = z0;
  s.v1 = v0;
  i = meet - 2;
  for (; i - 1 >= 0; i -= 2) s.backward_two(i);
  if (i == 0) s.backward_one();
  s.backward_end();
}

template <bool NodeRecords>
__attribute__((always_inline)) inline bool sweep_twisted(const PackSweep& a) {
  Sweeper<TwistedLone<NodeRecords>> s(a);
  drive_twisted(s, a.twisted_inv_gamma);
  return !Lane<2>::ok(s.ok);  // some new displacement beyond the limit or NaN
}

// Both planes of an L-wire pack in 2L lanes, [vertical: wire 0 (, wire 1); lateral: wire 0 (,
// wire 1)]: the band and its factors are the same both ways (a round wire bends alike), so each
// coefficient is loaded once for both and every band operation does both planes at once; each
// plane's state, load, damping, inverse mass and wind are its own (OnePlane's, in halves), the
// records interleaved per node [value][2L lanes] (WirePacks::dof_joint_force).
template <int L>
struct Halves;
template <>
struct Halves<1> {
  using T = Double2;
  using Half = double;
  static T both(Half a, Half b) { return T{a, b}; }
  static Half low(T x) { return x[0]; }
  static Half high(T x) { return x[1]; }
};
template <>
struct Halves<2> {
  using T = Double4;
  using Half = Double2;
  static T both(Half a, Half b) { return __builtin_shufflevector(a, b, 0, 1, 2, 3); }
  static Half low(T x) { return __builtin_shufflevector(x, x, 0, 1); }
  static Half high(T x) { return __builtin_shufflevector(x, x, 2, 3); }
};

template <int L, bool Drag>
struct TwoPlanes : Halves<L> {
  using H = Halves<L>;
  using T = typename H::T;
  using Half = typename H::Half;
  using H::both;
  using H::high;
  using H::low;
  struct Mask {
    typename Lane<L>::Mask vertical, lateral;
  };
  static constexpr int NR = kSweepRecord;
  OnePlane<L, false, false> vp;
  OnePlane<L, true, Drag> lp;
  double* rec;
  T beta, dt, ww_lo, wt_lo, ww_hi, wt_hi;
  int lo, hi;

  TwoPlanes(const PackSweep& a, const PackSweep& b, double* joint_record)
      : vp(a), lp(b), rec(joint_record), beta(both(vp.beta, lp.beta)), dt(both(vp.dt, lp.dt)),
        ww_lo(both(vp.ww_lo, lp.ww_lo)), wt_lo(both(vp.wt_lo, lp.wt_lo)), ww_hi(both(vp.ww_hi, lp.ww_hi)),
        wt_hi(both(vp.wt_hi, lp.wt_hi)), lo(a.lo), hi(a.hi) {}

  __attribute__((always_inline)) T c(int i, int k) const {
    const Half x = vp.c(i, k);
    return both(x, x);
  }
  __attribute__((always_inline)) T lower(int i) const {
    const Half x = vp.lower(i);
    return both(x, x);
  }
  __attribute__((always_inline)) T ip(int i) const {
    const Half x = vp.ip(i);
    return both(x, x);
  }
  __attribute__((always_inline)) T get(int i, int k) const {
    T x;
    std::memcpy(&x, rec + (static_cast<std::ptrdiff_t>(i) * NR + k) * 2 * L, sizeof x);
    return x;
  }
  __attribute__((always_inline)) void set(int i, int k, T x) {
    std::memcpy(rec + (static_cast<std::ptrdiff_t>(i) * NR + k) * 2 * L, &x, sizeof x);
  }
  __attribute__((always_inline)) T inv_mass(int i) const { return both(vp.inv_mass(i), lp.inv_mass(i)); }
  __attribute__((always_inline)) T init(int i, T vi) const { return both(vp.init(i, low(vi)), lp.init(i, high(vi))); }
  __attribute__((always_inline)) void state(int i, T& ui, T& vi) const {
    Half a, b, c, d;
    vp.state(i, a, b);
    lp.state(i, c, d);
    ui = both(a, c);
    vi = both(b, d);
  }
  __attribute__((always_inline)) void state2(int i, T& u0, T& u1, T& v0, T& v1) const {
    Half a0, a1, b0, b1, c0, c1, d0, d1;
    vp.state2(i, a0, a1, b0, b1);
    lp.state2(i, c0, c1, d0, d1);
    u0 = both(a0, c0);
    u1 = both(a1, c1);
    v0 = both(b0, d0);
    v1 = both(b1, d1);
  }
  __attribute__((always_inline)) void update(int i, T a, Mask& ok) {
    vp.update(i, low(a), ok.vertical);
    lp.update(i, high(a), ok.lateral);
  }
  __attribute__((always_inline)) void update2(int i, T a0, T a1, Mask& ok) {
    vp.update2(i, low(a0), low(a1), ok.vertical);
    lp.update2(i, high(a0), high(a1), ok.lateral);
  }
  static Mask all() { return Mask{Lane<L>::all(), Lane<L>::all()}; }
};

// The vertical plane's sweep `a` and the lateral plane's `b` on the same L-wire pack and nodes.
template <int L, bool Drag>
__attribute__((always_inline)) inline bool sweep_pair(const PackSweep& a, const PackSweep& b, double* joint_record,
                                                      bool* b_outside) {
  Sweeper<TwoPlanes<L, Drag>> s(a, b, joint_record);
  drive(s);
  *b_outside = !Lane<L>::ok(s.ok.lateral);
  return !Lane<L>::ok(s.ok.vertical);
}

}  // namespace

#if defined(__x86_64__) && defined(__GNUC__) && !defined(__clang__)
#define CATENARY_SIM_CLONES __attribute__((target_clones("arch=x86-64-v4", "arch=x86-64-v3", "default")))
#else
#define CATENARY_SIM_CLONES
#endif

CATENARY_SIM_CLONES bool sweep_pack(const PackSweep& a) {
  if (a.twisted_meet >= 0 && !a.plane) return a.node_records ? sweep_twisted<true>(a) : sweep_twisted<false>(a);
  if (a.plane) {
    if (a.wind[0]) return a.pack->lanes == 2 ? sweep<2, true, true>(a) : sweep<1, true, true>(a);
    return a.pack->lanes == 2 ? sweep<2, true, false>(a) : sweep<1, true, false>(a);
  }
  return a.pack->lanes == 2 ? sweep<2, false, false>(a) : sweep<1, false, false>(a);
}

CATENARY_SIM_CLONES bool sweep_pack_pair(const PackSweep& a, const PackSweep& b, double* joint_record, bool* b_outside) {
  if (a.pack->lanes == 2)
    return b.wind[0] ? sweep_pair<2, true>(a, b, joint_record, b_outside) : sweep_pair<2, false>(a, b, joint_record, b_outside);
  return b.wind[0] ? sweep_pair<1, true>(a, b, joint_record, b_outside) : sweep_pair<1, false>(a, b, joint_record, b_outside);
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
  // A lone wire swept from both ends: the whole wire (its pack's layout), or a window of an odd
  // count of nodes (the window's). Both lanes' first stations are the range's two ends.
  const Wire& w0 = wires[p.wire[0]];
  const bool whole = w0.twisted_meeting >= 0 && !windowed, in_window = windowed && w0.twisted && ww0.meet > 0;
  if (whole || in_window) {
    const TwistedRange r = whole ? whole_wire_range(w0) : window_range(w0, ww0);
    a.twisted_meet = r.meet;
    a.twisted_inv_gamma = r.inv_gamma;
    a.twisted_coef = whole ? p.twisted_coef.data() : ww0.twisted_coef.data();
    a.factors = whole ? p.twisted_factors.data() : ww0.twisted_factors.data();
    a.node_records = in_window;
    for (int lane = 0; lane < 2; ++lane) {
      a.ww_lo[lane] = r.end_ww[lane];
      a.wt_lo[lane] = r.end_wt[lane];
    }
    const int at = w0.w_dof + a.lo;
    a.u[0] = a.u[1] = x + at;  // (one wire: no second lane's offset)
    a.v[0] = v + at;
    a.u_next[0] = x_next + at;
    a.v_next[0] = v_next + at;
    a.accel[0] = accel + at;
    a.record = records + kSweepRecord * (p.offset + (in_window ? a.lo : 0));
    return true;
  }
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

bool setup_lateral_sweep(const Model& m, State& s, std::size_t pack, bool windowed, PackSweep& a) {
  const LateralModel& lat = *m.lateral;
  LateralState& ls = s.lateral;
  LateralWorkspace& lw = *ls.work;
  const WireLanes& p = m.wire_packs->packs[pack];
  if (!setup_pack_sweep(p, lat.wires, windowed ? &ls.window : nullptr, lw.sweep_factors.data(), s.work->sweep.data(), ls.y.data(),
                        ls.v.data(), lw.y_next.data(), lw.v_next.data(), lw.accel.data(), a))
    return false;
  // (the records in the vertical step's scratch, StepWorkspace::sweep; sweep_pack_pair puts them elsewhere)
  a.plane = lat.planes[pack].data();
  // The wind's drag is taken in the sweep (PackSweep::wind), on the velocity it reads anyway.
  for (int k = 0; k < p.lanes; ++k) a.wind[k] = lat.windy ? ls.wind_speed.data() + lat.wires[p.wire[k]].w_dof : nullptr;
  a.beta = m.beta;
  a.dt = lat.dt;
  a.limit = m.scene.numerics.divergence_limit;
  return true;
}

}  // namespace catenary_sim
