// Identical inputs give bit-identical output, and step() never allocates.
#include <gtest/gtest.h>

#include <atomic>
#include <cstdlib>
#include <cstring>
#include <new>

#include "catenary_sim/core/simulation.hpp"
#include "../support/scenes.hpp"

// Count every allocation made through operator new while counting is on.
static std::atomic<bool> g_counting{false};
static std::atomic<long> g_allocations{0};

void* operator new(std::size_t n) {
  if (g_counting) ++g_allocations;
  if (void* p = std::malloc(n ? n : 1)) return p;
  throw std::bad_alloc();
}
void* operator new[](std::size_t n) { return operator new(n); }
// (These pair with the operator new above, through malloc. GCC's new/delete pairing check sees
// only a free() of operator new's memory where it inlines a copied container's storage here.)
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wmismatched-new-delete"
void operator delete(void* p) noexcept { std::free(p); }
void operator delete[](void* p) noexcept { std::free(p); }
void operator delete(void* p, std::size_t) noexcept { std::free(p); }
void operator delete[](void* p, std::size_t) noexcept { std::free(p); }
#pragma GCC diagnostic pop

using namespace catenary_sim;

namespace {
using test_scenes::kReference;
}

TEST(Determinism, IdenticalInputsGiveBitIdenticalOutput) {
  const Scene scene = load_scene_file(kReference);
  Simulation a(scene), b(scene);
  for (int i = 0; i < 3000; ++i) {
    ASSERT_EQ(a.step(), StepStatus::kOk);
    ASSERT_EQ(b.step(), StepStatus::kOk);
    ASSERT_EQ(0, std::memcmp(a.state().contact_force.data(), b.state().contact_force.data(),
                             sizeof(double) * a.state().contact_force.size())) << "step " << i;
  }
  EXPECT_EQ(0, std::memcmp(a.state().u.data(), b.state().u.data(), sizeof(double) * a.state().u.size()));
  EXPECT_EQ(0, std::memcmp(a.state().v.data(), b.state().v.data(), sizeof(double) * a.state().v.size()));
  // A reset pass repeats the first one exactly (only the clock keeps running).
  Simulation c(scene);
  for (int i = 0; i < 500; ++i) c.step();
  c.reset(true);
  Simulation d(scene);
  for (int i = 0; i < 500; ++i) {
    c.step();
    d.step();
  }
  EXPECT_EQ(0, std::memcmp(c.state().u.data(), d.state().u.data(), sizeof(double) * c.state().u.size()));
  EXPECT_GT(c.state().time, d.state().time);
}

TEST(Allocation, StepNeverAllocates) {
  // The lumped-rotation variant, the implicit integrator and a moving force exercise the other
  // code paths.
  for (const std::vector<std::string>& ov :
       {std::vector<std::string>{}, std::vector<std::string>{"numerics.rotary_inertia=lumped"},
        std::vector<std::string>{"numerics.integrator=implicit"}, std::vector<std::string>{"numerics.window=auto"},
        std::vector<std::string>{"numerics.window=auto", "numerics.damping=centred"},
        std::vector<std::string>{"pantographs.0.type=moving_force", "pantographs.0.masses=null",
                                 "pantographs.0.stiffness=null", "pantographs.0.damping=null"}}) {
    Simulation sim(load_scene_file(kReference, ov));
    sim.step();  // warm-up outside the counted region
    g_allocations = 0;
    g_counting = true;
    for (int i = 0; i < 2000; ++i) sim.step();
    g_counting = false;
    EXPECT_EQ(g_allocations.load(), 0) << "step() allocated with overrides of size " << ov.size();
    EXPECT_EQ(sim.state().status, StepStatus::kOk);
  }
  // The endless line: 2000 steps run 145 m, so the block is moved back at least twice (and, with
  // the centred step, its window factors rebuilt).
  for (const char* damping : {"half_step", "centred"}) {
    Simulation endless(load_scene_file(test_scenes::kReferenceEndless, {std::string("numerics.damping=") + damping}));
    const double offset0 = endless.state().line_offset;
    endless.step();
    g_allocations = 0;
    g_counting = true;
    for (int i = 0; i < 2000; ++i) endless.step();
    g_counting = false;
    EXPECT_EQ(g_allocations.load(), 0) << "step() allocated on the endless line, damping " << damping;
    EXPECT_GE(endless.state().line_offset - offset0, 2 * 55.0);
  }
}

// The 3-D line's paths: a turbulent wind on the whole line, the moving window (which keeps a
// turbulent wind's lateral plane whole, and windows a steady wind's), the two-way dropper coupling,
// sway, the wind in the uplift, and the endless line moving its block: no allocation in step(),
// and two passes of one scene give the same bits, lateral state included.
TEST(Allocation, ThreeDimensionalStepNeverAllocatesAndRepeatsItsBits) {
  const std::string three_d = test_scenes::kReference3d;
  const std::vector<std::string> sway = {"pantograph_head.sway.amplitude=0.03", "pantograph_head.sway.frequency=0.8",
                                         "pantographs.0.aero_coefficient=0.005"};
  struct Case {
    std::string file;
    std::vector<std::string> overrides;
    bool endless = false;  // the file's line made endless (test_scenes::endless_scene)
  };
  // The stitched 3-D line too: its clamps in plan on the whole line, in the window and on the
  // endless block (whose moves hand each stitch wire's lateral state on).
  const std::string stitched = test_scenes::kReferenceStitched3d;
  std::vector<Case> cases = {{three_d, {}}, {three_d, {"numerics.window=auto"}},
                             {three_d, {"numerics.window=auto", "wind.turbulence=null"}},
                             {test_scenes::kReferenceEndless,
                              {"stagger.contact_wire=[0.3,-0.3]", "stagger.messenger=[0.0]", "wind.speed=20",
                               "wind.turbulence.intensity=0.15", "alignment.radius=1200"}},
                             {stitched, {}},
                             {stitched, {"numerics.window=auto", "wind.turbulence=null"}},
                             {stitched, {"numerics.window=auto", "numerics.preset=balanced", "train.start=1650", "train.end=5500"}, true}};
  // Hinged steady arms held across the track, their registrations moving with the uplift and the
  // wire's answer acting on the arms: on the whole line, in the window and on the endless block.
  const std::vector<std::string> hinged = {"steady_arms.stiffness=null", "steady_arms.mass=null", "steady_arms.length=1.15",
                                           "steady_arms.linear_mass=0.78", "steady_arms.clamp_mass=0.46",
                                           "stagger.steady_arm_stiffness=null", "wind.turbulence=null"};
  for (std::vector<std::string> ov : {std::vector<std::string>{}, std::vector<std::string>{"numerics.window=auto"}}) {
    ov.insert(ov.end(), hinged.begin(), hinged.end());
    cases.push_back({three_d, ov});
  }
  {
    std::vector<std::string> ov = {"stagger.contact_wire=[0.3,-0.3]", "stagger.messenger=[0.0]", "wind.speed=20"};
    ov.insert(ov.end(), hinged.begin(), hinged.end() - 1);
    cases.push_back({test_scenes::kReferenceEndless, ov});
  }
  // The same with the centred damping step in both planes.
  const std::size_t half_step_cases = cases.size();
  for (std::size_t k = 0; k < half_step_cases; ++k) {
    cases.push_back(cases[k]);
    cases.back().overrides.push_back("numerics.damping=centred");
  }
  for (Case& c : cases) {
    c.overrides.insert(c.overrides.end(), sway.begin(), sway.end());
    const Scene scene = c.endless ? test_scenes::endless_scene(c.file, c.overrides) : load_scene_file(c.file, c.overrides);
    Simulation a(scene), b(scene);
    ASSERT_TRUE(a.model().lateral);
    a.step();
    b.step();
    const double offset = a.state().line_offset;
    g_allocations = 0;
    g_counting = true;
    for (int i = 0; i < 2000; ++i) a.step();
    g_counting = false;
    EXPECT_EQ(g_allocations.load(), 0) << "step() allocated on " << c.file << " with " << c.overrides.size()
                                       << " overrides";
    // The endless line's block moved in the steps counted: its turbulent field generated the
    // points ahead (wind_field.hpp) in them.
    if (a.model().endless) {
      EXPECT_GT(a.state().line_offset, offset);
    }
    for (int i = 0; i < 2000; ++i) b.step();
    // Restoring a snapshot into a state of the same model (a skin's undo) allocates nothing
    // either: the lateral plane's buffers, its workspace and the endless line's turbulent field
    // (with its FFT plan) keep their storage.
    State restored = a.state();
    g_allocations = 0;
    g_counting = true;
    restored = b.state();
    g_counting = false;
    EXPECT_EQ(g_allocations.load(), 0) << "restoring a snapshot allocated with " << c.overrides.size() << " overrides";
    // A copy keeps the room of the dewirement log, which step() fills without allocating.
    EXPECT_GE(restored.lateral.events.capacity(), kMaxDewirementEvents);
    const State copied(b.state());
    EXPECT_GE(copied.lateral.events.capacity(), kMaxDewirementEvents);
    ASSERT_EQ(a.state().status, StepStatus::kOk);
    ASSERT_EQ(a.state().lateral.y.size(), b.state().lateral.y.size());
    EXPECT_EQ(0, std::memcmp(a.state().u.data(), b.state().u.data(), sizeof(double) * a.state().u.size()));
    EXPECT_EQ(0, std::memcmp(a.state().lateral.y.data(), b.state().lateral.y.data(),
                             sizeof(double) * a.state().lateral.y.size()));
    EXPECT_EQ(0, std::memcmp(a.state().lateral.v.data(), b.state().lateral.v.data(),
                             sizeof(double) * a.state().lateral.v.size()));
  }
}
