#include "catenary_sim/hil/loop.hpp"

#include "../core/util/format.hpp"  // the core's numbers in messages: one way for all

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdarg>
#include <cstdio>
#include <sstream>

namespace catenary_sim {
namespace hil {

namespace {

// Phase lock of the loop's windows onto the arrivals of a rig sending at the same rate: a gain
// per period on the offset of a triggering arrival from the window's centre, at most this share
// of a period per period: the rate stays within 0.2 % of the loop rate (a rig's crystal drifts far
// less), and a lost phase is found again within 250 periods.
constexpr double kLockGain = 0.05;
constexpr double kLockMax = 2e-3;
constexpr int kRelockPeriods = 16;
constexpr double kRecorderRowRate = 10.0;  // Hz, decimated rows of the pass recorder (unused here)
constexpr double kQuantilePeriod = 1.0;    // s (wall) between latency quantiles for the diagnostics
// A stop ends the pass once the train stands, the force ramp is over and the wire under every
// pantograph moves slower than this (the actuator is then held where it is, a step in velocity
// below what a load cell's noise makes), or at the latest this long after the ramp.
constexpr double kSettledMotion = 2e-3;  // m/s
constexpr double kSettleMax = 5.0;       // s (simulation)

// Throttle slots of the log lines.
enum Slot { kSlotOverrun, kSlotCompute, kSlotReject, kSlotNonFinite, kSlotStamps };

std::string printf_text(const char* f, ...) __attribute__((format(printf, 1, 2)));
std::string printf_text(const char* f, ...) {
  char buf[512];
  va_list ap;
  va_start(ap, f);
  std::vsnprintf(buf, sizeof buf, f, ap);
  va_end(ap);
  return buf;
}

}  // namespace

// ---- The loop ----

HilLoop::HilLoop(Scene scene, const LoopOptions& o, const std::string& rate_name, const std::string& scene_name)
    : opt_(o) {
  // The automatic dt of this scene decides how many steps a period holds (hil_timing).
  double auto_dt = 0.0;
  if (!scene.numerics.dt) auto_dt = build_model(scene).dt;
  timing_ = hil_timing(opt_.rate, scene.numerics.dt, auto_dt, rate_name, scene_name);
  auto name = [this](const char* parameter, const char* option) {
    return opt_.command_line ? std::string(option) : "parameter ~hil/" + std::string(parameter);
  };
  if (!std::isfinite(opt_.delay_compensation) || opt_.delay_compensation < 0.0 || opt_.delay_compensation > 0.1)
    throw HilError(name("delay_compensation", "--delay-compensation") + " = " + fmt_given(opt_.delay_compensation) +
                   " s rejected: allowed [0, 0.1] s");
  if (!std::isfinite(opt_.timeout) || opt_.timeout < 2.0 * timing_.period || opt_.timeout > 10.0)
    throw HilError(name("timeout", "--timeout") + " = " + fmt_given(opt_.timeout) + " s rejected: allowed [2 loop periods = " +
                   fmt(2.0 * timing_.period) + ", 10] s");
  // (checked before the scene is built: a refused option costs no static solve)
  if (!Simulation::max_acceleration_error(opt_.hold_deceleration).empty())
    throw HilError(name("hold_deceleration", "--hold-deceleration") + " = " + fmt_given(opt_.hold_deceleration) +
                   " m/s^2 rejected: allowed [0, " + fmt(Simulation::kMaxAcceleration) +
                   "] m/s^2 (0: at once; the core's limit on the train's acceleration)");
  scene.numerics.dt = timing_.dt;
  sim_ = std::make_unique<Simulation>(scene);
  const Model& m = sim_->model();
  external_ = external_pantographs(m);
  if (external_.empty())
    throw HilError(scene_name + ": the scene has no `type: external` pantograph (one the rig's measurement drives)");
  commanded_speed_ = scene.train_speed;
  std::string err;
  sim_->set_max_acceleration(opt_.hold_deceleration, &err);  // (in range: checked above)
  hold_ = MeasurementHold(external_.size());
  accept_buf_.assign(external_.size(), 0.0);
  hold_from_.assign(m.pantographs.size(), 0.0);
  recorder_ = std::make_unique<PassRecorder>(m, kRecorderRowRate);
  recorder_->record(m, sim_->state());
  armed_ = opt_.auto_start;
  sent_pv_.assign(kSentHistory * external_.size(), 0.0);
  last_pv_.assign(external_.size(), 0.0);
  compute_frame(m, sim_->state(), timing_.steps_per_period, frame_);
}

void HilLoop::log(LogLevel level, const std::string& text) {
  if (skin_) skin_->log(level, opt_.who + ": " + text);
}

bool HilLoop::throttle(int slot, double period) {
  const double now = steady_now();
  if (now < throttle_until_[slot]) return false;
  throttle_until_[slot] = now + period;
  return true;
}

// ---- Control ----

void HilLoop::command_speed(double v) {
  speed_command_ = v;
  speed_posted_ = true;  // (the loop takes the newest at its next period)
}

std::pair<bool, std::string> HilLoop::ask(Request r, double wait) {
  std::unique_lock<std::mutex> l(ctrl_mu_);
  if (!loop_running_) return {false, "refused: the loop is not running (starting up or shutting down); nothing changed"};
  ctrl_request_ = r;
  ctrl_done_ = false;
  ctrl_posted_ = true;
  ctrl_cv_.wait_for(l, std::chrono::duration<double>(wait), [this] { return ctrl_done_ || !loop_running_; });
  if (!ctrl_done_) {
    ctrl_posted_ = false;  // withdrawn: the loop has not taken it (it takes it under ctrl_mu_)
    return {false, "refused: the loop did not take the request within " + fmt(wait) +
                       " s (far behind its schedule, or stopping); nothing changed"};
  }
  return {ctrl_ok_, ctrl_reply_};
}

void HilLoop::poll_control() {
  if (speed_posted_.exchange(false)) {
    commanded_speed_ = speed_command_;
    // (in the safe hold the train keeps stopping: leave_hold applies the commanded speed)
    const bool holding = mode_ == Mode::kHold || (mode_ == Mode::kPaused && paused_from_ == Mode::kHold);
    std::string err;
    if (!holding) sim_->set_target_speed(commanded_speed_, &err);  // (checked: cannot fail)
    if (mode_ == Mode::kWaiting) {
      // Not started: the pass starts at the commanded speed (the line is at its initial static
      // state; reset() with the static force needs no new static solve and changes nothing else).
      for (int p : external_) sim_->set_external_force(p, sim_->state().uplift[p], nullptr);
      sim_->reset(true);
    }
  }
  if (!ctrl_posted_) return;
  std::unique_lock<std::mutex> l(ctrl_mu_, std::try_to_lock);
  if (!l.owns_lock() || !ctrl_posted_) return;  // (the control thread holds it for a moment: next period)
  ctrl_ok_ = execute(ctrl_request_, ctrl_reply_);
  ctrl_done_ = true;
  ctrl_posted_ = false;
  l.unlock();
  ctrl_cv_.notify_all();
}

bool HilLoop::execute(Request r, std::string& msg) {
  const std::string now = stopping_ ? "stopping (~stop)" : mode_ == Mode::kPaused
      ? std::string(paused_from_ == Mode::kHold ? "paused (in the safe hold)" : "paused")
      : mode_ == Mode::kWaiting ? (armed_ ? "waiting for the first measurement" : "waiting for ~arm")
      : mode_ == Mode::kEnded ? (diverged_ ? "ended (diverged)" : dewired_ ? "ended (dewirement)" : "ended")
      : mode_name(mode_);
  auto refuse = [&](const std::string& why) {
    msg = "refused: the pass is " + now + "; " + why;
    return false;
  };
  const std::string t = printf_text("t = %.4f s", sim_->state().time);
  switch (r) {
    case Request::kArm:
      if (mode_ == Mode::kWaiting) {
        if (armed_) return refuse("already armed: it starts with the first valid measurement");
        armed_ = true;
        msg = "armed: the pass starts with the first valid measurement";
        return true;
      }
      if (mode_ == Mode::kEnded) {
        new_pass();
        mode_ = Mode::kWaiting;
        armed_ = true;
        hold_ = MeasurementHold(external_.size());  // (the last pass's measurements start nothing)
        fresh_ = unused_ = owed_ = false;
        age_in_effect_ = -1.0;
        step_in_effect_ = 0;
        msg = "pass " + std::to_string(pass_count_) + " armed: the line is at its initial static state at " + t +
              " (time keeps running); it starts with the first valid measurement";
        return true;
      }
      return refuse("~arm starts a pass that has not started or has ended (~stop ends it, ~reset restarts it)");
    case Request::kPause:
      if (stopping_) return refuse("it ends by itself");
      if (mode_ == Mode::kRunning || mode_ == Mode::kHold) {
        paused_from_ = mode_;
        mode_ = Mode::kPaused;
        msg = "paused at " + t + ": the line is held, the contact point repeats (velocities 0); "
              "~set_paused false resumes";
        return true;
      }
      if (mode_ == Mode::kPaused) return refuse("already paused");
      return refuse(mode_ == Mode::kEnded ? "nothing to pause (~arm for a new pass)" : "nothing to pause yet");
    case Request::kResume:
      if (mode_ != Mode::kPaused) return refuse("not paused");
      mode_ = paused_from_;
      msg = "resumed at " + t + (mode_ == Mode::kHold ? " in the safe hold" : "");
      return true;
    case Request::kReset:
      if (stopping_) return refuse("~arm after its end starts a new pass");
      if (mode_ == Mode::kRunning || mode_ == Mode::kHold || mode_ == Mode::kPaused) {
        new_pass();
        msg = "new pass " + std::to_string(pass_count_) + " from the start at " + t + " (time keeps running)" +
              (mode_ == Mode::kPaused ? "; still paused" : "");
        return true;
      }
      return refuse(mode_ == Mode::kEnded ? "~arm starts a new pass" : "nothing to reset (it has not started)");
    case Request::kStop:
      if (stopping_) return refuse("already stopping");
      if (mode_ == Mode::kRunning || mode_ == Mode::kHold || mode_ == Mode::kPaused) {
        begin_stop();
        msg = "stopping at " + t + ": safe hold (the train stops at " + fmt(opt_.hold_deceleration) +
              " m/s^2, the force ramps to the static uplift over " + fmt(opt_.hold_ramp) +
              " s), then ENDED with the statistics written once the line has settled";
        return true;
      }
      return refuse(mode_ == Mode::kEnded ? "already ended" : "nothing to stop (it has not started)");
  }
  return false;
}

void HilLoop::begin_stop() {
  if (mode_ == Mode::kPaused) mode_ = paused_from_;
  stopping_ = true;
  recovering_ = false;
  if (mode_ == Mode::kHold) return;  // a safe hold already: it goes on, and then ends the pass
  mode_ = Mode::kHold;
  hold_start_time_ = sim_->state().time;
  for (int p : external_) hold_from_[p] = sim_->state().external_force[p];
  std::string err;
  sim_->set_target_speed(0.0, &err);
}

bool HilLoop::stop_settled() const {
  const State& s = sim_->state();
  const double elapsed = s.time - hold_start_time_;
  if (s.speed > 0.0 || elapsed < opt_.hold_ramp) return false;
  return point_motion_ < kSettledMotion || elapsed >= opt_.hold_ramp + kSettleMax;
}

void HilLoop::new_pass() {
  // As at_end loop: the static force first (no new static solve in reset), the clock running on.
  for (int p : external_) sim_->set_external_force(p, sim_->state().uplift[p], nullptr);
  const bool holding = mode_ == Mode::kHold || (mode_ == Mode::kPaused && paused_from_ == Mode::kHold);
  std::string err;
  sim_->set_target_speed(holding ? 0.0 : commanded_speed_, &err);  // (reset starts at the target speed)
  sim_->reset(true);
  ++pass_count_;
  energy_ = CouplingEnergy();
  recorder_ = std::make_unique<PassRecorder>(sim_->model(), kRecorderRowRate);
  recorder_->record(sim_->model(), sim_->state());
  if (holding) {  // the hold goes on from the new static state: nothing left to ramp
    hold_start_time_ = sim_->state().time;
    for (int p : external_) hold_from_[p] = sim_->state().uplift[p];
  }
  diverged_ = dewired_ = false;
  recovering_ = false;
}

// ---- Measurements ----

void HilLoop::reject(const std::string& what) {
  ++c_.rejected;
  if (throttle(kSlotReject, 1.0))
    log(LogLevel::kError, what + "; measurement ignored, the previous one stays in effect (" +
                              std::to_string(c_.rejected) + " rejected so far)");
}

std::string HilLoop::measurement_error(const double* force, std::size_t n_given, const char* field, bool indexed) const {
  const std::size_t n = external_.size();
  if (n_given != n)
    return std::string(field) + " with " + std::to_string(n_given) + " values rejected: the scene has " +
           std::to_string(n) + " external pantograph(s), send one total force (N) each in scene order";
  // The core's check of each value (NaN, inf, range).
  for (std::size_t i = 0; i < n; ++i)
    if (std::string e = Simulation::external_force_error(force[i]); !e.empty())
      return std::string(field) + (indexed ? "[" + std::to_string(i) + "]" : std::string()) + ": " + e;
  return std::string();
}

bool HilLoop::accept(const double* force, std::size_t n_given, double arrival, double measured, std::uint64_t step,
                     const char* field, bool indexed) {
  const std::size_t n = external_.size();
  // A rejected measurement changes nothing.
  if (std::string e = measurement_error(force, n_given, field, indexed); !e.empty()) {
    reject(e);
    return false;
  }
  std::string err;
  for (std::size_t i = 0; i < n; ++i) sim_->set_external_force(external_[i], force[i], &err);  // (checked above)
  for (std::size_t i = 0; i < n; ++i) accept_buf_[i] = sim_->state().external_force[external_[i]];
  if (unused_) ++c_.superseded;
  hold_.accept(accept_buf_, arrival, measured, step);
  if (opt_.extrapolate && hold_.stamps_implausible() && throttle(kSlotStamps, 10.0))
    log(LogLevel::kWarn, "the measurements' own stamps do not advance with their arrivals (less than half or more than "
                         "twice as fast): the extrapolation holds the newest measurement instead; check the rig's "
                         "clock and its unit (nanoseconds)");
  unused_ = true;
  ++c_.accepted;
  // Which period it starts. An answer to the last contact point sent starts the next period (a
  // rig that sends no step is taken as answering the last one). An answer to an older one is
  // late: if the last period ran at its deadline without a measurement, this is the answer that
  // period lacked, so it is held but starts nothing (else it would take the next period and push
  // every later answer a period back); otherwise the rig is a period behind (its round trip is
  // longer than a period) and it starts the next period like any other.
  if (step == 0 || step >= published_step_) {
    fresh_ = true;
    owed_ = false;
  } else {
    ++c_.late;
    if (owed_) owed_ = false;
    else fresh_ = true;
  }
  return true;
}

// ---- The loop ----

void HilLoop::wait_for_period(double w, double half, double& t) {
  // Wait for a fresh measurement inside the window [w - half, w + half], or for the window's end.
  // Blocking costs a wake-up (the thread that received the measurement signals this one); with
  // spin_wait the loop blocks only until that long before a due time (the start of the window for
  // an early measurement, else the expected arrival, the window's centre, on which the windows
  // are locked) and then polls on the steady clock until it is (or, for the arrival, until that
  // long after it).
  const double spin = opt_.spin_wait;
  while (skin_->running() && !stop_) {
    if (fresh_ && t >= w - half) break;
    if (t >= w + half) {
      // The window has closed (the loop is late, e.g. after an overrun): a measurement that is
      // already waiting is still taken for this period rather than running it with the held one.
      if (!fresh_) skin_->receive(t);
      break;
    }
    const double until = fresh_ ? w - half : w + half;
    double block_until = until;
    if (spin > 0.0) {
      const double due = fresh_ ? w - half : w;
      const double spin_end = fresh_ ? until : std::min(until, w + spin);
      if (t < due - spin) block_until = due - spin;
      else if (t < spin_end) block_until = t;  // poll
    }
    skin_->receive(block_until);
    t = steady_now();
  }
}

int HilLoop::run() {
  {
    std::lock_guard<std::mutex> l(ctrl_mu_);
    loop_running_ = true;
  }
  const double period = timing_.period, half = 0.5 * period;
  send_point();
  double w = steady_now() + period;  // centre of the next period's window
  const double start_wait_end = steady_now() + opt_.start_delay;
  if (opt_.start_delay > 0.0) log(LogLevel::kInfo, "measurements ignored for " + fmt(opt_.start_delay) + " s");
  next_quantiles_ = steady_now();
  bool relock = false;  // centre the windows on the next arrival
  int off_centre = 0;   // triggering arrivals in a row more than a quarter period off the centre
  while (skin_->running() && !stop_ && !exit_requested_) {
    double t = steady_now();
    wait_for_period(w, half, t);
    if (!skin_->running() || stop_) break;
    poll_control();
    if (mode_ == Mode::kWaiting && (t < start_wait_end || !armed_)) fresh_ = false;  // (start_delay, arm)
    const bool triggered = fresh_;
    if (mode_ == Mode::kWaiting && triggered) {
      w = t;  // the schedule starts on the rig's first measurement
      if (started_ == 0.0) started_ = t;
      relock = false;
      log(LogLevel::kInfo, "pass " + std::to_string(pass_count_) + ": first measurement received: running");
    } else if (triggered && relock) {
      w = std::max(t, w - half);  // centre the windows on this arrival (never earlier than this window)
      relock = false;
      ++c_.relocks;
    }
    // Jitter: how late the period starts after it was due (the window's start for a measurement
    // that came early, its end without one).
    if (mode_ != Mode::kWaiting && started_ > 0.0) jitter_.add(t - (triggered ? std::max(w - half, hold_.arrival()) : w + half));
    batch(t, triggered);
    // Phase lock on the arrival of the measurement (not on the start of the steps, which waits for
    // the window of an early one). Arrivals far off the centre for many periods in a row (the
    // rig's phase changed) make the next one the centre at once.
    if (triggered) {
      const double offset = hold_.arrival() - w;
      off_centre = std::fabs(offset) > 0.25 * period ? off_centre + 1 : 0;
      if (off_centre >= kRelockPeriods) {
        relock = true;
        off_centre = 0;
      }
      w += period + std::clamp(kLockGain * offset, -kLockMax * period, kLockMax * period);
    } else {
      w += period;
    }
    const double done = steady_now();
    skin_->after_period(done);
    if (done > w + half) {
      // The next window closed before its steps could begin: the loop fell behind. Drop the
      // missed periods (dt is never stretched; simulation time falls behind the wall clock) but
      // keep the windows' phase, which is locked onto the rig.
      ++c_.overruns;
      const double missed = std::ceil((done - (w + half)) / period);
      if (throttle(kSlotOverrun, 5.0))
        log(LogLevel::kWarn, printf_text("overrun: the loop is %.3f ms behind its %g Hz schedule (%lld overruns so far); %g "
                                 "period(s) dropped", (done - w) * 1e3, opt_.rate,
                                 static_cast<long long>(c_.overruns), missed));
      w += missed * period;
      relock = true;  // the windows' phase relative to the rig is lost: the next arrival sets it
    }
  }
  {
    std::lock_guard<std::mutex> l(ctrl_mu_);
    loop_running_ = false;  // (a waiting request is answered at once)
  }
  ctrl_cv_.notify_all();
  return exit_code_;
}

void HilLoop::enter_hold(double t, double age) {
  mode_ = Mode::kHold;
  ++c_.holds;
  hold_start_time_ = sim_->state().time;
  for (int p : external_) hold_from_[p] = sim_->state().external_force[p];
  std::string err;
  sim_->set_target_speed(0.0, &err);
  log(LogLevel::kError, printf_text("no valid %s for %.3f s (> timeout = %g s): safe hold: the train stops (%g m/s^2) and "
                            "the applied force ramps to the static uplift over %g s",
                            opt_.input.c_str(), std::isfinite(age) ? age : (t - started_), opt_.timeout,
                            opt_.hold_deceleration, opt_.hold_ramp));
}

void HilLoop::leave_hold() {
  mode_ = Mode::kRunning;
  recovering_ = true;
  std::string err;
  sim_->set_target_speed(commanded_speed_, &err);
  log(LogLevel::kWarn, printf_text("fresh %s: safe hold ended after %.3f s of simulation; the train accelerates back to "
                           "%.1f km/h", opt_.input.c_str(), sim_->state().time - hold_start_time_,
                           commanded_speed_ * 3.6));
}

void HilLoop::batch(double t, bool triggered) {
  if (mode_ == Mode::kEnded || mode_ == Mode::kPaused || (mode_ == Mode::kWaiting && !triggered)) {
    // (a measurement while waiting starts the run; paused or after the end it changes nothing, but
    // it is held: a pass resumed with the rig still sending is not in the safe hold)
    fresh_ = unused_ = false;
    send_point();
    return;
  }
  if (mode_ == Mode::kWaiting) mode_ = Mode::kRunning;
  const double age = hold_.age(t);
  if (mode_ == Mode::kRunning && age > opt_.timeout) enter_hold(t, age);
  else if (mode_ == Mode::kHold && triggered && !stopping_) leave_hold();
  ++c_.batches;
  if (triggered) ++c_.triggered;
  if (mode_ == Mode::kHold) ++c_.hold_batches;
  else if (!triggered) ++c_.held;
  if (mode_ == Mode::kRunning) c_.max_age_running = std::max(c_.max_age_running, age);
  age_in_effect_ = std::isfinite(age) ? age : -1.0;
  step_in_effect_ = mode_ == Mode::kRunning ? hold_.step() : 0;
  if (mode_ == Mode::kRunning) add_coupling_energy(t);
  step_period(t);
  finish_period(t, triggered);
}

void HilLoop::add_coupling_energy(double t) {
  // Coupling energy of this period (CouplingEnergy): the force applied now against the line's
  // motion now (the last contact point) and against the motion the rig answered.
  // (with delay compensation the answered point stands for the state that much later: what
  // is left is the delay not compensated)
  const std::uint64_t answered =
      hold_.step() > 0 ? hold_.step() + static_cast<std::uint64_t>(std::llround(opt_.delay_compensation / timing_.dt)) : 0;
  const std::size_t slot = answered % kSentHistory;
  const bool known = answered > 0 && answered <= published_step_ && sent_step_[slot] == answered;
  ++energy_.periods;
  if (known) ++energy_.known;
  for (std::size_t i = 0; i < external_.size(); ++i) {
    const double f = std::clamp(hold_.value(i, t, opt_.extrapolate, opt_.timeout), 0.0, Simulation::kMaxExternalForce);
    const double p_line = f * last_pv_[i];
    energy_.interface_j += p_line * timing_.period;
    energy_.peak_power_w = std::max(energy_.peak_power_w, std::fabs(p_line));
    if (known) {
      const double p_rig = f * sent_pv_[slot * external_.size() + i];
      energy_.rig_j += p_rig * timing_.period;
      energy_.delay_j += (p_line - p_rig) * timing_.period;
    }
  }
}

void HilLoop::step_period(double t) {
  const Model& m = sim_->model();
  std::string err;
  for (int j = 0; j < timing_.steps_per_period; ++j) {
    const State& s = sim_->state();
    for (std::size_t i = 0; i < external_.size(); ++i) {
      const int p = external_[i];
      double f;
      if (mode_ == Mode::kHold) {
        const double static_force = s.uplift[p] + m.pantographs[p].aero_coefficient * s.speed * s.speed;
        f = hold_ramp_force(hold_from_[p], static_force, s.time - hold_start_time_, opt_.hold_ramp);
      } else {
        f = hold_.value(i, t + j * timing_.dt, opt_.extrapolate, opt_.timeout);
      }
      f = std::clamp(f, 0.0, Simulation::kMaxExternalForce);
      sim_->set_external_force(p, f, &err);  // (finite and in range: cannot fail)
    }
    if (sim_->finished() || sim_->step() != StepStatus::kOk) break;
    // (the pass statistics leave the safe hold out: the train stands, and the recording would
    // grow for as long as the hold lasts)
    if (mode_ != Mode::kHold) recorder_->record(m, sim_->state());
  }
  if (recovering_ && sim_->state().speed >= sim_->state().target_speed - 1e-9) recovering_ = false;
}

void HilLoop::finish_period(double t, bool triggered) {
  send_point();
  const double published = steady_now();
  compute_.add(published - t);
  if (published - t > timing_.period && throttle(kSlotCompute, 5.0))
    log(LogLevel::kWarn, printf_text("a period's steps and contact point took %.3f ms (period %g ms) at t = %.4f s",
                             (published - t) * 1e3, timing_.period * 1e3, sim_->state().time));
  if (unused_) latency_.add(published - hold_.arrival());  // the first output computed with it
  unused_ = false;
  owed_ = !triggered && mode_ == Mode::kRunning;  // ran at the deadline: its measurement may still come
  if (triggered) wait_.add(t - hold_.arrival());
  fresh_ = false;
  if (published >= next_quantiles_) {
    next_quantiles_ = published + kQuantilePeriod;
    q_latency_[0] = latency_.quantile(0.5);
    q_latency_[1] = latency_.quantile(0.99);
    q_latency_[2] = latency_.max();
    q_jitter_ = summarize_jitter(jitter_);
  }
  handle_end();
}

void HilLoop::send_point() {
  compute_frame(sim_->model(), sim_->state(), timing_.steps_per_period, frame_);
  if (mode_ == Mode::kPaused) {
    // The line is held: the point does not move (an actuator following path_velocity stays put).
    for (PantographPoint& c : frame_.pantographs) {
      c.velocity = c.acceleration = c.path_velocity = 0.0;
      for (ContactPointMotion& w : c.wires) w.velocity = w.acceleration = w.path_velocity = 0.0;
    }
  }
  if (opt_.delay_compensation > 0.0 && mode_ != Mode::kPaused) {
    // Delay compensation: where the wire under the strip will be when the rig imposes it, a loop
    // delay later (first order along the path velocity: the wire's own motion plus the train
    // running along the slope; the velocities are kept).
    const double d = opt_.delay_compensation;
    for (PantographPoint& c : frame_.pantographs) {
      c.height += c.path_velocity * d;
      for (ContactPointMotion& w : c.wires)
        if (w.on_wire) w.height += w.path_velocity * d;
    }
  }
  if (stopping_) {
    point_motion_ = 0.0;
    for (const PantographPoint& c : frame_.pantographs)
      point_motion_ = std::max({point_motion_, std::fabs(c.velocity), std::fabs(c.path_velocity)});
  }
  frame_.mode = mode_;
  frame_.pass_count = pass_count_;
  frame_.measurement_step = step_in_effect_;
  for (PantographPoint& c : frame_.pantographs) c.measurement_age = age_in_effect_;
  if (!all_finite(frame_)) {
    if (throttle(kSlotNonFinite, 1.0))
      log(LogLevel::kError, printf_text("a contact point with a non-finite value was not sent (t = %g s)", sim_->state().time));
    return;
  }
  published_step_ = frame_.step;
  const std::size_t slot = frame_.step % kSentHistory;
  sent_step_[slot] = frame_.step;
  for (std::size_t i = 0; i < frame_.pantographs.size() && i < last_pv_.size(); ++i)
    last_pv_[i] = sent_pv_[slot * external_.size() + i] = frame_.pantographs[i].path_velocity;
  skin_->send(frame_);
}

void HilLoop::handle_end() {
  const State& s = sim_->state();
  if (mode_ == Mode::kEnded) return;
  const bool diverged = s.status == StepStatus::kDiverged;
  // (Simulation::finished() is true for a dewirement too: it is not the end of the line)
  const bool dewired = s.status == StepStatus::kDewired;
  const bool stopped = stopping_ && stop_settled();
  if (!diverged && !dewired && !stopped && !sim_->finished()) return;
  // The pass is over: its statistics are the skin's (filtering takes milliseconds).
  skin_->pass_ended(std::move(recorder_), s);
  recorder_ = std::make_unique<PassRecorder>(sim_->model(), kRecorderRowRate);
  if (diverged) {
    diverged_ = true;
    log(LogLevel::kError, sim_->status_message());
  } else if (dewired) {
    // The scene asks the pass to stop there (pantograph_head.on_dewirement: stop), as
    // simulate_pass does; the line is held and ~arm starts a new pass.
    dewired_ = true;
    log(LogLevel::kError, "pass " + std::to_string(pass_count_) + " " + sim_->status_message() + ": ended");
  } else if (stopping_) {
    log(LogLevel::kInfo, printf_text("pass %u stopped (~stop) at t = %.4f s (train front at %.2f m), the line settled: ended; "
                             "%lld periods, %lld overruns", pass_count_, s.time, s.front + s.line_offset,
                             static_cast<long long>(c_.batches), static_cast<long long>(c_.overruns)));
  } else {
    log(LogLevel::kInfo, printf_text("pass %u finished at t = %.4f s (train front at %.2f m): %lld periods, %lld overruns",
                             pass_count_, s.time, s.front + s.line_offset, static_cast<long long>(c_.batches),
                             static_cast<long long>(c_.overruns)));
  }
  if (!diverged && !dewired && !stopping_ && opt_.at_end == EndAction::kLoop) {
    // A new pass from the initial static state with the static force (no new static solve), the
    // clock running on; pass_count tells the rig to re-initialise.
    for (int p : external_) sim_->set_external_force(p, sim_->state().uplift[p], nullptr);
    sim_->reset(true);
    ++pass_count_;
    energy_ = CouplingEnergy();
    recorder_->record(sim_->model(), sim_->state());
    return;
  }
  mode_ = Mode::kEnded;
  stopping_ = false;
  if (opt_.at_end == EndAction::kExit) {
    exit_requested_ = true;
    exit_code_ = diverged ? 1 : 0;
  }
}

}  // namespace hil
}  // namespace catenary_sim
