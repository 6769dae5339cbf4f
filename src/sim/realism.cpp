#include "sim/realism.hpp"

#include <motormix/config/vehicle_derived.hpp>

#include <cstdlib>
#include <sstream>

namespace motormix::sim {

namespace {

constexpr double kMinFactor = 0.1, kMaxFactor = 10.0;

// Calls item(key, value) for each "key=value" of a comma-separated list; the
// first error it returns (or a malformed item) ends the walk.
template <typename Item>
std::optional<std::string> each_item(const std::string& list, Item item) {
  std::stringstream in(list);
  std::string entry;
  while (std::getline(in, entry, ',')) {
    const auto eq = entry.find('=');
    if (eq == std::string::npos || eq == 0 || eq + 1 == entry.size())
      return "'" + entry + "' is not KEY=VALUE";
    if (auto error = item(entry.substr(0, eq), entry.substr(eq + 1))) return error;
  }
  return std::nullopt;
}

}  // namespace

Realism Realism::ideal() {
  Realism r;
  for (const auto& piece : kRealismPieceNames) r[piece.value] = false;
  return r;
}

bool& Realism::operator[](RealismPiece piece) {
  switch (piece) {
    case RealismPiece::kRotorMomentum:
      return rotor_momentum;
    case RealismPiece::kSpinDown:
      return spin_down;
    case RealismPiece::kImu:
      return imu;
    case RealismPiece::kEscLatency:
      return esc_latency;
    case RealismPiece::kGroundEffect:
      break;
  }
  return ground_effect;
}

bool Realism::operator[](RealismPiece piece) const {
  return const_cast<Realism&>(*this)[piece];  // same storage, read only
}

std::optional<std::string> apply_switches(Realism& realism, const std::string& list) {
  return each_item(
      list, [&](const std::string& key, const std::string& value) -> std::optional<std::string> {
        const auto piece = parse_in(kRealismPieceNames, key);
        if (!piece)
          return "unknown piece '" + key + "' (one of " + joined_names(kRealismPieceNames) + ")";
        if (value != "on" && value != "off") return key + "=" + value + ": expected on or off";
        realism[*piece] = value == "on";
        return std::nullopt;
      });
}

std::optional<std::string> parse_model_error(ModelError& error, const std::string& list) {
  return each_item(
      list, [&](const std::string& key, const std::string& value) -> std::optional<std::string> {
        char* end = nullptr;
        const double f = std::strtod(value.c_str(), &end);
        if (end == value.c_str() || *end != '\0' || !(f >= kMinFactor && f <= kMaxFactor))
          return key + "=" + value + ": expected a factor from 0.1 to 10";
        double* slot = key == "mass"            ? &error.mass
                       : key == "inertia"       ? &error.inertia
                       : key == "drag"          ? &error.drag
                       : key == "time_constant" ? &error.time_constant
                       : key == "rotor_inertia" ? &error.rotor_inertia
                                                : nullptr;
        if (slot == nullptr)
          return "unknown factor '" + key +
                 "' (one of mass, inertia, drag, time_constant, rotor_inertia)";
        *slot = f;
        return std::nullopt;
      });
}

std::string describe(const Realism& realism) {
  std::ostringstream out;
  const char* sep = "";
  for (const auto& piece : kRealismPieceNames) {
    out << sep << piece.name << '=' << (realism[piece.value] ? "on" : "off");
    sep = ",";
  }
  const ModelError& e = realism.truth;
  if (!e.none()) {
    out << " truth mass=" << e.mass << ",inertia=" << e.inertia << ",drag=" << e.drag
        << ",time_constant=" << e.time_constant << ",rotor_inertia=" << e.rotor_inertia;
  }
  return out.str();
}

void apply_realism(config::Config& config, const Realism& realism) {
  config::VehiclePhysics& v = config.vehicle_model;
  if (v.wheeled) return;
  if (!realism.rotor_momentum) v.rotor_inertia_kgm2 = 0.0;
  if (!realism.spin_down) v.time_constant_down_s = v.time_constant_up_s;
  v.ground_effect = realism.ground_effect;
  if (!realism.imu) v.imu.lowpass_hz = 0.0;  // the rates arrive unfiltered, on time
  config::rederive_from_vehicle(config);
}

config::Config truth_config(const config::Config& config, const ModelError& error) {
  config::Config truth = config;
  config::VehiclePhysics& v = truth.vehicle_model;
  v.mass_kg *= error.mass;
  v.inertia_kgm2 *= error.inertia;
  v.drag_linear_n_per_mps *= error.drag;
  v.drag_rotational_nm_per_radps *= error.drag;
  v.time_constant_up_s *= error.time_constant;
  v.time_constant_down_s *= error.time_constant;
  v.rotor_inertia_kgm2 *= error.rotor_inertia;
  return truth;
}

}  // namespace motormix::sim
