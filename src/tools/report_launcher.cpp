#include "catenary_sim/tools/report_launcher.hpp"

#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>

#include "catenary_sim/tools/package_files.hpp"

extern char** environ;

namespace catenary_sim {

std::string find_pass_report_script() { return find_script("pass_report"); }

pid_t start_python_script(const std::string& script, const std::vector<std::string>& args, std::string* why) {
  const char* python = "/usr/bin/python3";
  if (::access(python, X_OK) != 0) {
    *why = "/usr/bin/python3 is missing: install python3, python3-numpy and python3-matplotlib (scripts/setup)";
    return -1;
  }
  std::vector<std::string> all{python, script};
  all.insert(all.end(), args.begin(), args.end());
  std::vector<char*> argv;
  for (std::string& a : all) argv.push_back(a.data());
  argv.push_back(nullptr);
  pid_t pid = 0;
  if (posix_spawn(&pid, python, nullptr, nullptr, argv.data(), environ) != 0) {
    *why = "cannot start " + std::string(python);
    return -1;
  }
  return pid;
}

pid_t start_pass_report(const std::string& dir, const std::string& html, bool quiet, std::string* why) {
  const std::string script = find_pass_report_script();
  if (script.empty()) {
    *why = script_not_found("pass_report");
    return -1;
  }
  std::vector<std::string> args{dir};
  if (!html.empty()) {
    args.push_back("--html");
    args.push_back(html);
  }
  if (quiet) args.push_back("--quiet");
  return start_python_script(script, args, why);
}

int pass_report_status(pid_t pid, bool block) {
  int status = 0;
  for (;;) {
    const pid_t r = ::waitpid(pid, &status, block ? 0 : WNOHANG);
    if (r == pid) break;
    if (r == 0) return kReportRunning;
    if (errno != EINTR) return kReportLost;
  }
  return WIFEXITED(status) ? WEXITSTATUS(status) : 128 + (WIFSIGNALED(status) ? WTERMSIG(status) : 0);
}

}  // namespace catenary_sim
