#pragma once
// What of the real world `motormix sim` plays, each piece on by default and
// each switchable off to compare with the idealized vehicle (docs/simulation.md
// says where each piece's numbers come from):
//
//   rotor_momentum  the rotors' angular momentum: gyroscopic torque, and the
//                   reaction torque of speeding a rotor up or slowing it down
//   spin_down       an unbraked ESC: a rotor slows more slowly than it speeds
//                   up (off: both at the speeding-up time constant)
//   imu             the gyro sampled at vehicle.imu.rate_hz with vibration at
//                   the rotor frequency and its second harmonic, bias drift and
//                   the flight controller's low-pass filter (off: the true
//                   rates with white noise and a constant bias)
//   esc_latency     ESC telemetry arrives late and with jitter
//   ground_effect   more thrust within one rotor diameter of the ground
//
// And the model error: the simulated vehicle differs from the one its
// configuration describes (which the built-in controller and motormix's
// `vehicle:` section see) by factors on its mass, inertia, drag, motor time
// constants and rotor inertia.

#include <motormix/config/config.hpp>
#include <motormix/enum_names.hpp>

#include <optional>
#include <string>

namespace motormix::sim {

enum class RealismPiece { kRotorMomentum, kSpinDown, kImu, kEscLatency, kGroundEffect };
inline constexpr EnumName<RealismPiece> kRealismPieceNames[] = {
    {RealismPiece::kRotorMomentum, "rotor_momentum"},
    {RealismPiece::kSpinDown, "spin_down"},
    {RealismPiece::kImu, "imu"},
    {RealismPiece::kEscLatency, "esc_latency"},
    {RealismPiece::kGroundEffect, "ground_effect"},
};
inline const char* to_string(RealismPiece value) { return name_in(kRealismPieceNames, value); }

// Factors from the configured vehicle to the simulated one (1: as configured).
struct ModelError {
  double mass = 1.0;
  double inertia = 1.0;
  double drag = 1.0;           // linear and rotational
  double time_constant = 1.0;  // the motors', up and down
  double rotor_inertia = 1.0;
  bool none() const {
    return mass == 1.0 && inertia == 1.0 && drag == 1.0 && time_constant == 1.0 &&
           rotor_inertia == 1.0;
  }
};

struct Realism {
  bool rotor_momentum = true;
  bool spin_down = true;
  bool imu = true;
  bool esc_latency = true;
  bool ground_effect = true;
  ModelError truth;

  static Realism ideal();  // every piece off, no model error: the simulator before 0.10
  bool& operator[](RealismPiece piece);
  bool operator[](RealismPiece piece) const;
};

// "imu=off,ground_effect=on" applied to `realism`; an error message naming
// the bad item when it does not parse.
std::optional<std::string> apply_switches(Realism& realism, const std::string& list);
// "mass=1.3,inertia=0.7" into `error` (factors 0.1..10).
std::optional<std::string> parse_model_error(ModelError& error, const std::string& list);
// "rotor_momentum=on,spin_down=on,... truth mass=1,..." for a run's report.
std::string describe(const Realism& realism);

// The configuration as the controller and motormix see it: the pieces
// switched off are gone from the vehicle too (no rotor inertia, equal time
// constants, no ground effect).
void apply_realism(config::Config& config, const Realism& realism);
// The vehicle the simulator flies: `config` (after apply_realism) with the
// model error's factors.
config::Config truth_config(const config::Config& config, const ModelError& error);

}  // namespace motormix::sim
