#pragma once
// The effectiveness matrix: what one unit of each motor command produces on
// each axis (rows roll, pitch, yaw, thrust; one column per motor). It is a
// pure function of the geometry; the mixing matrix is derived from it.

#include <motormix/axes.hpp>
#include <motormix/effectiveness/geometry.hpp>
#include <motormix/eigen_layout.hpp>  // Eigen, at the libraries' alignment
#include <motormix/motor_vector.hpp>

#include <vector>

namespace motormix {

using EffectivenessMatrix =
    Eigen::Matrix<double, kNumAxes, Eigen::Dynamic, Eigen::ColMajor, kNumAxes, kMaxMotors>;

// Rotor i with thrust T = thrust_coefficient along `axis` at `position`
// produces torque position x T (roll, pitch, and yaw for tilted rotors) plus
// its drag torque spin * torque_ratio * T about the axis, and collective
// thrust -T.z (up is positive).
EffectivenessMatrix rotor_effectiveness(const std::vector<Rotor>& rotors);

// Wheels in order left, right per row of wheels (front to back): forward
// command = mean of all wheels; turn (yaw, positive counter-clockwise, i.e.
// to the left) = (mean right - mean left) / 2. Roll and pitch rows are zero.
EffectivenessMatrix wheel_effectiveness(const WheelBase& base);

}  // namespace motormix
