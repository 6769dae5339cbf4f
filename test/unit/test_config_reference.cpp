// The configuration reference (docs/configuration.md) against the loader
// itself: every bundled configuration and a few that switch on every
// optional section and geometry form are loaded with a KeyLog, and the
// table of the keys the loader read (path, kind, default, allowed values,
// unit) must be the one between the page's markers, byte for byte. A key
// added to, or renamed in, the loader fails here until the page is
// regenerated: MOTORMIX_UPDATE_DOCS=1 on this test (scripts/regen-docs)
// rewrites the table.

#include "config/yaml_reader.hpp"
#include "test_paths.hpp"
#include "test_support.hpp"

#include <gtest/gtest.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <set>
#include <sstream>

namespace motormix::test {
namespace {

// Configurations that reach what the bundled ones leave out: every
// geometry form, every optional section.
const char* const kExtraConfigs[] = {
    R"(geometry:
  rotors:
    - {position: [0.2, 0.2, 0], spin: ccw, thrust_coefficient: 1, torque_ratio: 0.05, axis: [0, 0, -1]}
    - {position: [-0.2, -0.2, 0], spin: ccw}
    - {position: [0.2, -0.2, 0], spin: cw}
    - {position: [-0.2, 0.2, 0], spin: cw}
mixer: {strategy: optimal, optimal: {weights: {roll: 1, pitch: 1, yaw: 0.2, thrust: 0.5}, max_iterations: 50}, failed_motors: []}
battery: {nominal_v: 16.8, min_v: 12, max_v: 18, exponent: 1, max_gain: 1.5, filter_hz: 2, timeout_ms: 500}
motor_test: {enabled: true, max_throttle: 0.15, max_seconds: 3}
channels: {setpoint: S, pid: P, motor_pwm: M, status: ST, motor_status: MS, battery: B, motor_test: MT}
inputs: {yaw_source: pid, setpoint_timeout_ms: 100, pid_timeout_ms: 100, failsafe: hold_last, hold_last_ms: 500, max_future_ms: 1000, arm_max_throttle: 0.1}
publish: on_input
realtime: {priority: 0, cpus: [], lock_memory: false}
vehicle:
  mass_kg: 1.2
  inertia_kgm2: [0.02, 0.02, 0.04]
  max_thrust_n: 5.9
  torque_ratio_m: 0.016
  length_scale: 1.0
  time_constant_up_s: 0.03
  time_constant_down_s: 0.05
  esc: {min: 1000, max: 2000, thrust_expo: 0.3}
  drag: {linear: 0.3, rotational: 0.002}
  battery: {cells: 4, capacity_mah: 5000, internal_resistance_ohm: 0.02, initial_charge: 1, reference_v: 15.4, full_throttle_current_a: 9.1, avionics_current_a: 0.5}
)",
    R"(geometry:
  effectiveness: {roll: [-1, 1, 1, -1], pitch: [1, -1, 1, -1], yaw: [1, 1, -1, -1], thrust: [1, 1, 1, 1]}
  normalization: px4
  motor_names: [a, b, c, d]
mixer: {strategy: prioritized, prioritized: {airmode: roll_pitch_yaw, yaw_headroom: 0.15, tie_tolerance: 0.001}}
output: {min: 1000, max: 2000, disarmed: 900, idle: 0.05, slew_per_s: 100, thrust_model_factor: 0.3, spool_up_s: 0.5,
         per_motor: [{trim: 0.01, reversed: false, min: 1000, max: 2000, disarmed: 900}, {}, {}, {}]}
)",
    R"(geometry:
  mixing: [[-1, 1, 1, 1], [1, -1, 1, 1], [1, 1, -1, 1], [-1, -1, -1, 1]]
mixer: {strategy: budget, legacy_budget: {throttle: 0.6, roll_pitch: 0.25, yaw: 0.15}}
vehicle:
  rotors:
    - {position: [0.18, -0.18, 0], spin: ccw, axis: [0, 0, -1], max_thrust_n: 5.5, torque_ratio_m: 0.015}
    - {position: [-0.18, 0.18, 0], spin: ccw}
    - {position: [0.18, 0.18, 0], spin: cw}
    - {position: [-0.18, -0.18, 0], spin: cw}
)",
    R"(geometry:
  skid_steer: {wheels_per_side: 2, wheel_radius: 0.05, track_width: 0.3, max_wheel_speed: 10}
output: {mode: magnitude_direction, min: 0, max: 1, disarmed: 0}
vehicle: {wheel_radius_m: 0.05, track_m: 0.3, max_wheel_speed_rad_s: 20}
)",
};

std::string unit_of(const std::string& path) {
  static const std::pair<const char*, const char*> kSuffixes[] = {
      {"_hz", "Hz"},         {"_ms", "ms"},       {"_s", "s"},         {"_per_s", "per s"},
      {"_kg", "kg"},         {"_kgm2", "kg m^2"}, {"_n", "N"},         {"_m", "m"},
      {"_v", "V"},           {"_mah", "mAh"},     {"_ohm", "ohm"},     {"_a", "A"},
      {"_rad_s", "rad/s"},   {"_mps", "m/s"},     {"_deg", "degrees"}, {"nominal_v", "V"},
      {"min_v", "V"},        {"max_v", "V"}};
  std::string best;
  std::size_t best_len = 0;
  for (const auto& [suffix, unit] : kSuffixes) {
    const std::string s = suffix;
    if (path.size() >= s.size() && path.compare(path.size() - s.size(), s.size(), s) == 0 &&
        s.size() > best_len) {
      best = unit;
      best_len = s.size();
    }
  }
  return best;
}

std::string escape(const std::string& text) {
  std::string out;
  for (char c : text) out += c == '|' ? std::string("\\|") : std::string(1, c);
  return out;
}

// The Markdown table of every key read, one row per path.
std::string reference_table() {
  config::KeyLog log;
  namespace fs = std::filesystem;
  std::vector<fs::path> files;
  for (const auto& entry : fs::directory_iterator(source_path("config"))) {
    if (entry.path().extension() == ".yaml") files.push_back(entry.path());
  }
  std::sort(files.begin(), files.end());
  for (const auto& f : files) config::load_config_file(f.string());
  for (const char* text : kExtraConfigs) config::load_config_text(text, "reference");
  struct Row {
    std::string kind;
    std::set<std::string> defaults;
    std::set<std::string> allowed;  // several when it depends on the vehicle
    bool required = false;
  };
  std::map<std::string, Row> rows;
  for (const config::KeyRecord& r : log.records()) {
    Row& row = rows[r.path];
    // A typed read says more than a structural one of the same key.
    if (row.kind.empty() || row.kind == "value" || row.kind == "mapping") {
      if (!(r.kind == "value" && !row.kind.empty())) row.kind = r.kind;
    }
    if (!r.fallback.empty()) row.defaults.insert(r.fallback);
    if (!r.allowed.empty()) row.allowed.insert(r.allowed);
    row.required = row.required || r.required;
  }
  std::ostringstream out;
  out << "| key | kind | default | allowed | unit |\n|---|---|---|---|---|\n";
  for (const auto& [path, row] : rows) {
    if (row.kind == "mapping") continue;  // its keys have rows of their own
    std::string defaults;
    for (const std::string& d : row.defaults) defaults += (defaults.empty() ? "" : " or ") + d;
    if (row.required) defaults = "(required)";
    if (row.defaults.size() > 1) defaults += " (by vehicle)";
    const std::string kind = row.kind == "value" ? "list or structure" : row.kind;
    std::string allowed;
    for (const std::string& a : row.allowed) allowed += (allowed.empty() ? "" : "; or ") + a;
    if (row.allowed.size() > 1) allowed += " (by vehicle)";
    out << "| `" << path << "` | " << kind << " | " << escape(defaults) << " | "
        << escape(allowed) << " | " << unit_of(path) << " |\n";
  }
  return out.str();
}

constexpr const char* kBegin = "<!-- generated by test/unit/test_config_reference.cpp: begin -->\n";
constexpr const char* kEnd = "<!-- generated: end -->\n";

TEST(ConfigReference, PageListsEveryKeyTheLoaderReads) {
  const std::string table = reference_table();
  const std::string page_path = source_path("docs/configuration.md");
  std::ifstream in(page_path);
  std::stringstream page;
  page << in.rdbuf();
  std::string text = page.str();
  const std::size_t begin = text.find(kBegin);
  const std::size_t end = text.find(kEnd);
  ASSERT_NE(begin, std::string::npos) << page_path << " has no begin marker";
  ASSERT_NE(end, std::string::npos) << page_path << " has no end marker";
  const std::size_t from = begin + std::string(kBegin).size();
  const std::string shown = text.substr(from, end - from);
  if (std::getenv("MOTORMIX_UPDATE_DOCS") != nullptr && shown != table) {
    text.replace(from, end - from, table);
    std::ofstream(page_path) << text;
    GTEST_SKIP() << "rewrote the table in " << page_path;
  }
  EXPECT_EQ(shown, table) << "docs/configuration.md is not the loader's table: regenerate it "
                             "with scripts/regen-docs";
  // Every key the loader knows is there, the new one included.
  EXPECT_NE(table.find("`mixer.prioritized.tie_tolerance`"), std::string::npos);
  EXPECT_NE(table.find("`realtime.lock_memory`"), std::string::npos);
}

}  // namespace
}  // namespace motormix::test
