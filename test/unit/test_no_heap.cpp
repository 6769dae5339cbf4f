// The per-cycle path allocates nothing: every strategy and the output stage,
// on saturating and non-finite demands, in the core library as built and
// shipped (linked, not compiled again for the test). The net is the C
// library's allocator itself: this program defines malloc and its family,
// which the dynamic linker then resolves for every library in the process,
// so an allocation by Eigen (its aligned_malloc calls malloc), by the
// standard library (operator new calls malloc) or by anything else is
// counted. Each forwards to glibc's own entry point (__libc_malloc, ...).
// Without glibc, a counting global operator new is the net instead.

#include <motormix/allocation/budget_allocator.hpp>
#include <motormix/allocation/clip_allocator.hpp>
#include <motormix/allocation/legacy_budget_allocator.hpp>
#include <motormix/allocation/motor_failure.hpp>
#include <motormix/allocation/optimal_allocator.hpp>
#include <motormix/allocation/prioritized_allocator.hpp>
#include <motormix/allocation/shift_allocator.hpp>
#include <motormix/allocation/yaw_yielding_allocator.hpp>
#include <motormix/effectiveness/presets.hpp>
#include <motormix/mixer.hpp>
#include <motormix/safety/failure_detector.hpp>
#include <motormix/safety/spinning_descent.hpp>

#include <gtest/gtest.h>

#include <atomic>
#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <functional>
#include <limits>
#include <new>
#include <optional>
#include <random>

namespace {
std::atomic<long> g_allocations{0};
std::atomic<bool> g_counting{false};
void count_one() {
  if (g_counting.load(std::memory_order_relaxed)) g_allocations.fetch_add(1);
}
}  // namespace

#if defined(__GLIBC__)
extern "C" {
void* __libc_malloc(std::size_t size);
void* __libc_calloc(std::size_t count, std::size_t size);
void* __libc_realloc(void* p, std::size_t size);
void* __libc_memalign(std::size_t alignment, std::size_t size);
void __libc_free(void* p);

void* malloc(std::size_t size) {
  count_one();
  return __libc_malloc(size);
}
void* calloc(std::size_t count, std::size_t size) {
  count_one();
  return __libc_calloc(count, size);
}
void* realloc(void* p, std::size_t size) {
  count_one();
  return __libc_realloc(p, size);
}
void* aligned_alloc(std::size_t alignment, std::size_t size) {
  count_one();
  return __libc_memalign(alignment, size);
}
void* memalign(std::size_t alignment, std::size_t size) {
  count_one();
  return __libc_memalign(alignment, size);
}
int posix_memalign(void** out, std::size_t alignment, std::size_t size) {
  count_one();
  void* p = __libc_memalign(alignment, size);
  if (p == nullptr) return ENOMEM;
  *out = p;
  return 0;
}
void free(void* p) { __libc_free(p); }
}
#else
void* operator new(std::size_t size) {
  count_one();
  if (void* p = std::malloc(size ? size : 1)) return p;
  throw std::bad_alloc();
}
void* operator new[](std::size_t size) { return operator new(size); }
void operator delete(void* p) noexcept { std::free(p); }
void operator delete[](void* p) noexcept { std::free(p); }
void operator delete(void* p, std::size_t) noexcept { std::free(p); }
void operator delete[](void* p, std::size_t) noexcept { std::free(p); }
#endif

namespace motormix {
namespace {

std::vector<std::unique_ptr<Mixer>> mixers_for(const MixingMatrix& m, bool wheels) {
  const CommandRange range = wheels ? CommandRange{-1.0, 1.0} : CommandRange{0.0, 1.0};
  OutputChannel ch;
  ch.slew_per_s = 1e5;
  ch.thrust_model_factor = wheels ? 0.0 : 0.3;
  if (wheels) ch.mode = OutputMode::kMagnitudeDirection;
  const std::vector<OutputChannel> outputs(static_cast<std::size_t>(m.rows()), ch);
  const ThrustRange thrust = wheels ? ThrustRange::kBipolar : ThrustRange::kUnipolar;
  std::vector<std::unique_ptr<Mixer>> out;
  // Each strategy with every failure set prepared, as the config layer
  // builds it, so the failure paths are counted too.
  using Make = std::function<std::unique_ptr<const Allocator>(const MixingBasis&)>;
  const auto add_reallocating = [&](const Make& make,
                                    std::optional<AirmodeLimits> yaw_yielding = {}) {
    FailurePlan plan = prepare_failures(
        m, range, wheels ? 0.0 : 0.5,
        [&](const FailureMixing& f, const MixingBasis& basis) -> std::unique_ptr<const Allocator> {
          if (yaw_yielding && f.yaw_free) {
            return std::make_unique<YawYieldingAllocator>(basis, *f.yaw_free, range, *yaw_yielding,
                                                          0.15);
          }
          return make(basis);
        });
    out.push_back(std::make_unique<Mixer>(make(MixingBasis(m)), OutputStage(outputs), thrust,
                                          std::move(plan)));
  };
  const auto add = [&](std::unique_ptr<const Allocator> a) {
    out.push_back(std::make_unique<Mixer>(std::move(a), OutputStage(outputs), thrust));
  };
  add_reallocating([&](const MixingBasis& b) { return std::make_unique<ClipAllocator>(b, range); });
  add_reallocating(
      [&](const MixingBasis& b) { return std::make_unique<ShiftAllocator>(b, range); });
  // The named modes and a limited airmode between them.
  for (AirmodeLimits am : {limits_of(Airmode::kOff), limits_of(Airmode::kRollPitch),
                           limits_of(Airmode::kRollPitchYaw), AirmodeLimits{0.3, 0.2}}) {
    add_reallocating(
        [&](const MixingBasis& b) {
          return std::make_unique<PrioritizedAllocator>(b, range, am, 0.15);
        },
        am);
  }
  add_reallocating([&](const MixingBasis& b) {
    return std::make_unique<OptimalAllocator>(b, range, OptimalSettings{});
  });
  if (!wheels) {
    add(std::make_unique<LegacyBudgetAllocator>(m, LegacyBudgets{}));
    add(std::make_unique<BudgetAllocator>(m, LegacyBudgets{}));
  }
  return out;
}

// The net itself: an allocation made inside the core library (a preset's
// vehicle holds strings and vectors) is counted, so a count of zero below
// means none happened, not that none was seen.
TEST(NoHeap, TheNetCountsTheLibrarysAllocations) {
  g_allocations = 0;
  g_counting = true;
  const std::optional<Vehicle> v = find_preset("octo_coax_x8");
  g_counting = false;
  ASSERT_TRUE(v.has_value());
  EXPECT_GT(g_allocations.load(), 0);
}

TEST(NoHeap, EveryStrategyMixesWithoutAllocating) {
  for (const char* name : {"quad_x", "octo_coax_x8", "team_quad", "skid_steer_6"}) {
    SCOPED_TRACE(name);
    const Vehicle v = *find_preset(name);
    const bool wheels = v.thrust_range == ThrustRange::kBipolar;
    const MixingMatrix m =
        v.mixing_table
            ? *v.mixing_table
            : derive_mixing(*v.effectiveness, v.controlled, Normalization::kAxisMax).mixing;
    const auto mixers = mixers_for(m, wheels);
    std::mt19937 rng(5);
    std::uniform_real_distribution<double> wide(-2.0, 2.0);
    std::vector<AxisVector> demands(2000);
    for (auto& d : demands) d << wide(rng), wide(rng), wide(rng), wide(rng);
    demands[7][0] = std::numeric_limits<double>::quiet_NaN();
    MixerOutput out;
    mixers.front()->mix(demands[0], out);  // sizes `out` once, outside the count
    g_allocations = 0;
    g_counting = true;
    // No failure, every single and pair (prepared), a triple (not prepared).
    const MotorMask masks[] = {0, 0b1, 0b10, 0b101, 0b1000, 0b1011};
    for (const auto& mixer : mixers) {
      std::size_t k = 0;
      for (const AxisVector& d : demands) mixer->mix(d, out, 0.0025, masks[k++ % 6]);
      mixer->disarm(out);
    }
    g_counting = false;
    EXPECT_EQ(g_allocations.load(), 0);
  }
}

// The failure detector's per-cycle path: every source judging, a motor
// failing halfway, without one allocation.
TEST(NoHeap, TheFailureDetectorJudgesWithoutAllocating) {
  FailureDetectorSettings settings;
  settings.motors = 8;
  settings.sources = 7;  // telemetry, rates, outputs
  settings.torque_per_thrust = Eigen::Matrix<double, 3, 8>::Random();
  settings.min_residual_nm = 0.1;
  FailureDetector detector(settings);
  MotorVector thrust = MotorVector::Constant(8, 0.5);
  g_allocations = 0;
  g_counting = true;
  for (std::int64_t k = 0; k < 4000; ++k) {
    const std::int64_t t = k * 2500;
    for (int i = 0; i < 8; ++i) {
      detector.on_telemetry(i, i == 3 && k > 2000 ? 0.0 : 9000.0, 10.0, t);
    }
    detector.on_rates(Eigen::Vector3d(0.01 * static_cast<double>(k % 7), 0.0, 0.0), t, t);
    detector.update(thrust, 0, true, t);
  }
  detector.reset();
  g_counting = false;
  EXPECT_EQ(g_allocations.load(), 0);
  EXPECT_EQ(detector.detection().failed, 0U);  // reset forgot the declaration
}

// The spin landing's per-cycle path: the equilibria are solved in the
// constructor; taking over, every cycle (saturated or not, with and without
// a velocity) and landing allocate nothing.
TEST(NoHeap, TheSpinLandingFliesWithoutAllocating) {
  SpinningDescentModel m;
  m.mass_kg = 1.2;
  m.inertia_kgm2 = {0.0202, 0.0202, 0.0398};
  m.rotational_drag = 0.002;
  m.rotor_inertia_kgm2 = 3e-5;
  m.max_rotor_speed_rad_s = 750.0;
  const double a = 0.25 / std::sqrt(2.0);
  const double xy[4][2] = {{a, a}, {-a, -a}, {a, -a}, {-a, a}};
  const double spin[4] = {1, 1, -1, -1};
  for (std::size_t i = 0; i < 4; ++i) {
    const Eigen::Vector3d p(xy[i][0], xy[i][1], 0.0), axis(0.0, 0.0, -1.0);
    m.axis[i] = axis;
    m.torque_per_newton[i] = p.cross(axis) + spin[i] * 0.016 * -axis;
    m.max_thrust_n[i] = 5.88;
    m.spin[i] = spin[i];
  }
  SpinningDescent descent(m, SpinningDescentSettings{});
  ASSERT_TRUE(descent.equilibrium(0).found) << descent.equilibrium(0).why;
  const MotorVector last = MotorVector::Constant(4, 0.5);
  g_allocations = 0;
  g_counting = true;
  descent.start(0, 0, last);
  DescentInput in;
  for (std::int64_t k = 1; k < 4000; ++k) {
    const double t = static_cast<double>(k) * 0.0025;
    in.attitude =
        Eigen::Quaterniond(Eigen::AngleAxisd(0.3 * std::sin(t), Eigen::Vector3d::UnitX()));
    in.rates = {2.0 * std::cos(t), 1.0, 15.0};
    in.velocity = k < 2000 ? Eigen::Vector3d(0.1, 0.0, 1.0) : Eigen::Vector3d::Zero();
    if (k % 500 == 0) in.velocity.setConstant(std::numeric_limits<double>::quiet_NaN());
    descent.update(in, k * 2500);
  }
  g_counting = false;
  EXPECT_EQ(g_allocations.load(), 0);
  EXPECT_EQ(descent.command().phase, DescentPhase::kLanded);  // on the ground at the end
}

}  // namespace
}  // namespace motormix
