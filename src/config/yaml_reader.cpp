#include "config/yaml_reader.hpp"

#include <cmath>
#include <sstream>

namespace motormix::config {

namespace {

std::string format_number(double v) {
  std::ostringstream s;
  s << v;
  return s.str();
}

std::string where(const YAML::Node& node) {
  const YAML::Mark mark = node.Mark();
  if (mark.line < 0) return "";
  return " (line " + std::to_string(mark.line + 1) + ")";
}

}  // namespace

void fail(const std::string& path, const std::string& found, const std::string& allowed) {
  throw ConfigError("config key '" + path + "': found " + found + "; allowed: " + allowed);
}

std::string describe(const YAML::Node& node) {
  if (!node.IsDefined() || node.IsNull()) return "nothing";
  if (node.IsScalar()) return "'" + node.Scalar() + "'" + where(node);
  if (node.IsSequence()) return "a list of " + std::to_string(node.size()) + where(node);
  return "a mapping" + where(node);
}

double to_number(const YAML::Node& node, const std::string& path, double lo, double hi) {
  const std::string range = "a number from " + format_number(lo) + " to " + format_number(hi);
  if (!node.IsScalar()) fail(path, describe(node), range);
  double value = 0.0;
  try {
    value = node.as<double>();
  } catch (const YAML::Exception&) {
    fail(path, describe(node), range);
  }
  if (!std::isfinite(value) || value < lo || value > hi) fail(path, describe(node), range);
  return value;
}

MapReader::MapReader(const YAML::Node& node, std::string path)
    : node_(node), path_(std::move(path)) {
  if (node_.IsDefined() && !node_.IsNull() && !node_.IsMap()) {
    fail(path_.empty() ? "(document)" : path_, describe(node_), "a mapping of keys to values");
  }
}

bool MapReader::has(const std::string& key) const {
  return node_.IsMap() && node_[key].IsDefined() && !node_[key].IsNull();
}

std::string MapReader::path_of(const std::string& key) const {
  return path_.empty() ? key : path_ + "." + key;
}

YAML::Node MapReader::raw(const std::string& key) {
  read_.insert(key);
  if (!node_.IsMap()) return YAML::Node();
  return node_[key];
}

double MapReader::number(const std::string& key, double fallback, double lo, double hi) {
  if (!has(key)) {
    read_.insert(key);
    return fallback;
  }
  return to_number(raw(key), path_of(key), lo, hi);
}

double MapReader::required_number(const std::string& key, double lo, double hi) {
  if (!has(key)) {
    fail(path_of(key), "nothing",
         "a number from " + format_number(lo) + " to " + format_number(hi) + " (required)");
  }
  return to_number(raw(key), path_of(key), lo, hi);
}

std::string MapReader::text(const std::string& key, const std::string& fallback) {
  if (!has(key)) {
    read_.insert(key);
    return fallback;
  }
  const YAML::Node value = raw(key);
  if (!value.IsScalar() || value.Scalar().empty()) {
    fail(path_of(key), describe(value), "a non-empty string");
  }
  return value.Scalar();
}

std::string MapReader::choice(const std::string& key, const std::string& fallback,
                              const std::vector<std::string>& allowed) {
  const std::string value = text(key, fallback);
  for (const std::string& a : allowed) {
    if (a == value) return value;
  }
  std::string list;
  for (const std::string& a : allowed) list += (list.empty() ? "" : ", ") + a;
  fail(path_of(key), "'" + value + "'" + where(node_[key]), "one of " + list);
}

MapReader MapReader::map(const std::string& key) { return MapReader(raw(key), path_of(key)); }

void MapReader::finish() const {
  if (!node_.IsMap()) return;
  for (const auto& entry : node_) {
    const std::string key = entry.first.Scalar();
    if (read_.count(key) == 0) {
      std::string known;
      for (const std::string& k : read_) known += (known.empty() ? "" : ", ") + k;
      throw ConfigError("config key '" + path_of(key) + "'" + where(entry.first) +
                        " is not known here; known keys: " + known);
    }
  }
}

}  // namespace motormix::config
