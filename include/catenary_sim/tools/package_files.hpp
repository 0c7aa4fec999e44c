// The package's own files (scripts/, config/) found at run time from where the running binary
// lies, so that a binary carries no path of the tree it was built in and runs wherever it is
// installed: <prefix>/lib/catenary_sim/TOOL (or <prefix>/lib/libX.so) looks in
// <prefix>/share/catenary_sim, where an install space holds copies; a devel space holds none and
// names its sources in <prefix>/.catkin (catkin's record, read as catkin_find reads it).
#pragma once

#include <string>
#include <vector>

namespace catenary_sim {

// The directories looked in, in order: share/catenary_sim beside the binary or library this code
// is linked into and, if that prefix is a devel space, the package's sources; then the same for
// each PREFIX of $CMAKE_PREFIX_PATH (a sourced workspace's).
std::vector<std::string> package_share_dirs();

// A file of the package by its path in it (e.g. config/reference_55m.yaml); empty if none of
// package_share_dirs() has it.
std::string find_package_file(const std::string& relative);

// scripts/NAME of the package; empty if not found.
std::string find_script(const std::string& name);

// "scripts/NAME not found in DIR, DIR, ...": why find_script(NAME) came back empty.
std::string script_not_found(const std::string& name);

}  // namespace catenary_sim
