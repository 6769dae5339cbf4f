#pragma once
// `motormix import px4-params`: a PX4 airframe's parameters as a commented
// motormix configuration. The parameters come from a QGroundControl
// `.params` file (tab-separated: vehicle, component, name, value, type) or
// from the parameter messages of a ULog flight log (`.ulg`, told apart by
// its magic bytes). What is mapped:
//   - CA_ROTOR_COUNT and CA_ROTORi_PX/PY/PZ/KM/CT/AX/AY/AZ: the rotors
//     (geometry.rotors, KM's sign the spin: positive counter-clockwise),
//     with `normalization: px4`;
//   - MC_AIRMODE, or MC_AIRMODE_LIM and MC_AIRMODE_YLIM (PX4's limited airmode,
//     the same shares of the range as mixer.prioritized.airmode_limits): the
//     prioritized strategy's airmode;
//   - THR_MDL_FAC: output.thrust_model_factor;
//   - MINi/MAXi/DISi of the outputs the PWM_MAIN_FUNCi and PWM_AUX_FUNCi
//     parameters give to the motors (101 is motor 1), or of MAIN 1..n
//     without FUNC parameters: the output range, one per motor when they
//     differ (a motor on a UAVCAN ESC, which motormix cannot drive, is
//     named and gets PX4's default range);
//   - SYS_AUTOSTART of the common multirotor airframes, for logs from
//     before control allocation (no CA_ROTOR_COUNT): a preset.
// PX4 keeps no mass, inertia or thrust, so the configuration has no spin
// landing (`motor_loss: {mode: off}`) until a measured `vehicle:` is added.
// A rotor tilted by a servo in flight (CA_ROTORi_TILT) is refused: a fixed
// matrix cannot mix it. Everything else that looks like mixing or outputs
// (CA_*, PWM_MAIN_*, PWM_AUX_*, UAVCAN_EC_*, DSHOT_*, MOT_ORDERING, ...)
// and is not mapped is listed with why (a timer's DShot speed, say, is
// hardware.protocol with the pulse firmware), never dropped silently.

#include <map>
#include <string>
#include <vector>

namespace motormix::config {

struct Px4Parameters {
  std::map<std::string, double> values;  // name -> value (integers as doubles)
  std::string format;                    // "params" or "ulog"
};

// Reads a .params or .ulg file. Throws std::runtime_error naming the file
// and what is wrong (missing, truncated, not either format).
Px4Parameters read_px4_parameters(const std::string& path);
// The same from the file's bytes (`name` for the messages).
Px4Parameters parse_px4_parameters(const std::string& bytes, const std::string& name);

struct Px4Import {
  std::string yaml;                     // the configuration, with comments
  std::vector<std::string> not_mapped;  // "NAME = value: why", one per parameter
  std::vector<std::string> notes;       // what was assumed
};

// Throws std::runtime_error when the parameters describe no multirotor
// motormix can mix (no CA_ROTOR_COUNT and no known SYS_AUTOSTART, a
// CA_AIRFRAME other than a multicopter, a rotor count outside 1..16).
Px4Import import_px4(const Px4Parameters& params, const std::string& source_name);

}  // namespace motormix::config
