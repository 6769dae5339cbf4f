// The motormix mixer inside your own program, without LCM.
#include <motormix/embedded_mixer.hpp>

#include <cstdio>

int main(int argc, char** argv) try {
  auto mixer = motormix::EmbeddedMixer::from_file(argc > 1 ? argv[1] : "quad_x.yaml");
  motormix::Demand demand;
  demand.thrust = 0.6;
  demand.roll = 0.3;
  demand.yaw = 0.8;  // more than the motors can give at this thrust
  const motormix::MixReport r = mixer.mix(demand);
  for (int i = 0; i < mixer.motors(); ++i) {
    std::printf("%-4s command %.3f  pwm %6.1f%s\n", mixer.motor_names()[i].c_str(), r.command[i],
                r.pwm[i], r.saturated(i) ? "  saturated" : "");
  }
  std::printf("not delivered: roll %.3f pitch %.3f yaw %.3f thrust %.3f\n", r.unallocated[0],
              r.unallocated[1], r.unallocated[2], r.unallocated[3]);
} catch (const motormix::config::ConfigError& e) {
  std::fprintf(stderr, "%s\n", e.what());
  return 2;
}
