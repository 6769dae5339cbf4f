#include "paparazzi_import.hpp"

#include <motormix/motor_vector.hpp>

#include <pugixml.hpp>

#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <map>
#include <vector>

namespace motormix::config {

namespace {

// Coefficients are integers scaled by SCALE in practice; anything far beyond
// this is a typo or a damaged file.
constexpr double kMaxMagnitude = 1e6;

[[noreturn]] void refuse(const std::string& source, const std::string& what) {
  throw ConfigError(source + ": Paparazzi MIXING section: " + what);
}

double parse_number(const std::string& text, const std::string& source, const std::string& name) {
  const char* begin = text.c_str();
  char* end = nullptr;
  errno = 0;
  const double v = std::strtod(begin, &end);
  while (end && (*end == ' ' || *end == '\t' || *end == '\n' || *end == '\r')) ++end;
  if (end == begin || !end || *end != '\0' || errno == ERANGE || !std::isfinite(v) ||
      std::abs(v) > kMaxMagnitude) {
    refuse(source, name + ": found '" + text + "'; allowed: a finite number up to " +
                       std::to_string(static_cast<long>(kMaxMagnitude)) + " in magnitude");
  }
  return v;
}

// "{ -67, 67, -256 }" (braces optional) -> numbers.
std::vector<double> parse_list(const std::string& value, const std::string& source,
                               const std::string& name) {
  std::string body = value;
  const auto open = body.find('{');
  const auto close = body.rfind('}');
  if (open != std::string::npos || close != std::string::npos) {
    if (open == std::string::npos || close == std::string::npos || close < open) {
      refuse(source, name + ": found '" + value + "'; allowed: a list like { -256, 256, ... }");
    }
    body = body.substr(open + 1, close - open - 1);
  }
  std::vector<double> out;
  std::size_t start = 0;
  while (start <= body.size()) {
    const auto comma = body.find(',', start);
    const std::string item =
        body.substr(start, comma == std::string::npos ? std::string::npos : comma - start);
    out.push_back(parse_number(item, source, name + "[" + std::to_string(out.size()) + "]"));
    if (comma == std::string::npos) break;
    start = comma + 1;
  }
  return out;
}

}  // namespace

MixingMatrix parse_paparazzi_mixing(const std::string& xml_text, const std::string& source) {
  pugi::xml_document doc;
  const pugi::xml_parse_result parsed =
      doc.load_buffer(xml_text.data(), xml_text.size(), pugi::parse_default | pugi::parse_doctype);
  if (!parsed) {
    refuse(source, std::string("not valid XML: ") + parsed.description() + " at byte " +
                       std::to_string(parsed.offset));
  }
  const pugi::xpath_node_set sections = doc.select_nodes("//section[@name='MIXING']");
  if (sections.empty()) refuse(source, "no <section name=\"MIXING\"> found");
  if (sections.size() > 1) refuse(source, "more than one <section name=\"MIXING\">");

  std::map<std::string, std::string> defines;
  for (const pugi::xml_node define : sections.first().node().children("define")) {
    const std::string name = define.attribute("name").as_string();
    if (name.empty()) continue;
    if (defines.count(name)) refuse(source, "define " + name + " is given twice");
    defines[name] = define.attribute("value").as_string();
  }

  for (const char* trim : {"TRIM_ROLL", "TRIM_PITCH", "TRIM_YAW"}) {
    const auto it = defines.find(trim);
    if (it != defines.end() && parse_number(it->second, source, trim) != 0.0) {
      refuse(source, std::string(trim) + ": found '" + it->second +
                         "'; allowed: 0 (trim in the controller, or output.per_motor[].trim)");
    }
  }
  const double scale =
      defines.count("SCALE") ? parse_number(defines["SCALE"], source, "SCALE") : 256.0;
  if (!(scale > 0.0)) {
    refuse(source, "SCALE: found '" + defines["SCALE"] + "'; allowed: a positive number");
  }

  const char* names[kNumAxes] = {"ROLL_COEF", "PITCH_COEF", "YAW_COEF", "THRUST_COEF"};
  std::vector<std::vector<double>> columns(kNumAxes);
  for (int a = 0; a < kNumAxes; ++a) {
    const auto it = defines.find(names[a]);
    if (it != defines.end()) {
      columns[static_cast<std::size_t>(a)] = parse_list(it->second, source, names[a]);
    } else if (a != index(Axis::kThrust)) {
      refuse(source,
             std::string(names[a]) + " is missing" +
                 (defines.count("TYPE") ? " (a frame given only by TYPE '" + defines["TYPE"] +
                                              "' is not read: give the coefficient lists, "
                                              "or use a motormix preset)"
                                        : ""));
    }
  }
  const std::size_t n = columns[0].size();
  if (n < 1 || n > static_cast<std::size_t>(kMaxMotors)) {
    refuse(source, "ROLL_COEF has " + std::to_string(n) + " entries; allowed: 1 to " +
                       std::to_string(kMaxMotors) + " motors");
  }
  auto& thrust = columns[static_cast<std::size_t>(index(Axis::kThrust))];
  if (thrust.empty()) thrust.assign(n, scale);
  for (int a = 0; a < kNumAxes; ++a) {
    if (columns[static_cast<std::size_t>(a)].size() != n) {
      refuse(source, std::string(names[a]) + " has " +
                         std::to_string(columns[static_cast<std::size_t>(a)].size()) +
                         " entries; allowed: " + std::to_string(n) + ", as ROLL_COEF");
    }
  }
  if (defines.count("NB_MOTOR")) {
    const double nb = parse_number(defines["NB_MOTOR"], source, "NB_MOTOR");
    if (nb != static_cast<double>(n)) {
      refuse(source, "NB_MOTOR: found '" + defines["NB_MOTOR"] + "'; allowed: " +
                         std::to_string(n) + ", the length of the coefficient lists");
    }
  }

  MixingMatrix m(static_cast<Eigen::Index>(n), kNumAxes);
  for (std::size_t i = 0; i < n; ++i) {
    for (int a = 0; a < kNumAxes; ++a) {
      m(static_cast<Eigen::Index>(i), a) = columns[static_cast<std::size_t>(a)][i] / scale;
    }
  }
  return m;
}

}  // namespace motormix::config
