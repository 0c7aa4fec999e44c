// How late a bare periodic thread wakes up on this machine: the floor under the HIL loop's
// overruns (hardware in the loop). A thread with 1 us timer slack sleeps to absolute
// deadlines on CLOCK_MONOTONIC at `rate` Hz for `seconds` and counts the wake-ups later than
// 0.1, 0.5, 1 and 5 ms. It does nothing else, so lateness here is the machine's (other processes,
// or, on a VM, the hypervisor taking the vCPU away), not the node's. Run it under `chrt -f 50`
// too; a machine fit for the 1 kHz target shows no wake-up later than half a period.
//   bench_timer_jitter [rate=1000] [seconds=20]
#include <sys/prctl.h>
#include <time.h>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include "bench_cli.hpp"
#include "guarded_main.hpp"

static int bench_main(int argc, char** argv) {
  CLI::App app{"How late a bare periodic thread wakes up on this machine: the floor under the HIL loop's overruns.",
               "bench_timer_jitter"};
  double rate = 1000.0, seconds = 20.0;
  app.add_option("rate", rate, "wake-ups per second, Hz")
      ->check(bench::kFinite & CLI::Range(1.0, 100000.0))
      ->capture_default_str();
  app.add_option("seconds", seconds, "s of wall clock")
      ->check(bench::kFinite & bench::positive_up_to(3600.0))
      ->capture_default_str();
  CLI11_PARSE(app, argc, argv);
  prctl(PR_SET_TIMERSLACK, 1UL, 0, 0, 0);
  const long period_ns = static_cast<long>(1e9 / rate);
  const long n = static_cast<long>(seconds * rate);
  const double limits[] = {0.1e-3, 0.5e-3, 1e-3, 5e-3};
  long late[4] = {0, 0, 0, 0};
  double max = 0.0, sum = 0.0;
  timespec next, now;
  clock_gettime(CLOCK_MONOTONIC, &next);
  for (long i = 0; i < n; ++i) {
    next.tv_nsec += period_ns;
    while (next.tv_nsec >= 1000000000L) {
      next.tv_nsec -= 1000000000L;
      ++next.tv_sec;
    }
    clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &next, nullptr);
    clock_gettime(CLOCK_MONOTONIC, &now);
    const double l = static_cast<double>(now.tv_sec - next.tv_sec) + 1e-9 * static_cast<double>(now.tv_nsec - next.tv_nsec);
    for (int k = 0; k < 4; ++k) late[k] += l > limits[k];
    max = std::max(max, l);
    sum += l;
    if (l > 1.0 / rate) next = now;  // a missed period: go on from now (as the HIL loop drops them)
  }
  std::printf("%ld wake-ups at %g Hz: mean lateness %.1f us, max %.2f ms; later than 0.1 ms: %ld, 0.5 ms: %ld, "
              "1 ms: %ld, 5 ms: %ld (%.2f per second later than 0.5 ms)\n",
              n, rate, 1e6 * sum / n, 1e3 * max, late[0], late[1], late[2], late[3], late[1] / seconds);
  return 0;
}

int main(int argc, char** argv) { return bench::guarded_main("bench_timer_jitter", argc, argv, bench_main); }
