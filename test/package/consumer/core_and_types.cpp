// An outside program using an installed motormix: the pure core (a preset,
// its mixing matrix, the prioritized strategy, the output stage) and the
// generated message types. Exits non-zero if anything is off.
#include <motormix/allocation/prioritized_allocator.hpp>
#include <motormix/effectiveness/presets.hpp>
#include <motormix/mixer.hpp>
#include <motormix/motor_pwm_t.hpp>
#include <motormix/version.hpp>

#include <cmath>
#include <cstdio>
#include <memory>
#include <vector>

int main() {
  const auto vehicle = motormix::find_preset("quad_x");
  if (!vehicle) return 1;
  const motormix::MixingDerivation d = motormix::derive_mixing(
      *vehicle->effectiveness, vehicle->controlled, motormix::Normalization::kAxisMax);
  motormix::OutputChannel pwm;
  pwm.min = 1100.0;
  pwm.max = 1900.0;
  motormix::Mixer mixer(
      std::make_unique<motormix::PrioritizedAllocator>(d.mixing, motormix::CommandRange{0.0, 1.0},
                                                       motormix::Airmode::kOff, 0.15),
      motormix::OutputStage(std::vector<motormix::OutputChannel>(4, pwm)));
  motormix::AxisVector demand;
  demand << 0.9, -0.9, 1.0, 0.95;  // saturates
  motormix::MixerOutput out;
  mixer.mix(demand, out);

  motormix::motor_pwm_t msg;  // the .lcm package `motormix` is the C++ namespace
  msg.utime = 1;
  msg.num_motors = mixer.motors();
  for (int i = 0; i < mixer.motors(); ++i) {
    if (!(out.output[i] >= pwm.min && out.output[i] <= pwm.max)) return 2;
    msg.command.push_back(static_cast<float>(out.command[i]));
    msg.pwm.push_back(static_cast<float>(out.output[i]));
    msg.direction.push_back(0);
  }
  msg.armed = true;
  std::vector<unsigned char> buf(static_cast<std::size_t>(msg.getEncodedSize()));
  if (msg.encode(buf.data(), 0, static_cast<int>(buf.size())) != static_cast<int>(buf.size()))
    return 3;
  motormix::motor_pwm_t back;
  if (back.decode(buf.data(), 0, static_cast<int>(buf.size())) != static_cast<int>(buf.size()))
    return 4;
  for (int i = 0; i < back.num_motors; ++i) {
    if (std::abs(back.pwm[static_cast<std::size_t>(i)] - msg.pwm[static_cast<std::size_t>(i)]) >
        0.0f)
      return 5;
  }
  std::printf(
      "motormix %s: %d motors, pwm %.1f %.1f %.1f %.1f, saturated mask %u, round trip ok\n",
      motormix::kVersion, back.num_motors, back.pwm[0], back.pwm[1], back.pwm[2], back.pwm[3],
      static_cast<unsigned>(out.allocation.saturated_upper | out.allocation.saturated_lower));
  return 0;
}
