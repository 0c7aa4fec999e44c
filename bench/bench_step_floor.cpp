// The explicit step against its floor. The floor is the minimal fused kernel of one step at the
// reference scene's sizes: per section the contact wire and the messenger interleaved in the two
// lanes of a vector register, every array (coefficients, u, v, the new values) laid out
// lane-interleaved, one forward sweep (z = u + beta v, the condensation's L solve) and one backward
// sweep (D^-1 L^T, band force, load, damping, update of eq. 20-21, the displacement check), nothing
// else: no droppers, supports, pantograph or contact, no window, no gathers. It does the same
// arithmetic as the step's wire part, with the same dispatch (target_clones), so the step cannot
// beat it; the ratio says what the rest of the step costs.
//   bench_step_floor [repetitions=7] [scene=config/reference_55m.yaml] [preset=accurate]
// Also times a scalar floor (the two wires one after the other, no vector types) and, for the
// record, a floor with FMA contraction (what -ffp-contract=fast would allow; not used by the step,
// which must give the same bits everywhere).
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <string>
#include <vector>

#include "catenary_sim/core/simulation.hpp"
#include "../test/support/scenes.hpp"
#include "../src/core/engine/wire_lanes.hpp"  // the step's kernel, timed alone
#include "../src/core/engine/step_workspace.hpp"
#include "bench_cli.hpp"
#include "guarded_main.hpp"

using namespace catenary_sim;

namespace {

typedef double D2 __attribute__((vector_size(16)));
typedef long L2 __attribute__((vector_size(16)));

// One section, both wires interleaved: entry 2 i + k is node i of wire k.
// Coefficients as the step keeps them: one record per node (WireLanes::coef, factors).
struct Floor {
  int n = 0;
  std::vector<double> coef, fac;
  std::vector<double> u, v, un, vn, acc, th;
  double beta = 0, dt = 0, limit = 5.0;
};

inline D2 ld(const std::vector<double>& a, int i) {
  D2 x;
  std::memcpy(&x, a.data() + 2 * i, 16);
  return x;
}
using W = WireLanes;
constexpr int NC = W::kCoefficients;
inline D2 cf(const Floor& F, int i, int k) {
  D2 x;
  std::memcpy(&x, F.coef.data() + 2 * (i * NC + k), 16);
  return x;
}
inline D2 fc(const Floor& F, int i, int k) {
  D2 x;
  std::memcpy(&x, F.fac.data() + 2 * (2 * i + k), 16);
  return x;
}
inline void st(std::vector<double>& a, int i, D2 x) { std::memcpy(a.data() + 2 * i, &x, 16); }

// The fused kernel, two lanes. FMA: multiply-adds fused (only for the record).
template <bool FMA>
__attribute__((always_inline)) inline bool floor_kernel(Floor& F) {
  auto mul_sub = [](D2 a, D2 b, D2 c) {  // a - b c
    if constexpr (FMA) return D2{std::fma(-b[0], c[0], a[0]), std::fma(-b[1], c[1], a[1])};
    return a - b * c;
  };
  auto mul_add = [](D2 a, D2 b, D2 c) {  // a + b c
    if constexpr (FMA) return D2{std::fma(b[0], c[0], a[0]), std::fma(b[1], c[1], a[1])};
    return a + b * c;
  };
  const int n = F.n, hi = n - 1;
  const D2 beta = {F.beta, F.beta}, dt = {F.dt, F.dt}, lim = {F.limit, F.limit}, nlim = -lim;
  auto z = [&](int i) { return mul_add(ld(F.u, i), beta, ld(F.v, i)); };
  D2 zp = z(0), zc = z(1);
  D2 y = mul_sub(-cf(F, 0, W::kDwt) * zp, cf(F, 0, W::kEtw), zc);
  st(F.th, 0, y);
  for (int i = 1; i < hi; ++i) {
    const D2 zn = z(i + 1);
    const D2 r = mul_sub(mul_sub(-cf(F, i, W::kDwt) * zc, cf(F, i, W::kEtw), zn), cf(F, i - 1, W::kEwt), zp);
    y = mul_sub(r, fc(F, i, 0), y);
    st(F.th, i, y);
    zp = zc;
    zc = zn;
  }
  y = mul_sub(mul_sub(-cf(F, hi, W::kDwt) * zc, cf(F, hi - 1, W::kEwt), zp), fc(F, hi, 0), y);
  L2 ok = {-1, -1};
  auto update = [&](int j, D2 f, D2 u, D2 v) {
    const D2 a = cf(F, j, W::kInvMass) * f, vn = mul_add(v, dt, a), un = mul_add(u, dt, vn);
    ok &= (un <= lim) & (un >= nlim);
    st(F.acc, j, a);
    st(F.vn, j, vn);
    st(F.un, j, un);
  };
  D2 th1 = y * fc(F, hi, 1), th2 = {0, 0}, z2 = {0, 0};
  st(F.th, hi, th1);
  D2 u1 = ld(F.u, hi), v1 = ld(F.v, hi), z1 = mul_add(u1, beta, v1);
  for (int i = hi - 1; i >= 0; --i) {
    const D2 th0 = mul_sub(ld(F.th, i) * fc(F, i, 1), fc(F, i + 1, 0), th1);
    st(F.th, i, th0);
    const D2 u0 = ld(F.u, i), v0 = ld(F.v, i), z0 = mul_add(u0, beta, v0);
    const int j = i + 1;
    const D2 A = mul_add(mul_add(mul_add(cf(F, j, W::kDww) * z1, cf(F, j, W::kDwt), th1), cf(F, i, W::kEww), z0), cf(F, i, W::kEtw), th0);
    const D2 B = mul_add(cf(F, j, W::kEww) * z2, cf(F, j, W::kEwt), th2);  // zero coefficients at hi
    update(j, mul_sub(cf(F, j, W::kLoad), cf(F, j, W::kDampingMass), v1) - A - B, u1, v1);
    th2 = th1;
    th1 = th0;
    z2 = z1;
    z1 = z0;
    u1 = u0;
    v1 = v0;
  }
  const D2 A = mul_add(cf(F, 0, W::kDww) * z1, cf(F, 0, W::kDwt), th1);
  const D2 B = mul_add(cf(F, 0, W::kEww) * z2, cf(F, 0, W::kEwt), th2);
  update(0, mul_sub(cf(F, 0, W::kLoad), cf(F, 0, W::kDampingMass), v1) - A - B, u1, v1);
  std::swap(F.u, F.un);
  std::swap(F.v, F.vn);
  return !(ok[0] && ok[1]);
}

__attribute__((target_clones("arch=x86-64-v4", "arch=x86-64-v3", "default"))) bool floor_step(Floor& F) { return floor_kernel<false>(F); }
__attribute__((target_clones("arch=x86-64-v4", "arch=x86-64-v3", "default"))) bool floor_step_fma(Floor& F) {
  return floor_kernel<true>(F);
}

// The scalar floor: each wire on its own (lane k of the interleaved arrays), plain doubles.
bool floor_step_scalar(Floor& F) {
  const int n = F.n, hi = n - 1;
  bool bad = false;
  for (int k = 0; k < 2; ++k) {
    auto at = [&](const std::vector<double>& a, int i) { return a[2 * i + k]; };
    auto z = [&](int i) { return at(F.u, i) + F.beta * at(F.v, i); };
    double zp = z(0), zc = z(1);
    double y = -F.coef[2 * (0 * NC + W::kDwt) + k] * zp - F.coef[2 * (0 * NC + W::kEtw) + k] * zc;
    F.th[k] = y;
    for (int i = 1; i < hi; ++i) {
      const double zn = z(i + 1);
      y = ((-F.coef[2 * (i * NC + W::kDwt) + k] * zc - F.coef[2 * (i * NC + W::kEtw) + k] * zn) - F.coef[2 * ((i - 1) * NC + W::kEwt) + k] * zp) - F.fac[2 * (2 * i) + k] * y;
      F.th[2 * i + k] = y;
      zp = zc;
      zc = zn;
    }
    y = (-F.coef[2 * (hi * NC + W::kDwt) + k] * zc - F.coef[2 * ((hi - 1) * NC + W::kEwt) + k] * zp) - F.fac[2 * (2 * hi) + k] * y;
    double th1 = y * F.fac[2 * (2 * hi + 1) + k], th2 = 0, z2 = 0, u1 = at(F.u, hi), v1 = at(F.v, hi), z1 = u1 + F.beta * v1;
    F.th[2 * hi + k] = th1;
    auto update = [&](int j, double f, double u, double v) {
      const double a = F.coef[2 * (j * NC + W::kInvMass) + k] * f, vn = v + F.dt * a, un = u + F.dt * vn;
      bad |= !(std::fabs(un) <= F.limit);
      F.acc[2 * j + k] = a;
      F.vn[2 * j + k] = vn;
      F.un[2 * j + k] = un;
    };
    for (int i = hi - 1; i >= 0; --i) {
      const double th0 = at(F.th, i) * F.fac[2 * (2 * i + 1) + k] - F.fac[2 * (2 * i + 1) + k] * th1;
      F.th[2 * i + k] = th0;
      const double u0 = at(F.u, i), v0 = at(F.v, i), z0 = u0 + F.beta * v0;
      const int j = i + 1;
      const double A = ((F.coef[2 * (j * NC + W::kDww) + k] * z1 + F.coef[2 * (j * NC + W::kDwt) + k] * th1) + F.coef[2 * (i * NC + W::kEww) + k] * z0) + F.coef[2 * (i * NC + W::kEtw) + k] * th0;
      const double B = F.coef[2 * (j * NC + W::kEww) + k] * z2 + F.coef[2 * (j * NC + W::kEwt) + k] * th2;
      update(j, ((F.coef[2 * (j * NC + W::kLoad) + k] - F.coef[2 * (j * NC + W::kDampingMass) + k] * v1) - A) - B, u1, v1);
      th2 = th1;
      th1 = th0;
      z2 = z1;
      z1 = z0;
      u1 = u0;
      v1 = v0;
    }
    update(0, ((F.coef[2 * (0 * NC + W::kLoad) + k] - F.coef[2 * (0 * NC + W::kDampingMass) + k] * v1) - (F.coef[2 * (0 * NC + W::kDww) + k] * z1 + F.coef[2 * (0 * NC + W::kDwt) + k] * th1)) -
                  (F.coef[2 * (0 * NC + W::kEww) + k] * z2 + F.coef[2 * (0 * NC + W::kEwt) + k] * th2),
           u1, v1);
  }
  std::swap(F.u, F.un);
  std::swap(F.v, F.vn);
  return bad;
}

// The floor's arrays from the model: each pack of two wires (contact wire, messenger) as built.
std::vector<Floor> floors_of(const Model& m, const State& s0) {
  std::vector<Floor> out;
  for (const WireLanes& p : packs_of(m)) {
    if (p.lanes != 2) continue;
    Floor F;
    F.n = p.nodes;
    F.coef = p.coef;
    F.fac = p.factors;
    const std::size_t sz = 2 * static_cast<std::size_t>(p.nodes);
    F.u.assign(sz, 0.0);
    F.v.assign(sz, 0.0);
    for (int k = 0; k < 2; ++k)
      for (int i = 0; i < p.nodes; ++i) F.u[2 * i + k] = s0.u[m.wires[p.wire[k]].w_dof + i];
    F.un = F.vn = F.acc = F.th = std::vector<double>(sz, 0.0);
    F.beta = m.beta;
    F.dt = m.dt;
    F.limit = m.scene.numerics.divergence_limit;
    out.push_back(std::move(F));
  }
  return out;
}

}  // namespace

static int bench_main(int argc, char** argv) {
  CLI::App app{"The explicit step against its floor, the minimal fused kernel of one step at the scene's sizes.",
               "bench_step_floor"};
  int reps = 7;
  std::string path = test_scenes::kReference, preset = "accurate";
  bench::add_repetitions(app, reps);
  bench::add_scene(app, path);
  app.add_option("preset", preset, "numerics.preset of the pass")
      ->check(CLI::IsMember(bench::kPresets))
      ->capture_default_str();
  CLI11_PARSE(app, argc, argv);
  const Scene scene = load_scene_file(path, {"train.speed_kmh=300", "numerics.preset=" + preset});
  const Simulation proto(scene);
  const Model& m = proto.model();
  if (!m.wire_packs) {
    std::fprintf(stderr, "bench_step_floor: the scene has no wire packs (explicit, condensed rotations needed)\n");
    return 1;
  }
  long steps = 0;
  {
    Simulation sim(scene);
    while (sim.step() == StepStatus::kOk) ++steps;
  }
  int wire_dofs = 0;
  for (const Wire& w : m.wires) wire_dofs += w.nodes();
  std::printf("scene %s, preset %s: %d DOFs (%d wire nodes in %zu packs), dt %.4f ms, %ld steps; sweep_pack dispatches to: %s\n",
              path.c_str(), preset.c_str(), m.n_dof, wire_dofs, packs_of(m).size(), m.dt * 1e3, steps, sweep_pack_isa());
  struct Row {
    const char* label;
    std::vector<double> walls;
  };
  std::vector<Row> rows{{"step (Simulation::step, whole pass)", {}},
                        {"floor: fused kernel, 2 lanes", {}},
                        {"step's kernel alone (sweep_pack)", {}},
                        {"floor: scalar, wires in turn", {}},
                        {"floor with FMA (not reproducible)", {}}};
  long flagged = 0;  // floor sweeps that saw a displacement beyond the limit (keeps their results alive)
  // Interleaved repetitions: a change of the shared machine's load falls on every row alike.
  for (int r = 0; r < reps; ++r)
    for (std::size_t v = 0; v < rows.size(); ++v) {
      Simulation sim(scene);
      std::vector<Floor> F = floors_of(sim.model(), sim.state());
      State s = sim.state();  // for the kernel alone
      const auto t0 = std::chrono::steady_clock::now();
      if (v == 0) {
        while (sim.step() == StepStatus::kOk) {
        }
      } else if (v == 2) {
        // The step's wire kernel on the step's own layout (the state's arrays), no point forces.
        const Model& mm = sim.model();
        bool bad = false;
        for (long k = 0; k < steps; ++k) {
          for (const WireLanes& p : packs_of(mm)) {
            PackSweep a;
            a.pack = &p;
            a.lo = 0;
            a.hi = p.nodes - 1;
            a.factors = p.factors.data();
            for (int l = 0; l < p.lanes; ++l) {
              const int w0 = mm.wires[p.wire[l]].w_dof;
              a.ww_lo[l] = a.ww_hi[l] = 0.0;
              a.wt_lo[l] = mm.wires[p.wire[l]].d_wt[0];
              a.wt_hi[l] = mm.wires[p.wire[l]].d_wt[p.nodes - 1];
              a.ww_lo[l] = mm.wires[p.wire[l]].d_ww[0];
              a.ww_hi[l] = mm.wires[p.wire[l]].d_ww[p.nodes - 1];
              a.u[l] = s.u.data() + w0;
              a.v[l] = s.v.data() + w0;
              a.u_next[l] = s.work->u_next.data() + w0;
              a.v_next[l] = s.work->v_next.data() + w0;
              a.accel[l] = s.accel.data() + w0;
            }
            a.record = s.work->sweep.data() + kSweepRecord * p.offset;
            a.beta = mm.beta;
            a.dt = mm.dt;
            a.limit = mm.scene.numerics.divergence_limit;
            bad |= sweep_pack(a);
          }
          s.u.swap(s.work->u_next);
          s.v.swap(s.work->v_next);
        }
        flagged += bad;
      } else {
        bool bad = false;
        for (long k = 0; k < steps; ++k)
          for (Floor& f : F) bad |= v == 1 ? floor_step(f) : v == 3 ? floor_step_scalar(f) : floor_step_fma(f);
        flagged += bad;
      }
      rows[v].walls.push_back(std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
    }
  std::printf("%-38s %10s %10s %12s %14s\n", "variant", "wall_med_s", "wall_min_s", "ns/DOF/step", "ratio to floor");
  std::vector<double> med(rows.size());
  for (std::size_t v = 0; v < rows.size(); ++v) {
    std::sort(rows[v].walls.begin(), rows[v].walls.end());
    med[v] = rows[v].walls[rows[v].walls.size() / 2];
  }
  for (std::size_t v = 0; v < rows.size(); ++v)
    std::printf("%-38s %10.4f %10.4f %12.2f %14.3f\n", rows[v].label, med[v], rows[v].walls.front(),
                med[v] / steps / m.n_dof * 1e9, med[v] / med[1]);
  std::printf("(floor runs that flagged a displacement: %ld; the floor has no supports, so its wires sag freely)\n", flagged);
  std::printf("step / floor: %.3f on the medians, %.3f on the minima\n", med[0] / med[1],
              rows[0].walls.front() / rows[1].walls.front());
  return 0;
}

int main(int argc, char** argv) { return bench::guarded_main("bench_step_floor", argc, argv, bench_main); }
