#include "catenary_sim/tools/package_files.hpp"

#include <dlfcn.h>
#include <sys/stat.h>

#include <cstdlib>
#include <fstream>
#include <sstream>

namespace catenary_sim {
namespace {

bool is_file(const std::string& path) {
  struct stat st {};
  return ::stat(path.c_str(), &st) == 0 && S_ISREG(st.st_mode);
}

bool is_dir(const std::string& path) {
  struct stat st {};
  return ::stat(path.c_str(), &st) == 0 && S_ISDIR(st.st_mode);
}

std::string parent(const std::string& path) {
  const std::size_t slash = path.find_last_of('/');
  return slash == std::string::npos || slash == 0 ? std::string("/") : path.substr(0, slash);
}

// The real path of the executable or shared library this function was linked into (dladdr: a
// nodelet's library, not the nodelet manager's executable).
std::string this_binary() {
  Dl_info info{};
  if (::dladdr(reinterpret_cast<void*>(&this_binary), &info) == 0 || !info.dli_fname) return "";
  char* real = ::realpath(info.dli_fname, nullptr);
  if (!real) return "";
  const std::string path(real);
  std::free(real);
  return path;
}

// A catkin devel space's source directories: its .catkin file lists them (';'-separated), as
// catkin_find reads it; an install space's .catkin is empty. Each that holds this package (its
// package.xml at the top, or in a catenary_sim folder of a workspace's src) is one.
void add_devel_sources(const std::string& prefix, std::vector<std::string>& dirs) {
  std::ifstream marker(prefix + "/.catkin");
  std::string list;
  if (!marker || !std::getline(marker, list)) return;
  std::istringstream sources(list);
  for (std::string source; std::getline(sources, source, ';');) {
    if (source.empty()) continue;
    for (const std::string& dir : {source, source + "/catenary_sim"})
      if (is_file(dir + "/package.xml") && is_dir(dir + "/scripts")) {
        dirs.push_back(dir);
        break;
      }
  }
}

}  // namespace

std::vector<std::string> package_share_dirs() {
  std::vector<std::string> dirs;
  const std::string binary = this_binary();
  if (!binary.empty()) {
    // lib/catenary_sim/TOOL and lib/libX.so: the prefix is two or one levels above the binary's
    // directory.
    std::string dir = parent(binary);
    for (int up = 0; up < 3 && dir != "/"; ++up, dir = parent(dir)) {
      const std::string share = dir + "/share/catenary_sim";
      if (is_dir(share)) {
        dirs.push_back(share);
        add_devel_sources(dir, dirs);
        break;
      }
    }
  }
  if (const char* prefixes = std::getenv("CMAKE_PREFIX_PATH")) {
    std::istringstream list(prefixes);
    for (std::string prefix; std::getline(list, prefix, ':');)
      if (!prefix.empty()) {
        dirs.push_back(prefix + "/share/catenary_sim");
        add_devel_sources(prefix, dirs);
      }
  }
  return dirs;
}

std::string find_package_file(const std::string& relative) {
  for (const std::string& dir : package_share_dirs())
    if (is_file(dir + "/" + relative)) return dir + "/" + relative;
  return "";
}

std::string find_script(const std::string& name) { return find_package_file("scripts/" + name); }

std::string script_not_found(const std::string& name) {
  std::string where;
  for (const std::string& dir : package_share_dirs()) where += (where.empty() ? "" : ", ") + dir;
  return "scripts/" + name + " not found in " +
         (where.empty() ? std::string("share/catenary_sim beside this binary nor in $CMAKE_PREFIX_PATH") : where);
}

}  // namespace catenary_sim
