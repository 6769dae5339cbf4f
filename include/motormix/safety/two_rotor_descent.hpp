#pragma once
// A quadrotor that has lost two opposite motors still has two rotors that
// push up and turn the body the same way: it can come down spinning about
// its thrust axis with one torque left across it (Mueller & D'Andrea, ICRA
// 2014). The two rotors' differential thrust tilts the body about one axis
// only; the spin and the rotors' own angular momentum turn that one torque
// into control of the thrust axis' whole direction (a spinning body answers
// a torque by precessing, so its rate across the torque follows the rate
// along it). This header is that emergency controller. Pure: time is passed
// in, nothing is allocated after construction, no I/O.
//
// - The plan (plan_two_rotor_descent): which motors are left, how the
//   collective is split so that their torques across the thrust axis cancel,
//   which way the body will spin and the share of the weight the two can
//   carry with room left for control; solved at start-up for each pair.
// - The controller (TwoRotorDescent::update), every cycle:
//   * states: where the thrust axis should point (the world's up, tilted at
//     most max_tilt against the horizontal velocity, seen from the body),
//     the body rates across the axis and the differential thrust through the
//     motors' lag; one input, the differential thrust;
//   * the gain is a linear-quadratic regulator of that model linearized at
//     the spin rate flown, solved at start-up on a grid of spin rates and
//     interpolated (the spin grows for seconds after the failure: the
//     coupling that makes one torque enough grows with it);
//   * the spin rate: the gyro's while inside 90 % of its range, beyond it
//     the model's (the rotors' yaw torque against the drag), never below
//     what the gyro says;
//   * the collective as the three-rotor landing flies it (descent rate from
//     the velocity); the differential first, the collective in what is left;
//   * landing: still after the descent was flown, or the spin lost while
//     still (the ground took it).

#include <motormix/safety/spinning_descent.hpp>
#include <motormix/safety/touchdown.hpp>

#include <Eigen/Core>

#include <array>
#include <cstdint>
#include <string>

namespace motormix {

// What two motors of a four-rotor vehicle can do with the other two
// stopped.
struct TwoRotorPlan {
  bool found = false;
  std::string why;  // when not found: why these two cannot land it
  std::array<int, 2> failed{-1, -1};
  std::array<int, 2> working{-1, -1};
  std::array<double, 2> share{0.5, 0.5};  // of the collective, torques across cancelling
  double spin_sign = 1.0;                 // the body spins this way about body z
  double settled_spin_rad_s = 0.0;        // where the drag would hold it, carrying the weight
  double weight_share = 0.0;              // the weight the two carry with control room left
};

// Start-up only: the plan with motors `first` and `second` (0-based) stopped.
TwoRotorPlan plan_two_rotor_descent(const SpinningDescentModel& model, int first, int second);

class TwoRotorDescent {
 public:
  static constexpr int kStates = 5;  // thrust-axis error x, y; rates across x, y; differential
  static constexpr int kGridPoints = 26;
  static constexpr double kGridTopRadS = 100.0;  // spin rates of the gain grid: 0..this
  using Gain = Eigen::Matrix<double, 1, kStates>;

  TwoRotorDescent(const SpinningDescentModel& model, const SpinningDescentSettings& settings);

  // The plan for `failed` (a set of two motors as bits); nullptr when the
  // set is not two motors of a four-rotor vehicle.
  const TwoRotorPlan* plan(unsigned failed) const;
  // The regulator's gain at spin rate `spin` (rad/s, either sign) with
  // `failed` stopped (a found plan).
  Gain gain(unsigned failed, double spin) const;

  void start(unsigned failed, std::int64_t now_us, const MotorVector& thrust_fraction);
  void stop();
  bool running() const { return cmd_.phase != DescentPhase::kOff; }
  unsigned failed() const { return failed_; }

  const DescentCommand& update(const DescentInput& in, std::int64_t now_us);
  const DescentCommand& command() const { return cmd_; }

 private:
  static int pair_index(unsigned failed);

  SpinningDescentModel m_;
  SpinningDescentSettings s_;
  std::array<TwoRotorPlan, 6> plans_{};
  std::array<std::array<Gain, kGridPoints>, 6> gains_{};
  int pair_ = -1;
  unsigned failed_ = 0;
  std::int64_t last_us_ = 0;
  double velocity_integral_ = 0.0;
  double up_force_ = 0.0;
  double spin_ = 0.0;
  double peak_spin_ = 0.0;
  double lagged_differential_ = 0.0;  // N, working[0] minus working[1], through the lag
  Eigen::Vector2d lagged_n_ = Eigen::Vector2d::Zero();
  Touchdown touchdown_;
  DescentCommand cmd_;
};

}  // namespace motormix
