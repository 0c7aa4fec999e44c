// The hardware-in-the-loop loop, free of ROS and of any transport: the catenary of a scene
// against real pantographs. Force in, motion out: once per loop period (1 to 10 kHz, a whole
// number of core steps) the loop applies the newest measured contact force of every external
// pantograph, steps the core through the period and hands the motion of the wire under each
// pantograph (a PointFrame) to its transport. Two transports use it: catenary_sim_hil_node (ROS
// topics, ros/hil_node.hpp) and catenary_sim_hil_udp (fixed binary packets over UDP,
// hil/udp_loop.hpp); each is a thin skin (LoopSkin) that receives, sends and monitors.
//
// Pacing on the wall clock (docs/hil.md, "The loop on the wall clock"): each period has a window
// one period wide; a fresh measurement inside it starts the steps at once, else they start at the
// window's end with the held (or extrapolated) measurement; the windows lock onto the arrivals of
// a rig sending on its own clock. Input older than the timeout puts the line into the safe hold
// (the train stops, the force ramps to the static uplift). Control requests (arm, pause, reset,
// stop) come from any thread through ask(); the loop takes them once per period with a try-lock.
#pragma once

#include <array>
#include <atomic>
#include <condition_variable>
#include <cstdint>
#include <limits>
#include <memory>
#include <mutex>
#include <optional>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "catenary_sim/core/model/model.hpp"
#include "catenary_sim/core/scene/scene.hpp"
#include "catenary_sim/core/simulation.hpp"
#include "catenary_sim/core/engine/state.hpp"
#include "catenary_sim/core/output/statistics.hpp"
#include "catenary_sim/hil/contact_frame.hpp"
#include "catenary_sim/hil/latency.hpp"
#include "catenary_sim/hil/loop_timing.hpp"
#include "catenary_sim/hil/measurement_hold.hpp"

namespace catenary_sim {
namespace hil {

enum class EndAction { kStop, kLoop, kExit };
enum class Request { kArm, kPause, kResume, kReset, kStop };
enum class LogLevel { kInfo, kWarn, kError };

struct LoopOptions {
  double rate = 1000.0;            // Hz, [kMinLoopRate, kMaxLoopRate]
  double timeout = 0.05;           // s, [2 periods, 10]: older input puts the line into the safe hold
  bool extrapolate = false;        // extrapolate the last two measurements instead of holding
  double hold_ramp = 0.5;          // s, force ramp to the static force in the safe hold
  double hold_deceleration = 10.0; // m/s^2, the train stops (and accelerates back) at this rate
  bool auto_start = true;          // false: the pass waits for Request::kArm
  EndAction at_end = EndAction::kStop;
  double start_delay = 0.0;        // s (wall) in which measurements are ignored
  double spin_wait = 0.0;          // s before a due time from which the loop polls instead of blocking
  // s, [0, 0.1]: the contact point sent is predicted this far ahead along its path velocity (the
  // known loop delay: the rig imposes it that much later), so that the force measured on it is the
  // answer to the state at the time it is applied. 0: the state as it is.
  double delay_compensation = 0.0;
  std::string who = "catenary_sim_hil";    // prefix of the log lines
  // Errors name the options as the command line spells them (--hold-deceleration) instead of as
  // the ROS parameters (~hil/hold_deceleration).
  bool command_line = false;
  std::string input = "hil/contact_force"; // how the measurement input is named in messages
};

// Coupling quality (docs/hil.md, "Coupling quality"): the power at the interface, as a
// time-domain passivity observer sees it. The rig's pantograph works on the wire with the force
// it measured against the motion it was given (the contact point its measurement answers); the
// simulated line receives that force against its own motion when it is applied. With no delay
// the two are the same contact point; the difference is the energy the loop delay adds to the
// line (> 0) or removes (< 0). With delay compensation the answered point stands for the state
// that much later (what remains is the delay not compensated; the prediction's own error is not
// seen: the rig's actual position is not measured).
struct CouplingEnergy {
  double interface_j = 0.0;  // J, sum over periods of F x path velocity of the line x period (work on the line)
  double rig_j = 0.0;        // J, the same with the path velocity of the contact point answered
  double delay_j = 0.0;      // J, interface_j - rig_j over the periods whose answered point is known
  double peak_power_w = 0.0; // W, largest |F x path velocity| of a period
  std::int64_t periods = 0, known = 0;  // periods counted; of those, with the answered point known
};

// The loop's counters (also in the report files).
struct LoopCounters {
  std::int64_t batches = 0;        // loop periods that stepped
  std::int64_t triggered = 0;      // of those, started by a fresh measurement
  std::int64_t held = 0;           // running without a fresh measurement in the window (held input)
  std::int64_t hold_batches = 0;   // in the safe hold
  std::int64_t overruns = 0;       // the loop fell behind: a window closed before its steps began
  std::int64_t accepted = 0, rejected = 0;
  std::int64_t superseded = 0;     // replaced by a newer one before any period used them
  std::int64_t late = 0;           // answered an older contact point than the last published
  std::int64_t holds = 0;          // times the safe hold was entered
  std::int64_t relocks = 0;        // the windows were centred on an arrival again (after an overrun)
  double max_age_running = 0.0;    // s, oldest measurement used while running
};

class HilLoop;

// What a transport provides. Every call but log() comes from the loop thread.
class LoopSkin {
 public:
  virtual ~LoopSkin() = default;
  virtual bool running() = 0;
  // Takes the measurements that have arrived (handing each to HilLoop::accept) and returns when
  // loop.fresh() or when the steady clock reaches `until` (at once when it already has).
  virtual void receive(double until) = 0;
  // The contact points of the period (finite; mode, pass_count, measurement fields filled).
  virtual void send(const PointFrame& frame) = 0;
  virtual void log(LogLevel level, const std::string& text) = 0;
  // After each period's steps and contact point (monitoring: snapshots at a lower rate).
  virtual void after_period(double /*now*/) {}
  // A pass has ended: its recorder and final state (statistics are the skin's, off the loop).
  virtual void pass_ended(std::unique_ptr<PassRecorder> /*recorder*/, const State& /*state*/) {}
};

class HilLoop {
 public:
  // `scene` must have an external pantograph; its dt is chosen for the period (hil_timing: HilError
  // naming `rate_name` or the scene), the speed is the scene's. Throws HilError or SceneError.
  HilLoop(Scene scene, const LoopOptions& options, const std::string& rate_name = "parameter ~hil/rate",
          const std::string& scene_name = "~scene");
  void attach(LoopSkin* skin) { skin_ = skin; }
  // Runs until the skin stops running, stop() or the end of the pass with EndAction::kExit.
  // Returns 1 when that pass diverged, else 0.
  int run();
  void stop() { stop_ = true; }

  // Loop thread (from LoopSkin::receive): a measurement of one total force per external
  // pantograph arriving at `arrival` (steady s), measured at `measured` (s on any clock whose
  // differences count; 0: unknown), answering the contact point of `step` (0: the newest).
  // Validated whole (`field`[i] names a value in errors, or `field` alone when !indexed); a
  // rejected one changes nothing and is counted. False when rejected.
  bool accept(const double* force, std::size_t n, double arrival, double measured, std::uint64_t step,
              const char* field, bool indexed);
  // Why accept() would reject these forces (empty: it would not); changes nothing. A transport
  // that must know before it takes a packet's sequence number asks this first.
  std::string measurement_error(const double* force, std::size_t n, const char* field, bool indexed) const;
  // A measurement the transport already refused (bad packet or message): counted and logged.
  void reject(const std::string& what);
  // A fresh measurement may start the period.
  bool fresh() const { return fresh_; }
  // Sender stamp -> arrival on the same clock (s), when the transport knows it.
  void add_transport(double seconds) { transport_.add(seconds); }

  // Any thread: hand `r` to the loop and wait (at most `wait` s) for its answer (done, message).
  std::pair<bool, std::string> ask(Request r, double wait = 5.0);
  // Any thread: a speed command (m/s, already validated), taken at the next period.
  void command_speed(double v);

  const Simulation& simulation() const { return *sim_; }
  const Model& model() const { return sim_->model(); }
  const State& state() const { return sim_->state(); }
  const HilTiming& timing() const { return timing_; }
  const LoopOptions& options() const { return opt_; }
  const std::vector<int>& external() const { return external_; }
  Mode mode() const { return mode_; }
  bool armed() const { return armed_; }
  bool stopping() const { return stopping_; }
  bool recovering() const { return recovering_; }
  bool diverged() const { return diverged_; }
  // The pass stopped at a dewirement (the scene's pantograph_head.on_dewirement: stop).
  bool dewired() const { return dewired_; }
  std::uint32_t pass_count() const { return pass_count_; }
  double commanded_speed() const { return commanded_speed_; }
  double age(double now) const { return hold_.has_value() ? hold_.age(now) : -1.0; }
  double age_in_effect() const { return age_in_effect_; }
  std::uint64_t step_in_effect() const { return step_in_effect_; }
  const LoopCounters& counters() const { return c_; }
  double started() const { return started_; }  // steady s of the first measurement (0: none)
  // measurement arrival -> its contact point sent; rig stamp -> arrival; batch start -> sent;
  // arrival -> the steps that use it start; the lateness of each period's start against its due
  // time (the loop's jitter).
  const LatencyHistogram& latency() const { return latency_; }
  const LatencyHistogram& transport() const { return transport_; }
  const LatencyHistogram& compute() const { return compute_; }
  const LatencyHistogram& wait() const { return wait_; }
  const LatencyHistogram& jitter() const { return jitter_; }
  // Over the running periods of the current pass (reset with a new pass).
  const CouplingEnergy& energy() const { return energy_; }
  // p50, p99, max of latency(), refreshed once a second (for diagnostics).
  const double* latency_quantiles() const { return q_latency_; }
  // The jitter, refreshed once a second (for diagnostics).
  const JitterSummary& jitter_summary() const { return q_jitter_; }

 private:
  void log(LogLevel level, const std::string& text);
  // At most once per `period` s for each `slot`: true when the line may be logged now.
  bool throttle(int slot, double period);
  void wait_for_period(double w, double half, double& t);
  // One period at t (steady s), started by a fresh measurement or not: the mode's transitions and
  // counters, then add_coupling_energy (running), step_period and finish_period.
  void batch(double t, bool triggered);
  void add_coupling_energy(double t);
  // The period's core steps, each with the force in effect (held, extrapolated or the safe hold's ramp).
  void step_period(double t);
  // The contact point sent, the latencies counted and the end of the pass handled.
  void finish_period(double t, bool triggered);
  void send_point();
  void handle_end();
  void enter_hold(double t, double age);
  void leave_hold();
  void poll_control();
  bool execute(Request r, std::string& message);
  void begin_stop();
  void new_pass();
  bool stop_settled() const;

  LoopOptions opt_;
  LoopSkin* skin_ = nullptr;
  HilTiming timing_;
  std::unique_ptr<Simulation> sim_;
  std::vector<int> external_;
  double commanded_speed_ = 0.0;
  std::atomic<bool> stop_{false};

  Mode mode_ = Mode::kWaiting;
  bool armed_ = true;
  Mode paused_from_ = Mode::kRunning;
  bool stopping_ = false, recovering_ = false;
  double point_motion_ = 0.0;
  MeasurementHold hold_;
  bool fresh_ = false, unused_ = false, owed_ = false;
  std::uint64_t published_step_ = 0;
  std::vector<double> accept_buf_;
  double age_in_effect_ = -1.0;
  std::uint64_t step_in_effect_ = 0;
  double hold_start_time_ = 0.0;
  std::vector<double> hold_from_;
  bool diverged_ = false, dewired_ = false, exit_requested_ = false;
  int exit_code_ = 0;
  std::uint32_t pass_count_ = 0;
  double started_ = 0.0;
  PointFrame frame_;
  std::unique_ptr<PassRecorder> recorder_;
  LoopCounters c_;
  LatencyHistogram latency_, transport_, compute_, wait_, jitter_;
  double next_quantiles_ = 0.0;
  double q_latency_[3] = {0, 0, 0};
  JitterSummary q_jitter_;
  CouplingEnergy energy_;
  // Path velocity of every external pantograph in the contact points sent, by step (a ring: the answered point of a measurement up to 256 periods old).
  static constexpr std::size_t kSentHistory = 256;
  std::array<std::uint64_t, kSentHistory> sent_step_{};
  std::vector<double> sent_pv_;  // kSentHistory x external pantographs
  std::vector<double> last_pv_;  // of the last contact point sent
  std::array<double, 8> throttle_until_{};

  // Control hand-over (ask() from any thread, poll_control() on the loop thread).
  std::mutex ctrl_mu_;
  std::condition_variable ctrl_cv_;
  std::atomic<bool> ctrl_posted_{false};
  Request ctrl_request_ = Request::kArm;
  bool ctrl_done_ = false, ctrl_ok_ = false;
  std::string ctrl_reply_;
  bool loop_running_ = false;  // (under ctrl_mu_)
  std::atomic<bool> speed_posted_{false};
  std::atomic<double> speed_command_{0.0};
};

}  // namespace hil
}  // namespace catenary_sim
