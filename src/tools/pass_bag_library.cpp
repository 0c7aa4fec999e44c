// libcatenary_sim_pass_bag.so: simulate_pass's bag writer (pass_bag_writer.hpp), the ROS layer's
// PassBag behind the ROS-free interface simulate_pass loads it through.
#include "pass_bag_writer.hpp"

#include "catenary_sim/ros/conversions.hpp"
#include "catenary_sim/ros/pass_bag.hpp"

namespace catenary_sim {
namespace {

class RosPassBag final : public PassBagWriter {
 public:
  RosPassBag(const std::string& path, const ros_layer::PassBagOptions& o) : bag_(path, o) {}
  void write_scene(const std::string& scene_path, const std::vector<std::string>& overrides) override {
    bag_.write_scene(ros_layer::scene_yaml_message(scene_path, overrides));
  }
  void write(const Model& model, const State& state, const PassRecorder* recorder) override {
    bag_.write(model, state, recorder);
  }
  void close() override { bag_.close(); }
  std::size_t messages() const override { return bag_.messages(); }

 private:
  ros_layer::PassBag bag_;
};

}  // namespace
}  // namespace catenary_sim

extern "C" __attribute__((visibility("default"))) catenary_sim::PassBagWriter* catenary_sim_open_pass_bag(
    const std::string& path, double rate) {
  catenary_sim::ros_layer::PassBagOptions o;
  o.rate = rate;
  return new catenary_sim::RosPassBag(path, o);
}
