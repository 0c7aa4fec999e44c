// Hardware in the loop without a master: the loop timing, the held measurement, the virtual rig's
// pantograph, the hil/contact_point conversion, and the closed loop emulated in-process (the
// node's steps and the rig's pantograph exchanging forces and contact points period by period),
// with and without loop delay. The delay study here is what justifies the tolerance of the
// rostests (test_hil_loop.cpp) that run the same loop over topics on the wall clock.
#include <gtest/gtest.h>
#include <yaml-cpp/yaml.h>

#include <cmath>
#include <deque>
#include <limits>
#include <sstream>

#include "catenary_sim/core/simulation.hpp"
#include "catenary_sim/core/output/statistics.hpp"
#include "catenary_sim/ros/hil.hpp"
#include "catenary_sim/ros/virtual_rig.hpp"
#include "../support/scenes.hpp"

using namespace catenary_sim;
using namespace catenary_sim::ros_layer;

namespace {

Scene reference(double dt, double kmh) {
  return test_scenes::edited_scene("reference_55m.yaml", [dt, kmh](YAML::Node& root) {
    root["numerics"]["dt"] = dt;
    root["train"]["speed_kmh"] = kmh;
  });
}

// The same scene with its lumped pantographs made external (as config/reference_55m_hil.yaml).
Scene external_of(Scene s) {
  for (PantographSpec& p : s.pantographs) {
    p.moving_force = p.external = true;
    p.masses.clear();
    p.stiffness.clear();
    p.damping.clear();
  }
  validate(s);
  return s;
}

// The contact force sampled once per loop period (k steps), with the position, as the rostest
// collects it from hil/contact_point.
struct Series {
  std::vector<double> x, f;
  double fs = 0.0;
};

// Filtered statistics over the scene's analysis section, as PassRecorder computes them.
ForceStatistics section_statistics(const Model& m, const Series& s) {
  const double x0 = m.support_x[m.scene.analysis_first()], x1 = m.support_x[m.scene.analysis_last()];
  const std::vector<double> filtered = lowpass_zero_phase(s.f, s.fs, m.scene.output.filter_cutoff);
  std::vector<double> in;
  for (std::size_t i = 0; i < s.f.size(); ++i)
    if (s.x[i] >= x0 && s.x[i] <= x1) in.push_back(filtered[i]);
  return force_statistics(in);
}

Series internal_pass(const Scene& scene, int k) {
  Simulation sim(scene);
  Series out;
  out.fs = 1.0 / (k * sim.model().dt);
  while (!sim.finished()) {
    for (int j = 0; j < k; ++j) sim.step();
    out.x.push_back(pantograph_position(sim.model(), sim.state(), 0));
    out.f.push_back(total_contact_force(sim.model(), sim.state(), 0));
  }
  return out;
}

// The closed loop of catenary_sim_hil_node and virtual_rig, in-process: each period the node
// applies the rig's answer to the contact point of `delay` periods before the last one (0: the
// answer to the last one, i.e. a rig that answers within the period), steps k times and
// publishes; the rig steps its pantograph up to the new contact point (the wire extrapolated along
// its path velocity between contact points, as virtual_rig does) and answers.
Series hil_pass(const Scene& lumped, int k, int delay, Simulation* keep = nullptr) {
  Simulation local(external_of(lumped));
  Simulation& sim = keep ? *keep : local;
  const Model& m = sim.model();
  RigPantograph rig(lumped.pantographs[0], lumped.contact.stiffness);
  std::vector<ContactPointMotion> scratch;
  ContactPointArray msg = to_contact_points(m, sim.state(), ros::Time(1), "line", k, scratch);
  std::vector<WirePoint> points = wire_points(msg.pantographs[0]);
  rig.reset(points, msg.speed);
  std::deque<double> answers{rig.contact_force(points)};
  std::uint64_t rig_step = msg.step;
  Series out;
  out.fs = 1.0 / (k * m.dt);
  std::string err;
  while (!sim.finished()) {
    const std::size_t n = answers.size();
    const double f = n > static_cast<std::size_t>(delay) ? answers[n - 1 - delay] : answers.front();
    EXPECT_TRUE(sim.set_external_force(0, f, &err)) << err;
    for (int j = 0; j < k; ++j) sim.step();
    msg = to_contact_points(m, sim.state(), ros::Time(1), "line", k, scratch);
    out.x.push_back(msg.pantographs[0].position);
    out.f.push_back(msg.pantographs[0].applied_force);
    for (std::uint64_t s = rig_step; s < msg.step; ++s)
      rig.step(m.dt, rig.contact_force(points, static_cast<double>(s - rig_step) * m.dt), msg.speed);
    rig_step = msg.step;
    points = wire_points(msg.pantographs[0]);
    answers.push_back(rig.contact_force(points));
  }
  return out;
}

}  // namespace

TEST(HilTiming, AutomaticDtIsTheLargestDivisorOfThePeriodBelowTheAutomaticStep) {
  const double auto_dt = 0.8916e-3;  // the reference scene's automatic dt
  HilTiming t = hil_timing(1000.0, std::nullopt, auto_dt);
  EXPECT_EQ(t.steps_per_period, 2);
  EXPECT_DOUBLE_EQ(t.dt, 0.5e-3);
  EXPECT_DOUBLE_EQ(t.period, 1e-3);
  t = hil_timing(2000.0, std::nullopt, auto_dt);
  EXPECT_EQ(t.steps_per_period, 1);
  EXPECT_DOUBLE_EQ(t.dt, 0.5e-3);
  t = hil_timing(5000.0, std::nullopt, auto_dt);
  EXPECT_EQ(t.steps_per_period, 1);
  EXPECT_DOUBLE_EQ(t.dt, 0.2e-3);
  t = hil_timing(1000.0, std::nullopt, 0.25e-3);  // exactly a divisor: kept
  EXPECT_EQ(t.steps_per_period, 4);
}

TEST(HilTiming, ExplicitDtMustDivideThePeriod) {
  HilTiming t = hil_timing(1000.0, 0.0005, 0.0);
  EXPECT_EQ(t.steps_per_period, 2);
  t = hil_timing(5000.0, 0.0001, 0.0);
  EXPECT_EQ(t.steps_per_period, 2);
  t = hil_timing(1000.0, 0.0002, 0.0);  // 0.001 / 0.0002 is 5 up to round-off
  EXPECT_EQ(t.steps_per_period, 5);
  EXPECT_DOUBLE_EQ(t.dt, 0.001 / 5);
  for (auto [rate, dt] : std::vector<std::pair<double, double>>{{1000.0, 0.0008}, {5000.0, 0.0005}, {2000.0, 0.0003}}) {
    try {
      hil_timing(rate, dt, 0.0);
      ADD_FAILURE() << rate << " Hz with dt " << dt << " accepted";
    } catch (const ParamError& e) {
      const std::string msg = e.what();
      std::ostringstream d, p, r;
      d << "numerics.dt = " << dt << " s";
      p << "loop period " << 1.0 / rate << " s";
      r << "~hil/rate = " << rate << " Hz";
      EXPECT_NE(msg.find(d.str()), std::string::npos) << msg;
      EXPECT_NE(msg.find(p.str()), std::string::npos) << msg;
      EXPECT_NE(msg.find(r.str()), std::string::npos) << msg;
    }
  }
  for (double rate : {999.0, 10001.0, std::nan("")}) EXPECT_THROW(hil_timing(rate, std::nullopt, 1e-3), ParamError);
}

// The parameters added for the loop's scheduling and the decimated outputs: out of range names the
// parameter, the value and what is allowed.
TEST(HilParams, SpinWaitPriorityAndShapeParametersAreChecked) {
  HilParams p;
  p.scene = "x.yaml";
  EXPECT_NO_THROW(validate_hil_params(p));
  p.spin_wait = 0.0005;  // half the period at 1 kHz: the most allowed
  EXPECT_NO_THROW(validate_hil_params(p));
  auto message = [](const HilParams& q) {
    try {
      validate_hil_params(q);
    } catch (const ParamError& e) {
      return std::string(e.what());
    }
    return std::string("accepted");
  };
  for (double bad : {0.0006, -1e-6, std::nan("")}) {
    HilParams q = p;
    q.spin_wait = bad;
    const std::string msg = message(q);
    EXPECT_NE(msg.find("~hil/spin_wait"), std::string::npos) << msg;
    EXPECT_NE(msg.find("allowed [0, 0.0005] s"), std::string::npos) << msg;
  }
  HilParams q = p;
  q.rate = 5000.0;
  q.timeout = 0.01;
  q.spin_wait = 0.0002;  // more than half of 0.2 ms
  EXPECT_NE(message(q).find("allowed [0, 0.0001] s"), std::string::npos) << message(q);
  for (int bad : {-1, 100}) {
    q = p;
    q.realtime_priority = bad;
    const std::string msg = message(q);
    EXPECT_NE(msg.find("~hil/realtime_priority = " + std::to_string(bad)), std::string::npos) << msg;
    EXPECT_NE(msg.find("0 (normal scheduling) to 99"), std::string::npos) << msg;
  }
  q = p;
  q.shape_rate = 0.0;
  EXPECT_NE(message(q).find("~shape_rate = 0 rejected: allowed [0.1, 100] Hz"), std::string::npos) << message(q);
  q = p;
  q.shape_resolution = -1.0;
  EXPECT_NE(message(q).find("~shape_resolution = -1 rejected"), std::string::npos) << message(q);
}

// ~hil/hold_deceleration: every value the parameter check lets through, the loop takes, and every
// value the loop would refuse is refused at start-up naming the parameter (the two ranges are one).
TEST(HilParams, HoldDecelerationIsCheckedToTheRangeTheLoopTakes) {
  HilParams p;
  p.scene = "x.yaml";
  const Scene scene = load_scene_file(test_scenes::kReferenceHil);
  for (double a : {0.0, 2.5, 20.0, 20.5, 30.0, 50.0, -1.0}) {
    HilParams q = p;
    q.hold_deceleration = a;
    bool params_take = true;
    try {
      validate_hil_params(q);
    } catch (const ParamError& e) {
      params_take = false;
      const std::string msg = e.what();
      EXPECT_NE(msg.find("~hil/hold_deceleration = " + format_given(a)), std::string::npos) << msg;
      EXPECT_NE(msg.find("allowed [0, 20] m/s^2"), std::string::npos) << msg;
    }
    bool loop_takes = true;
    hil::LoopOptions o = loop_options(q);
    try {
      hil::HilLoop loop(scene, o);
    } catch (const hil::HilError& e) {
      loop_takes = false;
      EXPECT_NE(std::string(e.what()).find("~hil/hold_deceleration"), std::string::npos) << e.what();
    }
    EXPECT_EQ(params_take, loop_takes) << "hold_deceleration " << a << " m/s^2";
  }
}

TEST(HilScene, ReferenceHilIsTheReferenceSceneWithAnExternalPantograph) {
  YAML::Node hil = YAML::LoadFile(test_scenes::kReferenceHil);
  YAML::Node ref = YAML::LoadFile(test_scenes::kReference);
  for (YAML::Node p : ref["pantographs"]) {
    p["type"] = "external";
    p.remove("masses");
    p.remove("stiffness");
    p.remove("damping");
  }
  ref["name"] = "reference_55m_hil";
  EXPECT_EQ(YAML::Dump(hil), YAML::Dump(ref));
  // dt: auto gives the steps the README states at each rate.
  const Scene scene = load_scene_file(test_scenes::kReferenceHil);
  ASSERT_TRUE(scene.pantographs[0].external);
  ASSERT_FALSE(scene.numerics.dt);
  const double auto_dt = build_model(scene).dt;
  const std::vector<std::pair<double, double>> expected{{1000, 0.5e-3}, {2000, 0.5e-3}, {5000, 0.2e-3}, {10000, 0.1e-3}};
  for (auto [rate, dt] : expected) EXPECT_NEAR(hil_timing(rate, std::nullopt, auto_dt).dt, dt, 1e-15) << rate;
}

TEST(MeasurementHold, HoldsTheNewestAndExtrapolatesOnlyWhenAskedAndWithinTheHorizon) {
  MeasurementHold h(1);
  EXPECT_FALSE(h.has_value());
  EXPECT_TRUE(std::isinf(h.age(5.0)));
  h.accept({100.0}, 10.000, 0.0, 7);
  EXPECT_DOUBLE_EQ(h.value(0, 10.5, true, 1.0), 100.0);  // one measurement: nothing to extrapolate
  h.accept({110.0}, 10.001, 0.0, 9);
  EXPECT_EQ(h.step(), 9u);
  EXPECT_NEAR(h.age(10.011), 0.010, 1e-12);
  EXPECT_DOUBLE_EQ(h.value(0, 10.002, false, 1.0), 110.0);             // held
  EXPECT_NEAR(h.value(0, 10.002, true, 1.0), 120.0, 1e-6);             // 10 N per ms, 1 ms ahead
  EXPECT_NEAR(h.value(0, 10.100, true, 0.002), 130.0, 1e-6);           // at most the horizon ahead
  EXPECT_NEAR(h.value(0, 10.000, true, 1.0), 110.0, 1e-9);             // never backwards
  // Stamped measurements: the slope comes from their stamps, not from the arrival jitter.
  h.accept({120.0}, 10.0025, 50.002, 11);
  EXPECT_DOUBLE_EQ(h.value(0, 10.003, true, 1.0), 120.0);  // stamped after unstamped: two clocks, held
  h.accept({130.0}, 10.0030, 50.004, 13);                   // 5 N per ms by the stamps
  EXPECT_NEAR(h.value(0, 10.0040, true, 1.0), 135.0, 1e-6);
  EXPECT_FALSE(h.stamps_implausible());
}

// A rig whose stamps run a thousandfold slow (microseconds sent as nanoseconds) makes the slope a
// thousandfold steep: +-1 N of noise would swing the applied force between 0 and 2000 N. Over a
// baseline of arrivals long enough to average their jitter, stamps that do not run with them are
// held, not extrapolated; stamps that do (a rig at 1 kHz with 0.3 ms of jitter) extrapolate.
TEST(MeasurementHold, HoldsWhereTheStampsDoNotRunWithTheArrivals) {
  for (const double stamp_scale : {1.0, 1e-3, 1e3}) {
    SCOPED_TRACE(stamp_scale);
    MeasurementHold h(1);
    double force = 100.0, arrival = 0.0;
    for (int k = 0; k < 30; ++k) {
      arrival = 1.0 + 1e-3 * k + (k % 2 ? 3e-4 : 0.0);  // 1 kHz, alternate packets late
      force = k % 2 ? 101.0 : 99.0;                     // +-1 N of noise
      h.accept({force}, arrival, 5.0 + stamp_scale * 1e-3 * k, static_cast<std::uint64_t>(k));
    }
    const double held = h.value(0, arrival + 1e-3, true, 1e-3);
    if (stamp_scale == 1.0) {
      EXPECT_FALSE(h.stamps_implausible());
      EXPECT_NEAR(held, force + 2.0, 1e-6);  // the true slope, 2 N per ms, for the 1 ms ahead
    } else {
      EXPECT_TRUE(h.stamps_implausible());
      EXPECT_DOUBLE_EQ(held, force);
    }
  }
}

TEST(HoldRamp, LinearFromTheLastForceToTheStaticOne) {
  EXPECT_DOUBLE_EQ(hold_ramp_force(150.0, 100.0, 0.0, 0.5), 150.0);
  EXPECT_DOUBLE_EQ(hold_ramp_force(150.0, 100.0, 0.25, 0.5), 125.0);
  EXPECT_DOUBLE_EQ(hold_ramp_force(150.0, 100.0, 0.6, 0.5), 100.0);
  EXPECT_DOUBLE_EQ(hold_ramp_force(150.0, 100.0, 0.0, 0.0), 100.0);
}

TEST(LatencyHistogram, QuantilesToTheMicrosecond) {
  LatencyHistogram h;
  EXPECT_EQ(h.quantile(0.5), 0.0);
  for (int i = 1; i <= 1000; ++i) h.add(i * 1e-6);  // 1 .. 1000 us
  h.add(0.2);                                        // beyond the last bin: counted, and the max
  EXPECT_EQ(h.count(), 1001u);
  EXPECT_NEAR(h.quantile(0.5), 501e-6, 1.5e-6);
  EXPECT_NEAR(h.quantile(0.99), 992e-6, 1.5e-6);
  EXPECT_DOUBLE_EQ(h.max(), 0.2);
  EXPECT_DOUBLE_EQ(h.quantile(1.0), 0.2);
  h.add(std::nan(""));
  EXPECT_EQ(h.count(), 1001u);
}

TEST(RigPantograph, ResetPressesOnWithTheStaticForce) {
  const Scene scene = reference(0.0005, 300.0);
  RigPantograph rig(scene.pantographs[0], scene.contact.stiffness);
  std::vector<WirePoint> one{{true, 5.25, 0.0}};
  rig.reset(one, 83.0);
  EXPECT_NEAR(rig.contact_force(one), 100.0, 1e-9);
  EXPECT_NEAR(rig.head_height(), 5.25 + 100.0 / 50000.0, 1e-12);
  // An overlap: two wires 1 mm apart, the head presses on both (k0 x 2 mm > 100 N).
  std::vector<WirePoint> two{{true, 5.300, 0.0}, {false, 0.0, 0.0}, {true, 5.301, 0.0}};
  rig.reset(two, 0.0);
  EXPECT_NEAR(rig.contact_force(two), 100.0, 1e-9);
  // 3 mm apart: only the lower one is touched.
  std::vector<WirePoint> apart{{true, 5.303, 0.0}, {true, 5.300, 0.0}};
  rig.reset(apart, 0.0);
  EXPECT_NEAR(rig.contact_force(apart), 100.0, 1e-9);
  EXPECT_NEAR(rig.head_height(), 5.302, 1e-12);
  // At rest it stays at rest.
  for (int i = 0; i < 1000; ++i) rig.step(0.0005, rig.contact_force(apart), 0.0);
  EXPECT_NEAR(rig.contact_force(apart), 100.0, 1e-9);
  PantographSpec moving;
  moving.moving_force = true;
  EXPECT_THROW(RigPantograph(moving, 50000.0), std::invalid_argument);
}

// The rig's pantograph is a chain; a pantograph with heads on their own suspensions is refused by
// name (not merged into one head, which would change its dynamics silently).
TEST(RigPantograph, RefusesAPantographWithSeveralHeadsByName) {
  const Scene scene = load_scene_file(test_scenes::kReferenceTwoHeads);
  ASSERT_EQ(scene.pantographs[0].heads.size(), 2u);
  try {
    RigPantograph rig(scene.pantographs[0], scene.contact.stiffness);
    ADD_FAILURE() << "a two-head pantograph was accepted";
  } catch (const std::invalid_argument& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("'" + scene.pantographs[0].name + "'"), std::string::npos) << what;
    EXPECT_NE(what.find("2 heads"), std::string::npos) << what;
    EXPECT_NE(what.find("pantographs[].heads"), std::string::npos) << what;
  }
}

TEST(ContactPoints, TheMotionUnderTheExternalPantographAndNeverNaN) {
  Simulation sim(external_of(reference(0.0005, 300.0)));
  const Model& m = sim.model();
  for (int i = 0; i < 2000; ++i) sim.step();
  std::vector<ContactPointMotion> scratch, direct;
  const ContactPointArray msg = to_contact_points(m, sim.state(), ros::Time(12.5), "line", 2, scratch);
  contact_point_motion(m, sim.state(), 0, direct);
  ASSERT_EQ(msg.pantographs.size(), 1u);
  const ContactPoint& c = msg.pantographs[0];
  EXPECT_EQ(c.name, "leading");
  EXPECT_EQ(msg.step, 2000u);
  EXPECT_EQ(msg.steps_per_period, 2u);
  EXPECT_DOUBLE_EQ(msg.dt, m.dt);
  EXPECT_EQ(msg.header.stamp, ros::Time(12.5));
  EXPECT_DOUBLE_EQ(msg.simulation_time, sim.state().time);  // the stamp is the caller's (wall clock)
  ASSERT_EQ(c.on_wire.size(), 1u);
  ASSERT_TRUE(c.on_wire[0]);
  EXPECT_DOUBLE_EQ(c.height, direct[0].height);
  EXPECT_DOUBLE_EQ(c.velocity, direct[0].velocity);
  EXPECT_DOUBLE_EQ(c.acceleration, direct[0].acceleration);
  EXPECT_DOUBLE_EQ(c.path_velocity, direct[0].path_velocity);
  EXPECT_DOUBLE_EQ(c.applied_force, sim.state().external_force[0]);
  EXPECT_TRUE(all_finite(msg));
  // Off the line: no wire under the collector; finite values, the nominal height at rest.
  State off = sim.state();
  off.front = m.line_length + 20.0;
  observe(m, off);
  const ContactPointArray o = to_contact_points(m, off, ros::Time(13.0), "line", 2, scratch);
  EXPECT_FALSE(o.pantographs[0].on_wire[0]);
  EXPECT_DOUBLE_EQ(o.pantographs[0].height, m.scene.contact_wire_height);
  EXPECT_DOUBLE_EQ(o.pantographs[0].wire_height[0], 0.0);
  EXPECT_TRUE(all_finite(o));
  ContactPointArray bad = msg;
  bad.pantographs[0].wire_velocity[0] = std::numeric_limits<double>::quiet_NaN();
  EXPECT_FALSE(all_finite(bad));
  ContactPointArray bad_time = msg;
  bad_time.simulation_time = std::numeric_limits<double>::infinity();
  EXPECT_FALSE(all_finite(bad_time));
}

// One step per period and no delay: the rig's answer to each contact point is applied in the very
// next step, so the loop is the internal lumped pantograph exactly (only round-off differs).
TEST(ClosedLoop, WithoutDelayTheLoopIsTheInternalPantograph) {
  const Scene lumped = reference(0.0005, 300.0);
  Simulation internal(lumped);
  Simulation driven(external_of(lumped));
  const Series loop = hil_pass(lumped, 1, 0, &driven);
  const Model& m = internal.model();
  std::vector<double> f;
  while (!internal.finished()) {
    f.push_back(total_contact_force(m, internal.state(), 0));
    internal.step();
  }
  // The force applied in step n is the internal pantograph's force at t_n.
  ASSERT_EQ(loop.f.size(), f.size());
  double max_df = 0.0;
  for (std::size_t i = 0; i < f.size(); ++i) max_df = std::max(max_df, std::fabs(loop.f[i] - f[i]));
  double max_du = 0.0;
  for (int i = 0; i < m.n_catenary_dof; ++i)
    max_du = std::max(max_du, std::fabs(internal.state().u[i] - driven.state().u[i]));
  EXPECT_LT(max_df, 1e-6);  // N
  EXPECT_LT(max_du, 1e-9);  // m
}

// The tolerance of the rostests. A loop delay tau (the rig's answer used d periods late, and at
// 1 kHz the force held over the two steps of a period) turns the contact spring k0 into a spring
// with a delay: k0 x(t - tau) ~ k0 x(t) - k0 tau x'(t), a negative damper of k0 tau (50 N s/m per
// ms) across the contact, and a phase lag of 2 pi f tau (0.13 rad at 20 Hz, the filter's cutoff,
// per ms). The statistics use the force low-pass filtered at 20 Hz, where the lag is small; the
// effect measured here, on the reference pass at 300 km/h, is below 0.1 N on the mean and 1 % on
// the standard deviation for up to two periods (2 ms) of delay. On the wall clock the node uses
// the answer to the last contact point when it arrives within the period, and an older one (one
// period late) otherwise, so the live loop's delay stays within this range except for stalls; the
// rostests allow 0.5 N and 3 %.
TEST(ClosedLoop, DelayOfOneOrTwoPeriodsChangesTheStatisticsLittle) {
  const Scene lumped = reference(0.0005, 300.0);
  const Model m = build_model(lumped);
  const ForceStatistics ref = section_statistics(m, internal_pass(lumped, 2));
  for (int delay : {0, 1, 2}) {
    const ForceStatistics s = section_statistics(m, hil_pass(lumped, 2, delay));
    EXPECT_NEAR(s.mean, ref.mean, 0.1) << delay << " periods";
    EXPECT_NEAR(s.std_dev, ref.std_dev, 0.01 * ref.std_dev) << delay << " periods";
    RecordProperty("delay_" + std::to_string(delay) + "_std_change_percent",
                   std::to_string(100.0 * (s.std_dev / ref.std_dev - 1.0)));
    std::printf("1 kHz (2 steps of 0.5 ms), delay %d period(s): mean %.3f N (internal %.3f), std %.3f N (internal "
                "%.3f, %+.2f %%)\n", delay, s.mean, ref.mean, s.std_dev, ref.std_dev,
                100.0 * (s.std_dev / ref.std_dev - 1.0));
  }
}
