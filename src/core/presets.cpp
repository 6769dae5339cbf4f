#include <motormix/presets.hpp>

namespace motormix {

namespace {

// The team quad's sign table, motor order FL, FR, RL, RR. In this table a
// positive pitch demand raises the rear motors (nose down), and FL/RR take
// positive yaw.
Preset team_quad() {
  MixingMatrix m(4, kNumAxes);
  //    roll  pitch  yaw  thrust
  m << +1.0, -1.0, +1.0, 1.0,  // FL: front left
      -1.0, -1.0, -1.0, 1.0,   // FR: front right
      +1.0, +1.0, -1.0, 1.0,   // RL: rear left
      -1.0, +1.0, +1.0, 1.0;   // RR: rear right
  return {"team_quad",
          "the team's quad: sign table per motor, order FL, FR, RL, RR",
          {"FL", "FR", "RL", "RR"},
          m};
}

}  // namespace

std::optional<Preset> find_preset(std::string_view name) {
  if (name == "team_quad") return team_quad();
  return std::nullopt;
}

std::vector<std::string> preset_names() { return {"team_quad"}; }

}  // namespace motormix
