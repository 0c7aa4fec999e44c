// Seeded normal draws for the built line's imperfections (internal to the core).
#pragma once

#include <cmath>
#include <cstdint>
#include <random>

namespace catenary_sim {

// Normal errors from one mt19937_64 by Box-Muller: the same numbers on every machine (the
// standard library's normal_distribution is not specified bit for bit across implementations).
class NormalErrors {
 public:
  explicit NormalErrors(std::uint64_t seed) : gen_(seed) {}
  double uniform() { return (static_cast<double>(gen_() >> 11) + 0.5) * 0x1.0p-53; }  // (0, 1)
  double next(double std_dev) {
    const double u1 = uniform(), u2 = uniform();
    return std_dev * std::sqrt(-2.0 * std::log(u1)) * std::cos(2.0 * M_PI * u2);
  }

 private:
  std::mt19937_64 gen_;
};

}  // namespace catenary_sim
