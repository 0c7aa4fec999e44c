#include "scene/capped_file.hpp"

#include <algorithm>

namespace catenary_sim {

std::string read_capped(std::istream& in, std::size_t cap) {
  std::string text;
  char block[1 << 16];
  while (text.size() <= cap && in) {
    const std::size_t want = std::min(sizeof block, cap + 1 - text.size());
    in.read(block, static_cast<std::streamsize>(want));
    text.append(block, static_cast<std::size_t>(in.gcount()));
  }
  return text;
}

}  // namespace catenary_sim
