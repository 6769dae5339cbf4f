#pragma once
// The oracle table for limited airmode's corners: `prioritized` with each
// named airmode on three vehicles (the quad X, whose symmetric mix hides
// much, a hexa and an octo), over seeded demands from well inside the range
// to far beyond it, each line the demand's index and a 64-bit FNV-1a of
// the commands' bytes (the demands come from the seed; a mismatch prints
// its demand). test/data/airmode_oracle.txt was written by this from the
// named modes before the limits existed (MOTORMIX_UPDATE_ORACLE=1); the
// limits' corners must reproduce every line bit for bit.

#include <motormix/allocation/prioritized_allocator.hpp>
#include <motormix/config/load_config.hpp>

#include <cstdint>
#include <cstdio>
#include <cstring>
#include <random>
#include <string>
#include <vector>

namespace motormix::test {

inline constexpr const char* kOracleVehicles[] = {"quad_x", "hexa_x", "octo_x"};
inline constexpr int kOracleDemands = 300;

inline std::uint64_t fnv1a(const MotorVector& u) {
  std::uint64_t h = 14695981039346656037ULL;
  for (Eigen::Index i = 0; i < u.size(); ++i) {
    unsigned char bytes[sizeof(double)];
    const double v = u[i];
    std::memcpy(bytes, &v, sizeof v);
    for (unsigned char b : bytes) h = (h ^ b) * 1099511628211ULL;
  }
  return h;
}

// One line per (vehicle, mode, demand): "vehicle mode k hash"; `demands`
// gets the demands in the same order.
// `make` builds the allocator of (basis, range, named mode).
template <typename Make>
std::vector<std::string> airmode_oracle_lines(const Make& make,
                                              std::vector<AxisVector>* demands = nullptr) {
  std::vector<std::string> lines;
  for (const char* vehicle : kOracleVehicles) {
    const config::Config c =
        config::load_config_text(std::string("geometry: {preset: ") + vehicle + "}\n", vehicle);
    const MixingBasis basis(c.mixing);
    const CommandRange range{0.0, 1.0};
    for (Airmode mode : {Airmode::kOff, Airmode::kRollPitch, Airmode::kRollPitchYaw}) {
      const auto allocator = make(basis, range, mode);
      std::mt19937_64 rng(20261208);
      std::uniform_real_distribution<double> unit(-1.0, 1.0);
      MotorVector u;
      for (int k = 0; k < kOracleDemands; ++k) {
        // Small, saturating and far beyond: a third each; thrust over [0, 1].
        const double size = k % 3 == 0 ? 0.1 : k % 3 == 1 ? 0.6 : 2.0;
        AxisVector d;
        d << size * unit(rng), size * unit(rng), size * unit(rng), 0.5 + 0.5 * unit(rng);
        allocator->allocate(d, u);
        char hash[24];
        std::snprintf(hash, sizeof hash, "%016llx", static_cast<unsigned long long>(fnv1a(u)));
        lines.push_back(std::string(vehicle) + " " + to_string(mode) + " " + std::to_string(k) +
                        " " + hash);
        if (demands != nullptr) demands->push_back(d);
      }
    }
  }
  return lines;
}

}  // namespace motormix::test
