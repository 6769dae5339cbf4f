#pragma once
// The configuration's section readers, one file each (geometry_reader.cpp,
// mixer_reader.cpp, output_reader.cpp) and what they share; load_config.cpp
// reads the document with them. Private to the config library.

#include <motormix/config/config.hpp>
#include "config/yaml_reader.hpp"

#include <Eigen/Core>

#include <optional>
#include <string>
#include <vector>

namespace motormix::config::reading {

// Output values are microseconds by default; anything a servo or ESC driver
// could mean fits in this range.
inline constexpr double kMaxOutputValue = 100000.0;
// Budgets are fractions of full power; their sum may not exceed it.
inline constexpr double kBudgetSumTolerance = 1e-9;
// Mixing coefficients beyond this magnitude are almost certainly a typo.
inline constexpr double kMaxCoefficient = 1000.0;

// Where the configuration came from: relative file names inside it (e.g.
// geometry.paparazzi) are taken from its directory, and the text of every
// file it reads goes into the configuration hash.
struct LoadContext {
  std::string base_dir;
  std::string included_text;
};

// The whole file, or nothing when it cannot be read.
std::optional<std::string> read_text_file(const std::string& path);

// "a, b, c".
std::string join(const std::vector<std::string>& items);
// "roll, pitch" for the axes in `mask`.
std::string axis_list(AxisMask mask);
// A list of numbers of a given length (or a range of lengths), each in lo..hi.
std::vector<double> read_numbers(const YAML::Node& node, const std::string& path,
                                 std::size_t min_len, std::size_t max_len, double lo, double hi);
bool read_bool(MapReader& map, const std::string& key, bool fallback);
Eigen::Vector3d read_vector(const YAML::Node& node, const std::string& path);

// What a rotor entry's position may be: geometry.rotors takes [x, y] or
// [x, y, z] in any consistent unit, vehicle.rotors [x, y, z] in metres.
struct PositionForm {
  std::size_t min_coordinates;
  double extent;     // largest magnitude of a coordinate
  const char* hint;  // what the error says a position is
};
// position, spin (required) and axis (optional, nonzero) of one rotor entry:
// the keys geometry.rotors and vehicle.rotors share, read one way.
Rotor read_rotor_placement(MapReader& r, const PositionForm& form);

// geometry: (geometry_reader.cpp): the five forms (preset, rotors, table,
// effectiveness, paparazzi), motor order and names.
void read_geometry(MapReader geometry, Config& config, LoadContext& context);
// mixer:, battery: (mixer_reader.cpp).
void read_mixer(MapReader mixer, Config& config);
void read_battery(MapReader battery, Config& config);
// output:, inputs:, channels:, motor_test:, realtime: (output_reader.cpp).
void read_output(MapReader output, Config& config);
void read_inputs(MapReader inputs, Config& config);
void read_channels(MapReader channels, Config& config);
void read_motor_test(MapReader test, Config& config);
void read_realtime(MapReader rt, Config& config);

}  // namespace motormix::config::reading
