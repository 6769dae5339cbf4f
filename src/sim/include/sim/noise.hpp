#pragma once
// Gaussian sensor noise from a seed, the same sequence on every platform and
// standard library (std::normal_distribution's algorithm is left to the
// library, so a seed would not reproduce a run elsewhere): xoshiro256**
// seeded by splitmix64, and Marsaglia's polar method, two draws at a time
// (no trigonometry: a logarithm and a square root per pair).

#include <cmath>
#include <cstdint>

namespace motormix::sim {

class GaussianNoise {
 public:
  explicit GaussianNoise(std::uint64_t seed) {
    for (std::uint64_t& s : state_) {
      seed += 0x9E3779B97F4A7C15ULL;  // splitmix64
      std::uint64_t z = seed;
      z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ULL;
      z = (z ^ (z >> 27)) * 0x94D049BB133111EBULL;
      s = z ^ (z >> 31);
    }
  }

  // One draw with standard deviation sigma (0: none, and no draw).
  double operator()(double sigma) {
    if (!(sigma > 0)) return 0.0;
    if (has_spare_) {
      has_spare_ = false;
      return sigma * spare_;
    }
    double u, v, s;
    do {  // a point uniform in the unit disc (accepted 79 % of the time)
      u = uniform() * 2.0 - 1.0;
      v = uniform() * 2.0 - 1.0;
      s = u * u + v * v;
    } while (s >= 1.0 || s == 0.0);
    const double f = std::sqrt(-2.0 * std::log(s) / s);
    spare_ = v * f;
    has_spare_ = true;
    return sigma * u * f;
  }

 private:
  double uniform() { return static_cast<double>(next() >> 11) * 0x1.0p-53; }  // [0, 1)
  static std::uint64_t rotl(std::uint64_t x, int k) { return (x << k) | (x >> (64 - k)); }
  std::uint64_t next() {
    const std::uint64_t result = rotl(state_[1] * 5, 7) * 9;
    const std::uint64_t t = state_[1] << 17;
    state_[2] ^= state_[0];
    state_[3] ^= state_[1];
    state_[1] ^= state_[2];
    state_[0] ^= state_[3];
    state_[2] ^= t;
    state_[3] = rotl(state_[3], 45);
    return result;
  }

  std::uint64_t state_[4];
  double spare_ = 0.0;
  bool has_spare_ = false;
};

}  // namespace motormix::sim
