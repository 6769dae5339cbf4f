// A controller that signs what it sends: flies a quad through motormix with
// security.mode require (docs/signing-the-bus.md).
//
// It reads the vehicle's state (VEHICLE_STATE, as `motormix sim --lcm
// --no-controller` publishes it; a signed one must verify) and sends
// setpoint_t and pid_t signed with the bus key through motormix::signing.
// The flight: disarmed for a moment, armed at zero throttle, a climb to the
// altitude, a hover, a descent, disarmed on the ground. Attitude is held
// level by a proportional-derivative law on the body angles and rates;
// altitude by a proportional-integral law on the climb rate around a hover
// throttle it learns.
//
//   signed_controller --key FILE [--link-id 2] [--altitude 1] [--hover 4] [--lcm-url URL]
//
// Exit status: 0 when the hover held its altitude within 0.25 m and stayed
// level (tilt under 10 degrees) over its last two seconds, 1 otherwise,
// 2 on bad arguments or a bad key.

#include <motormix/signing.hpp>

#include <motormix/pid_t.hpp>
#include <motormix/setpoint_t.hpp>
#include <motormix/vehicle_state_t.hpp>

#include <lcm/lcm-cpp.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <optional>
#include <string>
#include <vector>

namespace {

constexpr double kRateHz = 200.0;
// Attitude: normalized torque demand per radian and per radian/second.
constexpr double kAttitudeP = 0.35, kRateD = 0.06;
// Altitude: climb rate per metre of error (at most kMaxClimb), throttle per
// m/s of climb-rate error, and the integral that learns the hover throttle.
constexpr double kAltitudeP = 1.0, kMaxClimb = 1.0, kClimbP = 0.15, kClimbI = 0.25;

std::int64_t wall_us() {
  return std::chrono::duration_cast<std::chrono::microseconds>(
             std::chrono::system_clock::now().time_since_epoch())
      .count();
}
double seconds() {
  return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

// The latest vehicle state whose signature verified (or that was unsigned:
// a simulator without a key).
struct StateWatch {
  motormix::signing::Verifier* verifier;
  std::optional<motormix::vehicle_state_t> latest;
  int refused = 0;
  void on_state(const lcm::ReceiveBuffer* rbuf, const std::string& channel) {
    std::size_t size = 0;
    const auto verdict = verifier->verify(channel, static_cast<const std::uint8_t*>(rbuf->data),
                                          rbuf->data_size, wall_us(), &size);
    if (verdict != motormix::signing::Verdict::kSigned &&
        verdict != motormix::signing::Verdict::kUnsigned) {
      ++refused;
      return;
    }
    motormix::vehicle_state_t msg;
    if (msg.decode(rbuf->data, 0, static_cast<int>(size)) == static_cast<int>(size)) latest = msg;
  }
};

// Encodes, signs and publishes one message.
template <typename Message>
void publish(lcm::LCM& bus, motormix::signing::Signer& signer, const std::string& channel,
             const Message& msg) {
  std::vector<std::uint8_t> bytes(static_cast<std::size_t>(msg.getEncodedSize()) +
                                  motormix::signing::kTrailerBytes);
  const int len = msg.encode(bytes.data(), 0, static_cast<int>(bytes.size()));
  if (len <= 0) return;
  const auto n = static_cast<std::size_t>(len);
  signer.sign(channel, bytes.data(), n, wall_us(), bytes.data() + n);
  bus.publish(channel, bytes.data(), static_cast<unsigned>(bytes.size()));
}

}  // namespace

int main(int argc, char** argv) {
  std::string key_path, url, setpoint_channel = "SETPOINT", pid_channel = "PID",
                             state_channel = "VEHICLE_STATE";
  int link_id = 2;
  double altitude = 1.0, hover_s = 4.0, timeout_s = 30.0;
  for (int i = 1; i + 1 < argc; i += 2) {
    const std::string a = argv[i], v = argv[i + 1];
    if (a == "--key")
      key_path = v;
    else if (a == "--link-id")
      link_id = std::stoi(v);
    else if (a == "--lcm-url")
      url = v;
    else if (a == "--altitude")
      altitude = std::stod(v);
    else if (a == "--hover")
      hover_s = std::stod(v);
    else if (a == "--timeout")
      timeout_s = std::stod(v);
    else if (a == "--setpoint-channel")
      setpoint_channel = v;
    else if (a == "--pid-channel")
      pid_channel = v;
    else if (a == "--state-channel")
      state_channel = v;
    else {
      std::fprintf(stderr, "signed_controller: unknown option %s\n", a.c_str());
      return 2;
    }
  }
  if (key_path.empty() || link_id < 0 || link_id > 255) {
    std::fprintf(stderr,
                 "usage: signed_controller --key FILE [--link-id 0..255] [--altitude M] "
                 "[--hover S] [--lcm-url URL]\n");
    return 2;
  }
  std::optional<motormix::signing::Signer> signer;
  std::optional<motormix::signing::Verifier> verifier;
  try {
    const motormix::signing::Key key = motormix::signing::load_key(key_path);
    signer.emplace(key, static_cast<std::uint8_t>(link_id));
    verifier.emplace(key);
  } catch (const motormix::signing::KeyError& e) {
    std::fprintf(stderr, "signed_controller: %s\n", e.what());
    return 2;
  }
  lcm::LCM bus(url);
  if (!bus.good()) {
    std::fprintf(stderr, "signed_controller: cannot open the LCM bus\n");
    return 1;
  }
  StateWatch watch{&*verifier, std::nullopt, 0};
  bus.subscribe(state_channel, &StateWatch::on_state, &watch);

  const auto send = [&](bool armed, double throttle, double roll, double pitch, double yaw) {
    const std::int64_t utime = wall_us();
    motormix::setpoint_t sp{};
    sp.utime = utime;
    sp.armed = armed;
    sp.throttle = static_cast<float>(throttle);
    sp.yaw = static_cast<float>(yaw);
    publish(bus, *signer, setpoint_channel, sp);
    motormix::pid_t pid{};
    pid.utime = utime;
    pid.roll = static_cast<float>(roll);
    pid.pitch = static_cast<float>(pitch);
    pid.yaw = static_cast<float>(yaw);
    publish(bus, *signer, pid_channel, pid);
  };

  enum class Phase { kDisarmed, kArming, kClimb, kHover, kDescend } phase = Phase::kDisarmed;
  double hover_throttle = 0.3;  // learned by the climb-rate integral
  const double start = seconds();
  double phase_start = start, next_tick = start;
  double worst_error = -1.0, worst_tilt = 0.0;
  while (seconds() - start < timeout_s) {
    next_tick += 1.0 / kRateHz;
    for (double left = next_tick - seconds(); left > 0; left = next_tick - seconds()) {
      if (bus.handleTimeout(std::max(1, static_cast<int>(left * 1000))) <= 0) break;
    }
    const double now = seconds(), in_phase = now - phase_start;
    if (phase == Phase::kDisarmed) {
      send(false, 0.0, 0.0, 0.0, 0.0);
      if (in_phase > 0.5 && watch.latest) phase = Phase::kArming, phase_start = now;
      continue;
    }
    if (phase == Phase::kArming) {
      send(true, 0.0, 0.0, 0.0, 0.0);
      if (in_phase > 0.5) phase = Phase::kClimb, phase_start = now;
      continue;
    }
    const motormix::vehicle_state_t& s = *watch.latest;
    const double w = s.q[0], x = s.q[1], y = s.q[2], z = s.q[3];
    const double roll = std::atan2(2 * (w * x + y * z), 1 - 2 * (x * x + y * y));
    const double pitch = std::asin(std::clamp(2 * (w * y - z * x), -1.0, 1.0));
    const double height = -s.position[2], climb = -s.velocity[2];
    const double target = phase == Phase::kDescend ? -0.5 : altitude;
    const double climb_sp = std::clamp(kAltitudeP * (target - height), -0.5, kMaxClimb);
    hover_throttle = std::clamp(hover_throttle + kClimbI * (climb_sp - climb) / kRateHz, 0.05, 0.8);
    const double level = std::max(0.5, std::cos(roll) * std::cos(pitch));
    const double throttle =
        std::clamp((hover_throttle + kClimbP * (climb_sp - climb)) / level, 0.0, 1.0);
    send(true, throttle, -kAttitudeP * roll - kRateD * s.rates[0],
         -kAttitudeP * pitch - kRateD * s.rates[1], -kRateD * s.rates[2]);
    if (s.crashed) {
      std::fprintf(stderr, "signed_controller: the vehicle crashed\n");
      break;
    }
    if (phase == Phase::kClimb && std::fabs(altitude - height) < 0.1) {
      phase = Phase::kHover, phase_start = now;
    } else if (phase == Phase::kHover) {
      if (in_phase > hover_s - 2.0) {
        worst_error = std::max(worst_error, std::fabs(altitude - height));
        const double tilt_deg =
            std::acos(std::min(1.0, std::cos(roll) * std::cos(pitch))) * 180 / M_PI;
        worst_tilt = std::max(worst_tilt, tilt_deg);
      }
      if (in_phase > hover_s) phase = Phase::kDescend, phase_start = now;
    } else if (phase == Phase::kDescend && (s.landed || in_phase > 10.0)) {
      break;
    }
  }
  for (int k = 0; k < 20; ++k) {  // disarmed, on the ground (or giving up)
    send(false, 0.0, 0.0, 0.0, 0.0);
    bus.handleTimeout(5);
  }
  if (worst_error < 0.0) {
    std::fprintf(stderr, "signed_controller: never hovered\n");
    return 1;
  }
  std::printf(
      "hover at %.1f m: altitude error at most %.3f m, tilt at most %.2f deg; hover "
      "throttle %.3f; %d vehicle states refused\n",
      altitude, worst_error, worst_tilt, hover_throttle, watch.refused);
  return worst_error < 0.25 && worst_tilt < 10.0 ? 0 : 1;
}
