#pragma once
// The mixing matrix maps an axis demand to motor commands (one row per motor,
// columns roll, pitch, yaw, thrust): command = M * demand. It is derived from
// the effectiveness matrix by a pseudo-inverse and a normalization, or given
// as a table. Its own pseudo-inverse is the normalized effectiveness that
// tells what a set of motor commands actually produces per axis, which is how
// every strategy reports what it could not deliver.

#include <motormix/axes.hpp>
#include <motormix/effectiveness/effectiveness.hpp>
#include <motormix/eigen_layout.hpp>  // Eigen, at the libraries' alignment
#include <motormix/enum_names.hpp>
#include <motormix/motor_vector.hpp>

#include <cstdint>
#include <string>

namespace motormix {

using MixingMatrix =
    Eigen::Matrix<double, Eigen::Dynamic, kNumAxes, Eigen::RowMajor, kMaxMotors, kNumAxes>;

// Bit per Axis (see bit()).
using AxisMask = std::uint8_t;
inline constexpr AxisMask kAllAxes = 0b1111;

enum class Normalization : std::uint8_t {
  kAxisMax,  // each axis column scaled so its largest magnitude is 1 (0.71 -> 1 on a quad X)
  kPx4,  // roll and pitch share one scale (RMS-based), yaw by its largest entry, thrust by its mean
  kNone,  // the raw pseudo-inverse
};

inline constexpr EnumName<Normalization> kNormalizationNames[] = {
    {Normalization::kAxisMax, "axis_max"},
    {Normalization::kPx4, "px4"},
    {Normalization::kNone, "none"},
};
inline const char* to_string(Normalization value) { return name_in(kNormalizationNames, value); }

struct MixingDerivation {
  MixingMatrix mixing;          // normalized; zero columns for axes not controlled
  AxisVector scale;             // raw column = scale * normalized column
  int rank = 0;                 // rank of the effectiveness rows that are controlled
  AxisMask uncontrollable = 0;  // controlled axes that no motor combination can command alone
  bool ok() const { return uncontrollable == 0; }
};

// Moore-Penrose pseudo-inverse by complete orthogonal decomposition: rank
// revealing like the SVD, cheaper, and exact for the square sign tables of
// quads. Set-up time only.
MixingDerivation derive_mixing(const EffectivenessMatrix& effectiveness, AxisMask controlled,
                               Normalization normalization);

// The normalized effectiveness, pinv(M): produced demand = E * command.
EffectivenessMatrix effectiveness_of(const MixingMatrix& mixing);

// Rank with a tolerance relative to the largest singular value.
int rank_of(const MixingMatrix& mixing);

// Columns that are entirely zero: axes the matrix does not command.
AxisMask controlled_axes(const MixingMatrix& mixing);

// Per axis, the largest pure demand on that axis (others zero, thrust at
// `base_thrust`) that keeps every command within [lower, upper]. Thrust's
// authority is measured from zero torque demand and zero thrust.
AxisVector authority_of(const MixingMatrix& mixing, double base_thrust, double lower, double upper);

}  // namespace motormix
