#pragma once
// The mixing matrix maps an axis demand to motor commands (one row per motor,
// columns roll, pitch, yaw, thrust): command = M * demand. Its pseudo-inverse
// is the normalized effectiveness matrix that tells what a set of motor
// commands actually produces on each axis, which is how every strategy
// reports what it could not deliver.

#include <motormix/axes.hpp>
#include <motormix/motor_vector.hpp>

#include <Eigen/Core>

namespace motormix {

using MixingMatrix =
    Eigen::Matrix<double, Eigen::Dynamic, kNumAxes, Eigen::RowMajor, kMaxMotors, kNumAxes>;

// kNumAxes x motors; produced = E * command.
using EffectivenessMatrix =
    Eigen::Matrix<double, kNumAxes, Eigen::Dynamic, Eigen::ColMajor, kNumAxes, kMaxMotors>;

// Moore-Penrose pseudo-inverse of the mixing matrix (complete orthogonal
// decomposition: rank-revealing and exact for the square sign tables of
// quads). Called at set-up only.
EffectivenessMatrix effectiveness_of(const MixingMatrix& mixing);

// Rank of the mixing matrix with a tolerance relative to its largest singular
// value; a matrix that cannot command all four axes has rank < 4.
int rank_of(const MixingMatrix& mixing);

}  // namespace motormix
