// Golden hashes: the results that must not move. Each reference pass hashes its state (the
// vertical plane's u and v, the lateral plane's y and v on a 3-D line) and its contact forces
// after every step, and the hash is compared with the one recorded when the pass was last
// verified (against analytic solutions, published data and finer solutions: test_reference_pass,
// test_calpe_example, BENCHMARKS.md). A refactoring keeps every hash bit for bit; a change of the
// numerics changes a hash on purpose, and the commit that records the new hash says why.
//
// A pass on a finite line is hashed whole, from the statics to the train's end (every path of the
// step is taken there: droppers going slack, contact lost and regained, the window's shift, an
// overlap's second wire, the end anchors). The endless line has no end: it is hashed over a fixed
// number of steps, several spans of travel with its block shifted under the train many times.
//
// On a mismatch the message prints the new hash: paste it only together with the reason.
#include <cctype>
#include <cstdint>
#include <cstdio>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "catenary_sim/core/simulation.hpp"
#include "../support/scenes.hpp"

using namespace catenary_sim;

namespace {

struct GoldenPass {
  const char* name;
  std::string scene_file;                 // under config/
  std::vector<std::string> overrides;     // --set style
  long max_steps;
  long expected_steps;
  std::uint64_t expected_hash;
};

// FNV-1a over the bytes of the doubles: any change of any bit of any value changes the hash.
struct Fnv1a {
  std::uint64_t value = 1469598103934665603ull;
  void mix(const double* p, std::size_t n) {
    const unsigned char* c = reinterpret_cast<const unsigned char*>(p);
    for (std::size_t i = 0; i < 8 * n; ++i) value = (value ^ c[i]) * 1099511628211ull;
  }
};

struct PassHash {
  long steps = 0;
  std::uint64_t hash = 0;
};

PassHash hash_pass(const GoldenPass& pass) {
  Simulation sim(load_scene_file(test_scenes::kConfigDir + pass.scene_file, pass.overrides));
  Fnv1a h;
  PassHash r;
  while (r.steps < pass.max_steps && sim.step() == StepStatus::kOk) {
    ++r.steps;
    const State& s = sim.state();
    h.mix(s.u.data(), s.u.size());
    h.mix(s.v.data(), s.v.size());
    h.mix(s.contact_force.data(), s.contact_force.size());
    if (sim.model().lateral) {
      h.mix(s.lateral.y.data(), s.lateral.y.size());
      h.mix(s.lateral.v.data(), s.lateral.v.size());
    }
  }
  r.hash = h.value;
  return r;
}

std::string hex(std::uint64_t v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "0x%016llxull", static_cast<unsigned long long>(v));
  return buf;
}

class GoldenHashes : public ::testing::TestWithParam<GoldenPass> {};

TEST_P(GoldenHashes, PassIsBitForBitTheRecordedOne) {
  const GoldenPass& pass = GetParam();
  const PassHash r = hash_pass(pass);
  EXPECT_EQ(r.steps, pass.expected_steps) << pass.name << ": steps taken";
  EXPECT_EQ(r.hash, pass.expected_hash)
      << pass.name << ": the pass's results moved; new hash " << hex(r.hash)
      << " (record it only with the reason in the commit)";
}

constexpr long kWhole = 100000000;  // more steps than any finite pass takes: the whole pass
const GoldenPass kPasses[] = {
    {"2-D, half-step (accurate)", "reference_55m.yaml", {}, kWhole, 7586, 0x3ae4fd040558571eull},
    {"2-D, centred damping (reference preset)", "reference_55m.yaml", {"numerics.preset=reference"}, kWhole, 80053, 0x445d37de0e508977ull},
    {"2-D, implicit", "reference_55m.yaml", {"numerics.integrator=implicit"}, kWhole, 6601, 0x86ece6bdc6fab455ull},
    {"2-D, moving window", "reference_55m.yaml", {"numerics.window=auto"}, kWhole, 7586, 0x5df456e6689565b2ull},
    {"2-D, endless line", "reference_55m_endless.yaml", {}, 20000, 20000, 0xa13d7368667b81a5ull},
    {"two sections with an overlap", "reference_55m_two_sections.yaml", {}, kWhole, 14754, 0x0233cbdea71c09eeull},
    {"two pantographs", "reference_55m_two_pantographs.yaml", {}, kWhole, 12707, 0x962d91cef7d7987full},
    {"two-head pantograph", "reference_55m_two_heads.yaml", {}, kWhole, 7774, 0x6a93414a9ecc75f4ull},
    {"3-D, stagger and turbulent wind", "reference_55m_3d.yaml", {}, kWhole, 7586, 0x0ebe0c4b703f3953ull},
};

INSTANTIATE_TEST_SUITE_P(ReferencePasses, GoldenHashes, ::testing::ValuesIn(kPasses),
                         [](const ::testing::TestParamInfo<GoldenPass>& info) {
                           std::string n;
                           for (const char* c = info.param.name; *c; ++c)
                             n += std::isalnum(static_cast<unsigned char>(*c)) ? *c : '_';
                           return n;
                         });

}  // namespace
