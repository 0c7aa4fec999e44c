// Child processes for the tests that run the tools and nodes as a user would (fuzz of bad input,
// the pass report, bags and replays): spawn with stdout and stderr to a log file, wait with a time
// limit, kill a hung child, and report how it ended; a scratch directory and a free port for a
// master of the test's own. Header-only; POSIX.
#pragma once

#include <arpa/inet.h>
#include <fcntl.h>
#include <netinet/in.h>
#include <signal.h>
#include <spawn.h>
#include <sys/socket.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <chrono>
#include <cstring>
#include <fstream>
#include <sstream>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

extern char** environ;

namespace catenary_sim_test {

inline std::string slurp(const std::string& path) {
  std::ifstream f(path);
  std::stringstream s;
  s << f.rdbuf();
  return s.str();
}

inline bool exists(const std::string& path) {
  struct stat st {};
  return stat(path.c_str(), &st) == 0;
}

// A new directory of the test's own, /tmp/<prefix>XXXXXX.
inline std::string temp_dir(const std::string& prefix) {
  std::string t = "/tmp/" + prefix + "XXXXXX";
  if (!mkdtemp(&t[0])) throw std::runtime_error("cannot make " + t + ": " + std::strerror(errno));
  return t;
}

// A TCP port free on the loopback interface (for a master of the test's own), 0 if none.
inline int free_port() {
  const int fd = socket(AF_INET, SOCK_STREAM, 0);
  sockaddr_in a{};
  a.sin_family = AF_INET;
  a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  socklen_t len = sizeof a;
  int port = 0;
  if (bind(fd, reinterpret_cast<sockaddr*>(&a), sizeof a) == 0 && getsockname(fd, reinterpret_cast<sockaddr*>(&a), &len) == 0)
    port = ntohs(a.sin_port);
  close(fd);
  return port;
}

struct ChildRun {
  int exit_code = -1;  // -1: did not exit (killed by a signal, hung or never started)
  int signal = 0;      // the signal that ended it, 0 if none
  bool hung = false;   // killed after the time limit
  std::string out;     // stdout and stderr
};

class Child {
 public:
  // Starts args[0] with stdin from /dev/null, stdout and stderr to `log`, and `env` ("NAME=value")
  // added before the test's own environment (the first of a name wins in getenv).
  Child(const std::vector<std::string>& args, const std::string& log, const std::vector<std::string>& env = {})
      : log_(log) {
    std::vector<char*> argv;
    for (const std::string& a : args) argv.push_back(const_cast<char*>(a.c_str()));
    argv.push_back(nullptr);
    std::vector<std::string> envs = env;
    for (char** e = environ; *e; ++e) envs.push_back(*e);
    std::vector<char*> envp;
    for (std::string& e : envs) envp.push_back(&e[0]);
    envp.push_back(nullptr);
    posix_spawn_file_actions_t fa;
    posix_spawn_file_actions_init(&fa);
    posix_spawn_file_actions_addopen(&fa, 0, "/dev/null", O_RDONLY, 0);
    posix_spawn_file_actions_addopen(&fa, 1, log.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    posix_spawn_file_actions_adddup2(&fa, 1, 2);
    if (posix_spawn(&pid_, argv[0], &fa, nullptr, argv.data(), envp.data()) != 0) pid_ = -1;
    posix_spawn_file_actions_destroy(&fa);
  }
  Child(const Child&) = delete;
  Child& operator=(const Child&) = delete;
  ~Child() {
    if (pid_ > 0) {
      kill(pid_, SIGKILL);
      waitpid(pid_, nullptr, 0);
    }
  }

  bool started() const { return pid_ > 0; }
  pid_t pid() const { return pid_; }

  // Waits up to `limit` s, then kills it (SIGKILL) and reports it as hung.
  ChildRun wait(double limit) {
    ChildRun r;
    if (pid_ <= 0) {
      r.out = "spawn failed";
      return r;
    }
    const auto deadline = std::chrono::steady_clock::now() + std::chrono::duration<double>(limit);
    int status = 0;
    while (waitpid(pid_, &status, WNOHANG) == 0) {
      if (std::chrono::steady_clock::now() > deadline) {
        kill(pid_, SIGKILL);
        waitpid(pid_, &status, 0);
        r.hung = true;
        break;
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(5));
    }
    pid_ = -1;
    if (WIFEXITED(status)) r.exit_code = WEXITSTATUS(status);
    if (WIFSIGNALED(status)) r.signal = WTERMSIG(status);
    r.out = slurp(log_);
    return r;
  }

 private:
  std::string log_;
  pid_t pid_ = -1;
};

// Runs a command to its end (at most `limit` s) with its output in `log`.
inline ChildRun run_child(const std::vector<std::string>& args, const std::string& log, double limit,
                          const std::vector<std::string>& env = {}) {
  return Child(args, log, env).wait(limit);
}

}  // namespace catenary_sim_test
