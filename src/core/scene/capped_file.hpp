// Reading a file the scene names (the scene itself, an imperfection profile) with a size cap.
#pragma once

#include <cstddef>
#include <istream>
#include <string>

namespace catenary_sim {

// At most cap + 1 bytes of `in`, read in blocks as they come: /dev/zero or a huge file cannot fill
// the memory, and a scene of a few kB costs a few kB (not the cap). A result longer than cap means
// the file is over it.
std::string read_capped(std::istream& in, std::size_t cap);

}  // namespace catenary_sim
