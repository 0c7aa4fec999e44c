#include "catenary_sim/hil/realtime.hpp"

#include <pthread.h>
#include <sched.h>
#include <sys/mman.h>
#include <sys/prctl.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <stdexcept>

namespace catenary_sim {
namespace hil {

namespace {

std::string why(int err) {
  if (err == EPERM)
    return "not permitted (needs root, CAP_SYS_NICE / CAP_IPC_LOCK, or an rtprio / memlock limit in "
           "/etc/security/limits.conf)";
  return std::strerror(err);
}

std::string cpu_text(const std::vector<int>& cpus) {
  std::string s;
  for (int c : cpus) s += (s.empty() ? "" : ",") + std::to_string(c);
  return s;
}

}  // namespace

std::vector<int> parse_cpu_list(const std::string& text, const std::string& name) {
  std::vector<int> out;
  std::size_t i = 0;
  auto number = [&](int& v) {
    std::size_t j = i;
    while (j < text.size() && text[j] >= '0' && text[j] <= '9') ++j;
    if (j == i || j - i > 4) return false;
    v = std::stoi(text.substr(i, j - i));
    i = j;
    return true;
  };
  auto bad = [&] {
    return std::invalid_argument(name + " = '" + text + "' rejected: allowed CPU numbers as 2, 2,3 or 0-3");
  };
  if (text.empty()) throw bad();
  while (i < text.size()) {
    int a = 0, b = 0;
    if (!number(a)) throw bad();
    b = a;
    if (i < text.size() && text[i] == '-') {
      ++i;
      if (!number(b) || b < a) throw bad();
    }
    for (int c = a; c <= b; ++c) out.push_back(c);
    if (i < text.size()) {
      if (text[i] != ',') throw bad();
      ++i;
      if (i == text.size()) throw bad();
    }
  }
  return out;
}

std::string check_realtime(const RealtimeOptions& o) {
  const int lo = sched_get_priority_min(SCHED_FIFO), hi = sched_get_priority_max(SCHED_FIFO);
  if (o.fifo_priority != 0 && (o.fifo_priority < lo || o.fifo_priority > hi))
    return o.priority_name + " = " + std::to_string(o.fifo_priority) + " rejected: allowed 0 (normal scheduling) or " +
           std::to_string(lo) + " to " + std::to_string(hi) + " (SCHED_FIFO)";
  const long n = sysconf(_SC_NPROCESSORS_CONF);
  cpu_set_t allowed;
  CPU_ZERO(&allowed);
  sched_getaffinity(0, sizeof allowed, &allowed);
  for (int c : o.cpus) {
    if (c < 0 || c >= n || c >= CPU_SETSIZE)
      return o.cpus_name + " = " + cpu_text(o.cpus) + " rejected: CPU " + std::to_string(c) +
             " does not exist (allowed 0 to " + std::to_string(n - 1) + ")";
    if (!CPU_ISSET(c, &allowed))
      return o.cpus_name + " = " + cpu_text(o.cpus) + " rejected: CPU " + std::to_string(c) +
             " is not in this process's allowed set (taskset, cgroup cpuset)";
  }
  return {};
}

std::string apply_realtime(const RealtimeOptions& o) {
  prctl(PR_SET_TIMERSLACK, 1UL, 0, 0, 0);
  if (std::string e = check_realtime(o); !e.empty()) return e;
  if (!o.cpus.empty()) {
    cpu_set_t set;
    CPU_ZERO(&set);
    for (int c : o.cpus) CPU_SET(c, &set);
    if (const int err = pthread_setaffinity_np(pthread_self(), sizeof set, &set); err != 0)
      return o.cpus_name + " = " + cpu_text(o.cpus) + ": CPU affinity refused: " + why(err);
  }
  if (o.fifo_priority > 0) {
    sched_param sp{};
    sp.sched_priority = o.fifo_priority;
    if (const int err = pthread_setschedparam(pthread_self(), SCHED_FIFO, &sp); err != 0)
      return o.priority_name + " = " + std::to_string(o.fifo_priority) + ": SCHED_FIFO refused: " + why(err);
  }
  if (o.lock_memory && mlockall(MCL_CURRENT | MCL_FUTURE) != 0)
    return o.lock_memory_name + ": mlockall refused: " + why(errno);
  return {};
}

}  // namespace hil
}  // namespace catenary_sim
