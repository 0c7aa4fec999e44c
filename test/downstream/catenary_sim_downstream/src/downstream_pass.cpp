// One pass of a scene through catenary_sim's public face, from another package:
//   downstream_pass SCENE
// prints the steps taken, whether the pass finished, and the leading pantograph's mean contact
// force over the pass.
#include <cstdio>
#include <exception>

#include "catenary_sim/core/simulation.hpp"

int main(int argc, char** argv) {
  if (argc != 2) {
    std::fprintf(stderr, "usage: downstream_pass SCENE\n");
    return 2;
  }
  try {
    catenary_sim::Simulation sim(catenary_sim::load_scene_file(argv[1], {}));
    long steps = 0;
    double sum = 0.0;
    while (sim.step() == catenary_sim::StepStatus::kOk) {
      ++steps;
      sum += catenary_sim::total_contact_force(sim.model(), sim.state(), 0);
    }
    std::printf("steps %ld finished %d mean_contact_force_n %.6f\n", steps, sim.finished() ? 1 : 0,
                steps > 0 ? sum / steps : 0.0);
    return sim.finished() ? 0 : 1;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "downstream_pass: %s\n", e.what());
    return 1;
  }
}
