// simulate_pass's side of the bag writer: finds and loads libcatenary_sim_pass_bag.so.
#include <dlfcn.h>

#include <climits>
#include <cstdlib>

#include "catenary_sim/core/output/output_files.hpp"
#include "pass_bag_writer.hpp"

namespace catenary_sim {
namespace {

constexpr const char* kLibrary = "libcatenary_sim_pass_bag.so";

// <prefix>/lib/ of this program, which lies in <prefix>/lib/catenary_sim/; empty if unknown.
std::string prefix_lib() {
  char* real = ::realpath("/proc/self/exe", nullptr);
  if (!real) return "";
  std::string path(real);
  std::free(real);
  for (int up = 0; up < 2; ++up) {
    const std::size_t slash = path.find_last_of('/');
    if (slash == std::string::npos || slash == 0) return "";
    path.erase(slash);
  }
  return path;
}

}  // namespace

std::unique_ptr<PassBagWriter> open_pass_bag(const std::string& path, double rate) {
  // Once per process, and never closed: the writer's code stays mapped until the program ends.
  static void* library = nullptr;
  std::string why;
  if (!library) {
    const std::string beside = prefix_lib();
    if (!beside.empty()) library = ::dlopen((beside + "/" + kLibrary).c_str(), RTLD_NOW | RTLD_LOCAL);
    if (!library) {
      const char* e = ::dlerror();
      why = e ? e : "";
      library = ::dlopen(kLibrary, RTLD_NOW | RTLD_LOCAL);
    }
    if (!library) {
      const char* e = ::dlerror();
      throw OutputError("the bag writer " + std::string(kLibrary) + " cannot be loaded (" + (why.empty() ? "" : why + "; ") +
                        (e ? e : "not found") + "); it is built and installed with simulate_pass");
    }
  }
  const auto open = reinterpret_cast<PassBagOpen>(::dlsym(library, CATENARY_SIM_PASS_BAG_OPEN));
  if (!open) throw OutputError("the bag writer " + std::string(kLibrary) + " has no " + CATENARY_SIM_PASS_BAG_OPEN);
  return std::unique_ptr<PassBagWriter>(open(path, rate));
}

}  // namespace catenary_sim
