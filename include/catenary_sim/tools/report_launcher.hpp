// The pass report (scripts/pass_report) and the other Python drawings, run as a child process
// (matplotlib takes seconds) by simulate_pass --report, pantograph_frf and the node's
// ~report_file; the core only writes the files they read (core/output/pass_files.hpp).
#pragma once

#include <sys/types.h>

#include <string>
#include <vector>

namespace catenary_sim {

std::string find_pass_report_script();

// Starts /usr/bin/python3 SCRIPT ARGS... with its output going to ours; returns its pid, or -1
// with the reason in *why. Wait for it with pass_report_status(pid, true).
pid_t start_python_script(const std::string& script, const std::vector<std::string>& args, std::string* why);

// Starts /usr/bin/python3 scripts/pass_report DIR [--html HTML] [--quiet] with its output going to
// ours; returns its pid, or -1 with the reason in *why.
pid_t start_pass_report(const std::string& dir, const std::string& html, bool quiet, std::string* why);

// The report's exit status: 0 written, 2 bad input, 3 matplotlib missing, 128 + signal;
// kReportRunning while it is still running (block = false); kReportLost if pid is not our child.
constexpr int kReportRunning = -1, kReportLost = -2;
int pass_report_status(pid_t pid, bool block);

}  // namespace catenary_sim
