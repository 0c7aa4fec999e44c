// Real-time set-up of a loop thread (docs/hil.md, "Preparing a rig PC"): memory locked, SCHED_FIFO
// priority, CPU affinity. Each setting is checked, and a refusal names the option, the value and
// why (not permitted, out of range, no such CPU). ROS-free.
#pragma once

#include <string>
#include <vector>

namespace catenary_sim {
namespace hil {

struct RealtimeOptions {
  bool lock_memory = false;  // mlockall(MCL_CURRENT | MCL_FUTURE): no page faults in the loop
  int fifo_priority = 0;     // > 0: SCHED_FIFO at this priority for the calling thread, [0, 99]
  std::vector<int> cpus;     // the calling thread on these CPUs only (empty: unchanged)
  // How the options are named in errors (a command line's --flags or a node's ~params).
  std::string lock_memory_name = "--lock-memory", priority_name = "--fifo-priority", cpus_name = "--cpus";
};

// Empty when valid, else the error (ranges and CPUs that exist), without changing anything.
std::string check_realtime(const RealtimeOptions& o);
// Applies the options to the calling thread; empty on success, else the first error (later
// options are not applied). Timer slack is set to 1 us in any case (wake-ups on time).
std::string apply_realtime(const RealtimeOptions& o);
// Parses "2", "2,3" or "0-3" into CPU numbers; throws std::invalid_argument naming `name`.
std::vector<int> parse_cpu_list(const std::string& text, const std::string& name);

}  // namespace hil
}  // namespace catenary_sim
