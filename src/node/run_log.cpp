#include "node/run_log.hpp"

#include "node/describe.hpp"

#include <motormix/config/matrix_export.hpp>

#include <ostream>

namespace motormix::node {

void log_summary(const config::Config& config, const loop::ControlLoop& loop,
                 const std::string& url, std::ostream& log) {
  for (const std::string& line : describe_run(config, loop)) log << "motormix: " << line << "\n";
  log << "motormix: lcm url '" << (url.empty() ? "(default)" : url) << "'\n";
  log << config::export_matrix(config, config::MatrixFormat::kTable) << std::flush;
}

void log_landing(std::ostream& log, const config::Config& config, const loop::CycleResult& r) {
  const auto name = [&](int m) {
    return m >= 0 ? config.motor_names()[static_cast<std::size_t>(m)] : std::string("?");
  };
  switch (r.landing.state) {
    case DescentPhase::kDescending: {
      int second = -1;
      for (int i = r.landing.motor + 1; i < config.motors() && second < 0; ++i) {
        if ((r.landing.failed >> i) & 1U) second = i;
      }
      if (second < 0) {
        log << "motormix: motor " << name(r.landing.motor)
            << " failed: yaw given up, landing spinning on the other three" << std::endl;
      } else {
        log << "motormix: motors " << name(r.landing.motor) << " and " << name(second)
            << " failed: yaw given up, landing spinning on the other two" << std::endl;
      }
      break;
    }
    case DescentPhase::kLanded:
      log << "motormix: spin landing touched down: disarmed (arm again only after a "
             "disarmed setpoint)"
          << std::endl;
      break;
    case DescentPhase::kNoAttitude:
      log << "motormix: motor " << name(r.landing.motor) << " failed and no fresh attitude on "
          << config.channels.attitude << ": no spin landing, mixing as before" << std::endl;
      break;
    case DescentPhase::kOff:
      log << "motormix: spin landing ended" << std::endl;
      break;
  }
}

void log_failures(std::ostream& log, const config::Config& config, const loop::CycleResult& r) {
  log << "motormix: failed motors:";
  if (r.failed == 0) log << " none";
  for (int i = 0; i < config.motors(); ++i) {
    if ((r.failed >> i) & 1U) log << " " << config.motor_names()[static_cast<std::size_t>(i)];
  }
  log << " (" << to_string(r.failure);
  if (r.failure != FailureHandling::kNone) {
    log << "; axes held:";
    for (int a = 0; a < kNumAxes; ++a) {
      if ((r.held >> a) & 1U) log << " " << kAxisNames[static_cast<std::size_t>(a)];
    }
    if (r.held == 0) log << " none promised";
  }
  log << ")" << std::endl;
}

}  // namespace motormix::node
