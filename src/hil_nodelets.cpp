// The hardware-in-the-loop pair as nodelets: catenary_sim/HilNodelet (catenary_sim_hil_node's
// HilNode) and catenary_sim/VirtualRigNodelet (virtual_rig's VirtualRig). Loaded into one nodelet
// manager (launch/hil.launch inprocess:=true) they exchange hil/contact_point and
// hil/contact_force as shared pointers: no serialisation, no socket, and no network thread
// between the rig's publish() and the node's queue. Each runs its loop on a thread of its own
// (not on the manager's callback threads: their subscriptions use queues of their own); unloading
// the nodelet or shutting the manager down ends it. Parameters as for the processes.
#include <nodelet/nodelet.h>
#include <pluginlib/class_list_macros.hpp>
#include <ros/ros.h>

#include <atomic>
#include <memory>
#include <stdexcept>
#include <thread>

#include "catenary_sim/ros/hil_node.hpp"
#include "catenary_sim/ros/virtual_rig_loop.hpp"

namespace catenary_sim {
namespace ros_layer {

// Runs `Loop` (HilNode or VirtualRig: a constructor from the node handles, run(), stop()) on a
// thread of its own.
template <class Loop>
class LoopNodelet : public nodelet::Nodelet {
 public:
  ~LoopNodelet() override {
    stopping_ = true;
    if (loop_) loop_->stop();
    if (thread_.joinable()) thread_.join();
  }

 protected:
  // What to do when run() returns on its own (not through stop() or a shutdown).
  virtual void finished(int /*exit_code*/) {}

 private:
  void onInit() override {
    try {
      loop_ = std::make_unique<Loop>(getNodeHandle(), getPrivateNodeHandle());
    } catch (const std::exception& e) {
      NODELET_FATAL("%s", e.what());
      throw;  // the manager refuses the nodelet (its loader exits with an error)
    }
    thread_ = std::thread([this] {
      const int rc = loop_->run();
      if (!stopping_ && ros::ok() && !ros::isShuttingDown()) finished(rc);
    });
  }

  std::atomic<bool> stopping_{false};  // unloading: run() was told to stop
  std::unique_ptr<Loop> loop_;
  std::thread thread_;
};

class HilNodelet : public LoopNodelet<HilNode> {
 protected:
  // The pass ended with ~at_end exit: as the process exits, the manager is shut down.
  void finished(int exit_code) override {
    NODELET_INFO("catenary_sim_hil: the pass ended (~at_end exit, code %d): shutting the manager down", exit_code);
    ros::requestShutdown();
  }
};

class VirtualRigNodelet : public LoopNodelet<VirtualRig> {};

}  // namespace ros_layer
}  // namespace catenary_sim

PLUGINLIB_EXPORT_CLASS(catenary_sim::ros_layer::HilNodelet, nodelet::Nodelet)
PLUGINLIB_EXPORT_CLASS(catenary_sim::ros_layer::VirtualRigNodelet, nodelet::Nodelet)
