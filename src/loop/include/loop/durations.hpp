#pragma once
// Seconds (as configured) to the loop's microseconds, rounded to nearest.

#include <cmath>
#include <cstdint>

namespace motormix::loop {

inline std::int64_t seconds_to_us(double s) {
  return static_cast<std::int64_t>(std::llround(s * 1e6));
}

}  // namespace motormix::loop
