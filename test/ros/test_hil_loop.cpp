// rostest companion of hil.test (1 kHz) and hil_2khz.test: catenary_sim_hil_node and
// virtual_rig close the loop over the topics, on the wall clock, on config/reference_55m_hil.yaml
// (the whole 550 m pass at 300 km/h: 6.6 s). The contact force collected from hil/contact_point
// must give the statistics of the internal lumped pantograph of config/reference_55m.yaml (same
// dt, same sampling), within the tolerance that test_hil.cpp's delay study justifies: a loop
// delay of one or two periods is a phase lag that moves the 20 Hz filtered mean by < 0.1 N and its
// standard deviation by < 1 %; allowed here: 0.5 N and 3 % (the live loop also sees stalls).
#include <gtest/gtest.h>
#include <ros/ros.h>
#include <yaml-cpp/yaml.h>

#include <cmath>
#include <cstdio>
#include <mutex>
#include <sstream>
#include <string>
#include <vector>

#include "catenary_sim/ContactPointArray.h"
#include "catenary_sim/MeasuredContactForce.h"
#include "catenary_sim/core/simulation.hpp"
#include "catenary_sim/core/statistics.hpp"
#include "catenary_sim/ros/hil.hpp"

#ifndef CATENARY_SIM_SOURCE_DIR
#define CATENARY_SIM_SOURCE_DIR "."
#endif

using namespace catenary_sim;

namespace {

std::mutex mu;
std::vector<ContactPointArray> points;
bool ended = false;
std::vector<std::string> measurement_frames;  // header.frame_id of every hil/contact_force from the rig

void on_point(const ContactPointArray::ConstPtr& m) {
  std::lock_guard<std::mutex> l(mu);
  points.push_back(*m);
  if (m->mode == ContactPointArray::ENDED) ended = true;
}

void on_measurement(const MeasuredContactForce::ConstPtr& m) {
  std::lock_guard<std::mutex> l(mu);
  measurement_frames.push_back(m->header.frame_id);
}

}  // namespace

TEST(HilLoop, ClosedLoopStatisticsMatchTheInternalPantograph) {
  ros::NodeHandle pnh("~");
  double rate = 0.0;
  ASSERT_TRUE(pnh.getParam("rate", rate));
  const ros::WallTime deadline = ros::WallTime::now() + ros::WallDuration(90.0);
  while (ros::ok() && ros::WallTime::now() < deadline) {
    {
      std::lock_guard<std::mutex> l(mu);
      if (ended) break;
    }
    ros::WallDuration(0.05).sleep();
  }
  std::vector<ContactPointArray> msgs;
  std::vector<std::string> frames;
  {
    std::lock_guard<std::mutex> l(mu);
    msgs = points;
    frames = measurement_frames;
    ASSERT_TRUE(ended) << "the pass did not end within 90 s (" << points.size() << " contact points)";
  }
  // Every contact point finite; the running ones one period apart, in order, with increasing stamps.
  std::vector<const ContactPointArray*> run;
  for (const ContactPointArray& m : msgs) {
    EXPECT_TRUE(ros_layer::all_finite(m)) << "step " << m.step;
    EXPECT_NE(m.mode, ContactPointArray::SAFE_HOLD) << "step " << m.step;
    if (m.mode == ContactPointArray::RUNNING || (m.mode == ContactPointArray::ENDED && run.size() && m.step > run.back()->step))
      run.push_back(&m);
  }
  ASSERT_GT(run.size(), 100u);
  // The rig answers in the frame of the contact points (the line frame), never an empty frame_id.
  ASSERT_FALSE(frames.empty());
  for (const std::string& f : frames) ASSERT_EQ(f, msgs[0].header.frame_id);
  EXPECT_FALSE(msgs[0].header.frame_id.empty());
  const int k = static_cast<int>(run[0]->steps_per_period);
  const double dt = run[0]->dt;
  EXPECT_NEAR(k * dt, 1.0 / rate, 1e-12);
  std::size_t gaps = 0, zero_delay = 0;
  for (std::size_t i = 1; i < run.size(); ++i) {
    EXPECT_GT(run[i]->header.stamp, run[i - 1]->header.stamp);
    gaps += run[i]->step != run[i - 1]->step + k;
    zero_delay += run[i]->measurement_step + k == run[i]->step;
  }
  // (a contact point lost on the way: tolerated, the statistics use the position of each sample)
  EXPECT_LE(gaps, run.size() / 100) << "contact points lost";

  // The internal lumped pantograph of the same line, same dt, sampled at the same steps.
  YAML::Node root = YAML::LoadFile(CATENARY_SIM_SOURCE_DIR "/config/reference_55m.yaml");
  root["numerics"]["dt"] = dt;
  std::stringstream yaml;
  yaml << root;
  Simulation internal(load_scene_string(yaml.str()));
  const Model& m = internal.model();
  ASSERT_NEAR(internal.state().speed, run.back()->speed, 1e-9);
  std::vector<double> xi, fi;
  while (!internal.finished()) {
    for (int j = 0; j < k; ++j) internal.step();
    xi.push_back(pantograph_position(m, internal.state(), 0));
    fi.push_back(total_contact_force(m, internal.state(), 0));
  }
  std::vector<double> xh, fh;
  for (const ContactPointArray* c : run) {
    xh.push_back(c->pantographs[0].position);
    fh.push_back(c->pantographs[0].applied_force);
  }
  const double x0 = m.support_x[m.scene.analysis_first()], x1 = m.support_x[m.scene.analysis_last()];
  auto stats = [&](const std::vector<double>& x, const std::vector<double>& f) {
    const std::vector<double> filtered = lowpass_zero_phase(f, rate, m.scene.output.filter_cutoff);
    std::vector<double> in;
    for (std::size_t i = 0; i < f.size(); ++i)
      if (x[i] >= x0 && x[i] <= x1) in.push_back(filtered[i]);
    return force_statistics(in);
  };
  const ForceStatistics si = stats(xi, fi), sh = stats(xh, fh);
  char summary[512];
  std::snprintf(summary, sizeof summary,
                "%g Hz (%d x %g ms): loop mean %.3f N std %.3f N max %.2f min %.2f; internal mean %.3f N std %.3f N "
                "max %.2f min %.2f; %zu periods, %.1f %% used the answer to the previous contact point, %zu gaps",
                rate, k, dt * 1e3, sh.mean, sh.std_dev, sh.max, sh.min, si.mean, si.std_dev, si.max, si.min,
                run.size(), 100.0 * zero_delay / run.size(), gaps);
  RecordProperty("summary", summary);
  ROS_INFO("test_hil_loop: %s", summary);
  EXPECT_NEAR(sh.mean, si.mean, 0.5);
  EXPECT_NEAR(sh.std_dev, si.std_dev, 0.03 * si.std_dev);
}

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  ros::init(argc, argv, "test_hil_loop");
  ros::NodeHandle nh;
  ros::Subscriber sub =
      nh.subscribe("hil/contact_point", 100000, &on_point, ros::TransportHints().tcpNoDelay());
  ros::Subscriber msub = nh.subscribe("hil/contact_force", 100000, &on_measurement);
  ros::AsyncSpinner spinner(1);
  spinner.start();
  const int rc = RUN_ALL_TESTS();
  spinner.stop();
  ros::shutdown();
  return rc;
}
