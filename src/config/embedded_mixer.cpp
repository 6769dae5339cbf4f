#include <motormix/embedded_mixer.hpp>

#include <motormix/config/build_mixer.hpp>
#include <motormix/config/load_config.hpp>

#include <utility>

namespace motormix {

EmbeddedMixer::EmbeddedMixer(config::Config config, Mixer mixer)
    : config_(std::move(config)), mixer_(std::move(mixer)) {
  mixer_.disarm(out_);  // sizes every vector once; mix() then never allocates
}

EmbeddedMixer EmbeddedMixer::from_file(const std::string& path,
                                       const std::vector<std::string>& overrides) {
  config::Config c = config::load_config_file(path, overrides);
  Mixer m = config::build_mixer(c);
  return EmbeddedMixer(std::move(c), std::move(m));
}

EmbeddedMixer EmbeddedMixer::from_yaml(const std::string& yaml_text,
                                       const std::vector<std::string>& overrides) {
  config::Config c = config::load_config_text(yaml_text, "embedded configuration", overrides);
  Mixer m = config::build_mixer(c);
  return EmbeddedMixer(std::move(c), std::move(m));
}

MixReport EmbeddedMixer::mix(const Demand& demand, double dt_s, MotorMask failed) {
  AxisVector d;
  d << demand.roll, demand.pitch, demand.yaw, demand.thrust;
  return report(mixer_.mix(d, out_, dt_s, failed | config_.failed_motors));
}

MixReport EmbeddedMixer::disarm() {
  mixer_.disarm(out_);
  return report(MixStatus::kOk);
}

MixReport EmbeddedMixer::report(MixStatus status) const {
  return MixReport{status,
                   out_.armed,
                   out_.command,
                   out_.output,
                   out_.direction,
                   out_.allocation.saturated_upper,
                   out_.allocation.saturated_lower,
                   out_.allocation.axis_limited,
                   out_.allocation.unallocated,
                   out_.failed,
                   out_.failure,
                   out_.held};
}

}  // namespace motormix
