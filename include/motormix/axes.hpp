#pragma once
// The four control axes a mixer turns into motor commands, and the vector type
// that carries one value per axis through the pipeline.

#include <motormix/eigen_layout.hpp>  // Eigen, at the libraries' alignment

#include <array>
#include <cstdint>

namespace motormix {

// Order matters: it is the column order of every mixing matrix and the order
// used in messages, JSON and YAML.
enum class Axis : int { kRoll = 0, kPitch = 1, kYaw = 2, kThrust = 3 };

inline constexpr int kNumAxes = 4;
inline constexpr std::array<const char*, kNumAxes> kAxisNames = {"roll", "pitch", "yaw", "thrust"};

// roll, pitch, yaw in -1..1; thrust in 0..1 for aircraft (-1..1 forward for
// ground vehicles).
using AxisVector = Eigen::Matrix<double, kNumAxes, 1>;

// Range of the thrust axis: aircraft push only up (0..1); ground vehicles
// drive both ways (-1..1).
enum class ThrustRange : std::uint8_t { kUnipolar, kBipolar };

// Lowest thrust (throttle) demand of the range; the highest is always 1.
constexpr double thrust_floor(ThrustRange range) {
  return range == ThrustRange::kUnipolar ? 0.0 : -1.0;
}

constexpr int index(Axis axis) { return static_cast<int>(axis); }
constexpr std::uint8_t bit(Axis axis) { return static_cast<std::uint8_t>(1U << index(axis)); }

}  // namespace motormix
