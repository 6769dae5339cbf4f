#include "loop/message_checks.hpp"

#include <gtest/gtest.h>

#include <limits>

namespace motormix::test {
namespace {

using loop::check_pid;
using loop::check_setpoint;
using loop::PidSample;
using loop::Rejection;
using loop::SetpointSample;

constexpr std::int64_t kFirst = std::numeric_limits<std::int64_t>::min();

TEST(MessageChecks, SetpointRanges) {
  EXPECT_EQ(check_setpoint({1, 1.0, -1.0, true}, ThrustRange::kUnipolar, kFirst), Rejection::kNone);
  EXPECT_EQ(check_setpoint({1, -0.5, 0, true}, ThrustRange::kUnipolar, kFirst),
            Rejection::kOutOfRange);
  EXPECT_EQ(check_setpoint({1, -0.5, 0, true}, ThrustRange::kBipolar, kFirst), Rejection::kNone);
  EXPECT_EQ(check_setpoint({1, 0.5, 1.0001, true}, ThrustRange::kUnipolar, kFirst),
            Rejection::kOutOfRange);
  EXPECT_EQ(check_setpoint({1, std::numeric_limits<double>::infinity(), 0, true},
                           ThrustRange::kUnipolar, kFirst),
            Rejection::kNonFinite);
}

TEST(MessageChecks, PidRangesAndOrder) {
  EXPECT_EQ(check_pid({5, 1, -1, 0}, kFirst), Rejection::kNone);
  EXPECT_EQ(check_pid({5, 0, std::nan(""), 0}, kFirst), Rejection::kNonFinite);
  EXPECT_EQ(check_pid({5, 0, 0, -2}, kFirst), Rejection::kOutOfRange);
  EXPECT_EQ(check_pid({5, 0, 0, 0}, 5), Rejection::kNone);  // a repeat is fine
  EXPECT_EQ(check_pid({4, 0, 0, 0}, 5), Rejection::kOutOfOrder);
  EXPECT_EQ(check_pid({std::numeric_limits<std::int64_t>::min(), 0, 0, 0},
                      std::numeric_limits<std::int64_t>::max()),
            Rejection::kNone);  // a clock reset, not a reorder; and no overflow
}

}  // namespace
}  // namespace motormix::test
