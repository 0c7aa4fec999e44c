// simulate_pass --bag: the rosbag writer, in a library of its own (libcatenary_sim_pass_bag.so)
// that simulate_pass loads only when --bag is given. Linked into the program, the ROS libraries
// a bag needs were loaded and relocated at every start: 15 ms of a 25 ms start-up, paid by every
// case of a study that writes no bag.
#pragma once

#include <cstddef>
#include <memory>
#include <string>
#include <vector>

#include "catenary_sim/core/engine/state.hpp"
#include "catenary_sim/core/model/model.hpp"
#include "catenary_sim/core/output/pass_recorder.hpp"

namespace catenary_sim {

// A pass's bag (ros_layer::PassBag behind it).
class PassBagWriter {
 public:
  virtual ~PassBagWriter() = default;
  // The scene as the node publishes it: the file at `scene_path` with the --set overrides.
  virtual void write_scene(const std::string& scene_path, const std::vector<std::string>& overrides) = 0;
  virtual void write(const Model& model, const State& state, const PassRecorder* recorder) = 0;
  virtual void close() = 0;
  virtual std::size_t messages() const = 0;
};

// The library's one entry point, looked up by this name: opens (truncates) the bag at `path`,
// /contact_force, /pantograph_state and /tf at `rate` Hz (0: every step). Throws (a
// std::exception naming the path) if it cannot.
#define CATENARY_SIM_PASS_BAG_OPEN "catenary_sim_open_pass_bag"
using PassBagOpen = PassBagWriter* (*)(const std::string& path, double rate);

// Loads the library beside this program's lib/ (<prefix>/lib/libcatenary_sim_pass_bag.so, the
// devel or install space's) or, failing that, by the dynamic linker's search, and opens the bag.
// Throws OutputError if the library cannot be loaded, and what the writer throws.
std::unique_ptr<PassBagWriter> open_pass_bag(const std::string& path, double rate);

}  // namespace catenary_sim
