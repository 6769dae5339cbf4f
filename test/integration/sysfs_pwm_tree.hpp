#pragma once
// A Linux sysfs PWM tree in a temporary directory, for `motormix output`'s
// sysfs driver in the integration tests: pwmchip0 with its export file and
// channels 0..n-1 already exported; each channel's duty_cycle is a file the
// test reads back.

#include <chrono>
#include <filesystem>
#include <fstream>
#include <string>
#include <thread>

namespace motormix::test {

inline void make_sysfs_pwm_tree(const std::string& root, int channels) {
  std::filesystem::create_directories(root + "/pwmchip0");
  std::ofstream(root + "/pwmchip0/export");
  for (int c = 0; c < channels; ++c) {
    const std::string dir = root + "/pwmchip0/pwm" + std::to_string(c);
    std::filesystem::create_directories(dir);
    for (const char* f : {"period", "duty_cycle", "enable"}) std::ofstream(dir + "/" + f);
  }
}

// Channel c's duty cycle in ns, -1 when unreadable.
inline long long read_duty(const std::string& root, int c) {
  std::ifstream in(root + "/pwmchip0/pwm" + std::to_string(c) + "/duty_cycle");
  long long v = -1;
  in >> v;
  return v;
}

// Waits (polling, bounded) until channel c's duty is `ns`: how long it took,
// ms, or -1 when not within bound_ms.
inline double wait_duty(const std::string& root, int c, long long ns, double bound_ms) {
  const auto start = std::chrono::steady_clock::now();
  while (std::chrono::steady_clock::now() - start <
         std::chrono::duration<double, std::milli>(bound_ms)) {
    if (read_duty(root, c) == ns) {
      return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start)
          .count();
    }
    std::this_thread::sleep_for(std::chrono::microseconds(500));
  }
  return -1.0;
}

}  // namespace motormix::test
