#include "log/ulog_import.hpp"

#include "messages/esc_telemetry.hpp"

#include <motormix/attitude_t.hpp>
#include <motormix/config/ulog.hpp>
#include <motormix/esc_telemetry_t.hpp>
#include <motormix/motor_pwm_t.hpp>
#include <motormix/motor_vector.hpp>
#include <motormix/pid_t.hpp>
#include <motormix/setpoint_t.hpp>
#include "messages/log_writer.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <ostream>
#include <stdexcept>
#include <utility>

namespace motormix::lcmlog {

namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
// PX4's arming_state for "armed" (vehicle_status), in every release that
// logs it.
constexpr double kPx4ArmingStateArmed = 2.0;
// esc_report.actuator_function: 101 is motor 1 (PX4's output functions).
constexpr int kPx4MotorFunctionFirst = 101;
constexpr int kPx4EscReportsMax = 8;  // esc_status.esc[8]
// The largest PX4 body rate kept; motormix refuses faster ones as corrupt.
constexpr double kMaxImportedRateRadS = 30.0;

// A value of a step function of time: the last sample at or before `t`.
class Steps {
 public:
  void add(double t, std::vector<double> v) { samples_.emplace_back(t, std::move(v)); }
  void sort() {
    std::stable_sort(samples_.begin(), samples_.end(),
                     [](const auto& a, const auto& b) { return a.first < b.first; });
  }
  bool empty() const { return samples_.empty(); }
  // nullptr before the first sample.
  const std::vector<double>* at(double t) const {
    const auto it = std::upper_bound(samples_.begin(), samples_.end(), t,
                                     [](double x, const auto& s) { return x < s.first; });
    return it == samples_.begin() ? nullptr : &std::prev(it)->second;
  }

 private:
  std::vector<std::pair<double, std::vector<double>>> samples_;
};

using Event = ImportedEvent;

template <typename Message>
Event encode(std::int64_t t, int order, const std::string& channel, const Message& m) {
  Event e{t, order, channel, {}};
  e.bytes.resize(static_cast<std::size_t>(m.getEncodedSize()));
  m.encode(e.bytes.data(), 0, static_cast<int>(e.bytes.size()));
  return e;
}

std::vector<std::string> indexed(const std::string& name, int n) {
  std::vector<std::string> out;
  for (int i = 0; i < n; ++i) out.push_back(name + "[" + std::to_string(i) + "]");
  return out;
}

class Importer {
 public:
  Importer(const config::Ulog& ulog, const UlogImportOptions& options, UlogImportSummary& summary)
      : ulog_(ulog), options_(options), summary_(summary) {}

  std::vector<Event> run() {
    motors_ = options_.motors;
    if (motors_ <= 0) {
      const auto& p = ulog_.parameters();
      const auto it = p.find("CA_ROTOR_COUNT");
      motors_ = it != p.end() && it->second >= 1 && it->second <= kMaxMotors
                    ? static_cast<int>(it->second)
                    : 4;
      if (it == p.end()) note("no CA_ROTOR_COUNT: PX4's outputs read as 4 motors");
    }
    read_armed();
    inputs();
    attitude();
    esc();
    reference();
    std::stable_sort(events_.begin(), events_.end(), [](const Event& a, const Event& b) {
      return a.t != b.t ? a.t < b.t : a.order < b.order;
    });
    return std::move(events_);
  }

 private:
  void note(const std::string& text) { summary_.notes.push_back(text); }
  void add(Event e) {
    ++summary_.events[e.channel];
    events_.push_back(std::move(e));
  }
  bool armed_at(double t) const {
    if (armed_.empty()) return true;
    const auto* v = armed_.at(t);
    return v != nullptr && (*v)[0] != 0.0;
  }
  // Into [lo, hi], counted when it had to move.
  double clamp(double v, double lo, double hi) {
    if (v < lo || v > hi) ++summary_.clamped;
    return std::clamp(v, lo, hi);
  }

  void read_armed() {
    if (ulog_.logged("actuator_armed")) {
      for (auto& r : ulog_.samples("actuator_armed", {"timestamp", "armed"}))
        armed_.add(r[0], {r[1]});
    } else if (ulog_.has_field("vehicle_status", "arming_state")) {
      for (auto& r : ulog_.samples("vehicle_status", {"timestamp", "arming_state"}))
        armed_.add(r[0], {r[1] == kPx4ArmingStateArmed ? 1.0 : 0.0});
    } else {
      note("neither actuator_armed nor vehicle_status: every setpoint says armed");
    }
    armed_.sort();
  }

  void write_inputs(std::int64_t t, double roll, double pitch, double yaw, double thrust) {
    if (!std::isfinite(roll) || !std::isfinite(pitch) || !std::isfinite(yaw) ||
        !std::isfinite(thrust)) {
      ++summary_.skipped;
      return;
    }
    pid_t pid{};
    pid.utime = t;
    pid.roll = static_cast<float>(clamp(roll, -1.0, 1.0));
    pid.pitch = static_cast<float>(clamp(pitch, -1.0, 1.0));
    pid.yaw = static_cast<float>(clamp(yaw, -1.0, 1.0));
    setpoint_t sp{};
    sp.utime = t;
    sp.throttle = static_cast<float>(clamp(thrust, 0.0, 1.0));
    sp.yaw = pid.yaw;
    sp.armed = armed_at(static_cast<double>(t));
    add(encode(t, 0, options_.channels.pid, pid));
    add(encode(t, 1, options_.channels.setpoint, sp));
  }

  // Torque and thrust setpoints, paired by sample time (PX4 publishes both
  // from one rate-controller step); a torque without its thrust takes the
  // latest thrust before it.
  void inputs() {
    const std::vector<std::string> xyz{"timestamp_sample", "xyz[0]", "xyz[1]", "xyz[2]"};
    if (ulog_.logged("vehicle_torque_setpoint") && ulog_.logged("vehicle_thrust_setpoint")) {
      Steps thrust;
      for (auto& r : ulog_.samples("vehicle_thrust_setpoint", xyz)) thrust.add(r[0], {r[3]});
      thrust.sort();
      for (const auto& r : ulog_.samples("vehicle_torque_setpoint", xyz)) {
        const auto* f = thrust.at(r[0]);
        if (f == nullptr) continue;  // before PX4's first thrust
        write_inputs(static_cast<std::int64_t>(r[0]), r[1], r[2], r[3], -(*f)[0]);
      }
    } else if (ulog_.logged("actuator_controls_0")) {
      const std::string time = ulog_.has_field("actuator_controls_0", "timestamp_sample")
                                   ? "timestamp_sample"
                                   : "timestamp";
      for (const auto& r : ulog_.samples("actuator_controls_0", {time, "control[0]", "control[1]",
                                                                 "control[2]", "control[3]"}))
        write_inputs(static_cast<std::int64_t>(r[0]), r[1], r[2], r[3], r[4]);
      note("inputs from actuator_controls_0 (a log from before control allocation)");
    } else {
      throw std::runtime_error(
          "no mixing inputs: neither vehicle_torque_setpoint with vehicle_thrust_setpoint nor "
          "actuator_controls_0 was logged");
    }
  }

  void attitude() {
    if (!ulog_.logged("vehicle_angular_velocity")) {
      note("no vehicle_angular_velocity: no attitude_t");
      return;
    }
    Steps q, velocity;
    if (ulog_.logged("vehicle_attitude")) {
      for (auto& r :
           ulog_.samples("vehicle_attitude", {"timestamp_sample", "q[0]", "q[1]", "q[2]", "q[3]"}))
        q.add(r[0], {r[1], r[2], r[3], r[4]});
    } else {
      note("no vehicle_attitude: attitude_t carries rates only");
    }
    if (ulog_.has_field("vehicle_local_position", "v_z_valid")) {
      for (auto& r : ulog_.samples("vehicle_local_position", {"timestamp_sample", "vx", "vy", "vz",
                                                              "v_xy_valid", "v_z_valid"}))
        velocity.add(r[0], r[4] != 0.0 && r[5] != 0.0 ? std::vector<double>{r[1], r[2], r[3]}
                                                      : std::vector<double>{kNaN, kNaN, kNaN});
    }
    q.sort();
    velocity.sort();
    const std::string time = ulog_.has_field("vehicle_angular_velocity", "timestamp_sample")
                                 ? "timestamp_sample"
                                 : "timestamp";
    for (const auto& r :
         ulog_.samples("vehicle_angular_velocity", {time, "xyz[0]", "xyz[1]", "xyz[2]"})) {
      attitude_t a{};
      a.utime = static_cast<std::int64_t>(r[0]);
      bool usable = true;
      for (int k = 0; k < 3; ++k) {
        usable = usable && std::isfinite(r[1 + static_cast<std::size_t>(k)]);
        a.rates[k] = static_cast<float>(
            clamp(r[1 + static_cast<std::size_t>(k)], -kMaxImportedRateRadS, kMaxImportedRateRadS));
      }
      if (!usable) {
        ++summary_.skipped;
        continue;
      }
      const auto* qv = q.at(r[0]);
      const auto* vv = velocity.at(r[0]);
      const bool q_ok = qv != nullptr && std::all_of(qv->begin(), qv->end(),
                                                     [](double c) { return std::isfinite(c); });
      for (int k = 0; k < 4; ++k)
        a.q[k] = static_cast<float>(q_ok ? (*qv)[static_cast<std::size_t>(k)] : kNaN);
      const bool v_ok = vv != nullptr && std::all_of(vv->begin(), vv->end(),
                                                     [](double c) { return std::isfinite(c); });
      for (int k = 0; k < 3; ++k)
        a.velocity[k] = static_cast<float>(v_ok ? (*vv)[static_cast<std::size_t>(k)] : kNaN);
      add(encode(a.utime, 0, options_.channels.attitude, a));
    }
  }

  // One esc_telemetry_t per esc_status, with the reports of this vehicle's
  // motors (a simulator may report more ESCs than the frame has rotors).
  void esc() {
    if (!ulog_.logged("esc_status")) {
      note("no esc_status: no esc_telemetry_t");
      return;
    }
    // A report field this log's release lacks is read as "timestamp" and
    // written as unknown.
    const auto has = [&](const char* f) {
      return ulog_.has_field("esc_status", std::string("esc[0].") + f);
    };
    const bool functions = has("actuator_function");
    const std::array<const char*, 4> wanted{"esc_rpm", "esc_current", "esc_voltage",
                                            "esc_temperature"};
    std::array<bool, 4> present{};
    for (std::size_t k = 0; k < wanted.size(); ++k) present[k] = has(wanted[k]);
    if (!present[0]) note("esc_status without esc_rpm: rpm unknown");
    std::vector<std::string> fields{"timestamp", "esc_count"};
    for (int i = 0; i < kPx4EscReportsMax; ++i) {
      const std::string e = "esc[" + std::to_string(i) + "].";
      for (std::size_t k = 0; k < wanted.size(); ++k)
        fields.push_back(present[k] ? e + wanted[k] : "timestamp");
      fields.push_back(functions ? e + "actuator_function" : "esc_count");
    }
    constexpr std::size_t kPerReport = 5;
    for (const auto& r : ulog_.samples("esc_status", fields)) {
      esc_telemetry_t m{};
      messages::start_esc_telemetry(m, static_cast<std::int64_t>(r[0]));
      const int count = std::min(static_cast<int>(r[1]), kPx4EscReportsMax);
      for (int i = 0; i < count; ++i) {
        const std::size_t at = 2 + kPerReport * static_cast<std::size_t>(i);
        const int motor =
            functions ? static_cast<int>(r[at + 4]) - kPx4MotorFunctionFirst + 1 : i + 1;
        if (motor < 1 || motor > motors_) continue;  // not one of this vehicle's motors
        if (std::find(m.motor.begin(), m.motor.end(), motor) != m.motor.end()) continue;
        const auto finite_or_nan = [](double v, double lo, double hi) {
          return std::isfinite(v) && v >= lo && v <= hi ? v : kNaN;
        };
        const auto field = [&](std::size_t k) { return present[k] ? r[at + k] : kNaN; };
        loop::EscReading reading = messages::unknown_reading(motor);
        reading.rpm = finite_or_nan(std::abs(field(0)), 0.0, 1e6);
        reading.current_a = finite_or_nan(field(1), -50.0, 1000.0);
        reading.voltage_v = finite_or_nan(field(2), 0.0, 100.0);
        reading.temperature_c = finite_or_nan(field(3), -60.0, 250.0);
        messages::add_esc_reading(m, reading);
      }
      if (m.count == 0) continue;
      add(encode(m.utime, 0, options_.channels.esc_telemetry, m));
    }
  }

  // PX4's own commands: actuator_motors (normalized, NaN when disarmed)
  // with the latest actuator_outputs as the pulses.
  void reference() {
    if (!ulog_.logged("actuator_motors")) {
      note("no actuator_motors: nothing of PX4's to compare with");
      return;
    }
    Steps outputs;
    if (ulog_.logged("actuator_outputs")) {
      std::vector<std::string> f{"timestamp"};
      for (auto& n : indexed("output", motors_)) f.push_back(n);
      for (auto& r : ulog_.samples("actuator_outputs", f))
        outputs.add(r[0], std::vector<double>(r.begin() + 1, r.end()));
    }
    outputs.sort();
    std::vector<std::string> f{"timestamp", "timestamp_sample"};
    for (auto& n : indexed("control", motors_)) f.push_back(n);
    for (const auto& r : ulog_.samples("actuator_motors", f)) {
      motor_pwm_t m{};
      m.utime = static_cast<std::int64_t>(r[0]);
      m.num_motors = motors_;
      const auto* pulses = outputs.at(r[0]);
      // PX4 keeps allocating while disarmed; its output driver stops the
      // motors (and a NaN command stops one).
      m.armed = armed_at(r[0]);
      for (int i = 0; i < motors_; ++i) {
        const double c = r[2 + static_cast<std::size_t>(i)];
        if (!std::isfinite(c)) m.armed = false;
        m.command.push_back(static_cast<float>(std::isfinite(c) ? c : 0.0));
        const double p = pulses ? (*pulses)[static_cast<std::size_t>(i)] : kNaN;
        m.pwm.push_back(static_cast<float>(p));
        m.direction.push_back(0);
      }
      m.setpoint_utime = static_cast<std::int64_t>(r[1]);
      m.pid_utime = m.setpoint_utime;
      add(encode(m.utime, 2, options_.reference, m));
    }
  }

  const config::Ulog& ulog_;
  const UlogImportOptions& options_;
  UlogImportSummary& summary_;
  int motors_ = 4;
  Steps armed_;
  std::vector<Event> events_;
};

}  // namespace

std::vector<ImportedEvent> ulog_events(const config::Ulog& ulog, const UlogImportOptions& options,
                                       UlogImportSummary& summary) {
  return Importer(ulog, options, summary).run();
}

bool import_ulog(const std::string& ulog_path, const std::string& out_path,
                 const UlogImportOptions& options, UlogImportSummary& summary, std::ostream& log) {
  std::vector<Event> events;
  try {
    events = ulog_events(config::Ulog::read(ulog_path), options, summary);
  } catch (const std::runtime_error& e) {
    log << "motormix import ulog: " << e.what() << "\n";
    return false;
  }
  messages::LogWriter out(out_path);
  if (!out.good()) {
    log << "motormix import ulog: cannot write " << out_path << "\n";
    return false;
  }
  for (const Event& e : events)
    out.raw(e.channel, e.t, e.bytes.data(), static_cast<int>(e.bytes.size()));
  if (!out.close()) {
    log << "motormix import ulog: cannot write " << out_path << " (disk full or I/O error)\n";
    return false;
  }
  if (!events.empty())
    summary.duration_s = static_cast<double>(events.back().t - events.front().t) / 1e6;
  return true;
}

}  // namespace motormix::lcmlog
