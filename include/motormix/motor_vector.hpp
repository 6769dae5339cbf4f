#pragma once
// Per-motor values with a fixed capacity, so the per-cycle path never touches
// the heap: resizing within kMaxMotors only changes a size field.

#include <motormix/eigen_layout.hpp>  // Eigen, at the libraries' alignment

namespace motormix {

inline constexpr int kMaxMotors = 16;

using MotorVector = Eigen::Matrix<double, Eigen::Dynamic, 1, Eigen::ColMajor, kMaxMotors, 1>;

// Bit i refers to motor i; 16 motors fit with room to spare.
using MotorMask = std::uint32_t;

}  // namespace motormix
