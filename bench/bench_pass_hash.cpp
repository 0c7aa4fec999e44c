// One pass, timed, with a hash of the state after every step: compares two builds (or two
// machines) bit for bit and for speed with the same program. Built here with the package; to
// build it against another checkout's core library (e.g. an older commit in /tmp/base):
//   g++ -O3 -DNDEBUG -std=c++17 -ffp-contract=off -I/tmp/base/include -I/usr/include/eigen3
//       bench/bench_pass_hash.cpp /tmp/base/.ws/devel/lib/libcatenary_sim_core.a -lyaml-cpp
//       -o /tmp/bench_pass_hash_base
// (the flags of the package's Release build; add -DBENCH_PASS_HASH_2D_ONLY for a checkout older
// than the 3-D line, e.g. 25f35a6).
//   bench_pass_hash SCENE [field=value ...]
// Prints the steps, the FNV-1a hash of u, v and the contact forces over every step (and, with a
// lateral plane, of its y and v: a 2-D scene's hash is what it was before the 3-D line), and the
// wall time of the stepping (model building and statics not included).
#include <chrono>
#include <cstdint>
#include <cstdio>
#include <string>
#include <vector>

#include "catenary_sim/core/simulation.hpp"
#include "bench_cli.hpp"
#include "guarded_main.hpp"

using namespace catenary_sim;

static int bench_main(int argc, char** argv) {
  CLI::App app{"One pass, timed, with a hash of the state after every step: two builds or machines compared bit for "
               "bit and for speed.",
               "bench_pass_hash"};
  std::string path;
  std::vector<std::string> overrides;
  app.add_option("scene", path, "scene YAML")->required()->check(CLI::ExistingFile);
  bench::add_overrides(app, overrides, "overrides of the scene's fields (as simulate_pass --set)");
  CLI11_PARSE(app, argc, argv);
  Simulation sim(load_scene_file(path, overrides));
  std::uint64_t hash = 1469598103934665603ull;
  auto mix = [&](const double* p, std::size_t n) {
    const unsigned char* c = reinterpret_cast<const unsigned char*>(p);
    for (std::size_t i = 0; i < 8 * n; ++i) hash = (hash ^ c[i]) * 1099511628211ull;
  };
  // Timed without hashing first, then hashed on a second pass of the same scene.
  const auto t0 = std::chrono::steady_clock::now();
  long steps = 0;
  while (sim.step() == StepStatus::kOk) ++steps;
  const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  Simulation again(load_scene_file(path, overrides));
  while (again.step() == StepStatus::kOk) {
    const State& s = again.state();
    mix(s.u.data(), s.u.size());
    mix(s.v.data(), s.v.size());
    mix(s.contact_force.data(), s.contact_force.size());
#ifndef BENCH_PASS_HASH_2D_ONLY  // (for a checkout older than the 3-D line: -DBENCH_PASS_HASH_2D_ONLY)
    if (again.model().lateral) {
      mix(s.lateral.y.data(), s.lateral.y.size());
      mix(s.lateral.v.data(), s.lateral.v.size());
    }
#endif
  }
  std::printf("%ld steps, %d DOFs, wall %.4f s, %.3f ns per DOF and step, hash %016llx\n", steps, sim.model().n_dof, wall,
              wall / steps / sim.model().n_dof * 1e9, static_cast<unsigned long long>(hash));
  return 0;
}

int main(int argc, char** argv) { return bench::guarded_main("bench_pass_hash", argc, argv, bench_main); }
