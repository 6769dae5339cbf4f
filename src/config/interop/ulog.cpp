// PX4's ULog format (ulog.hpp): definitions ('F' formats, 'P' parameters),
// subscriptions ('A') and data ('D'); every other message skipped by its
// size.

#include <motormix/config/ulog.hpp>

#include <array>
#include <cstring>
#include <fstream>
#include <iterator>
#include <limits>
#include <sstream>
#include <stdexcept>

namespace motormix::config {

namespace {

constexpr std::array<std::uint8_t, 7> kMagic{0x55, 0x4c, 0x6f, 0x67, 0x01, 0x12, 0x35};
constexpr std::size_t kHeaderBytes = 16;  // magic, version, start time
constexpr int kMaxNesting = 8;
// Bounds a damaged or hostile format cannot push the reader past (PX4's
// largest arrays hold a few hundred elements).
constexpr std::size_t kMaxArray = 4096;
constexpr std::size_t kMaxFields = 65536;

std::size_t primitive_size(const std::string& type) {
  if (type == "int8_t" || type == "uint8_t" || type == "char" || type == "bool") return 1;
  if (type == "int16_t" || type == "uint16_t") return 2;
  if (type == "int32_t" || type == "uint32_t" || type == "float") return 4;
  if (type == "int64_t" || type == "uint64_t" || type == "double") return 8;
  return 0;
}

std::uint64_t little_endian(const char* p, std::size_t n) {
  std::uint64_t v = 0;
  for (std::size_t i = n; i-- > 0;) v = (v << 8) | static_cast<std::uint8_t>(p[i]);
  return v;
}

double value_of(const std::string& type, const char* p) {
  const std::size_t n = primitive_size(type);
  const std::uint64_t raw = little_endian(p, n);
  if (type == "float") {
    const auto bits = static_cast<std::uint32_t>(raw);
    float f = 0.0F;
    std::memcpy(&f, &bits, sizeof f);
    return f;
  }
  if (type == "double") {
    double d = 0.0;
    std::memcpy(&d, &raw, sizeof d);
    return d;
  }
  if (type[0] == 'u' || type == "char" || type == "bool") return static_cast<double>(raw);
  // Signed: extend from n bytes.
  const unsigned shift = static_cast<unsigned>(64 - 8 * n);
  const auto s = static_cast<std::int64_t>(raw << shift) >> shift;
  return static_cast<double>(s);
}

}  // namespace

bool Ulog::is_ulog(const std::string& bytes) {
  if (bytes.size() < kHeaderBytes) return false;
  for (std::size_t i = 0; i < kMagic.size(); ++i)
    if (static_cast<std::uint8_t>(bytes[i]) != kMagic[i]) return false;
  return true;
}

Ulog Ulog::read(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw std::runtime_error("cannot open " + path);
  const std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  if (!is_ulog(bytes)) throw std::runtime_error(path + ": not a ULog (no ULog header)");
  return parse(bytes, path);
}

Ulog Ulog::parse(const std::string& bytes, const std::string& name) {
  Ulog log;
  log.name_ = name;
  std::size_t at = kHeaderBytes;
  while (at + 3 <= bytes.size()) {
    const auto size = static_cast<std::size_t>(little_endian(bytes.data() + at, 2));
    const char type = bytes[at + 2];
    const std::size_t body = at + 3;
    if (body + size > bytes.size()) break;  // cut short: what came before stands
    const char* p = bytes.data() + body;
    if (type == 'P' && size >= 1) {
      const auto key_len = static_cast<std::size_t>(static_cast<std::uint8_t>(p[0]));
      if (1 + key_len + 4 <= size) {
        const std::string key(p + 1, key_len);
        const std::size_t space = key.find(' ');
        const std::string kind = key.substr(0, space);
        if (space != std::string::npos && (kind == "float" || kind == "int32_t")) {
          log.parameters_.emplace(key.substr(space + 1), value_of(kind, p + 1 + key_len));
        }
      }
    } else if (type == 'F') {
      const std::string text(p, size);
      const std::size_t colon = text.find(':');
      if (colon != std::string::npos) {
        Format f;
        f.raw = text.substr(colon + 1);
        log.formats_[text.substr(0, colon)] = f;
      }
    } else if (type == 'A' && size >= 3) {
      Subscription s;
      s.instance = static_cast<std::uint8_t>(p[0]);
      s.topic.assign(p + 3, size - 3);
      log.subscriptions_[static_cast<std::uint16_t>(little_endian(p + 1, 2))] = s;
    } else if (type == 'D' && size >= 2) {
      log.data_[static_cast<std::uint16_t>(little_endian(p, 2))].emplace_back(p + 2, size - 2);
    }
    at = body + size;
  }
  return log;
}

// The flattened fields of format `name` (and of the formats it nests).
void Ulog::resolve(const std::string& name, int depth) const {
  auto it = formats_.find(name);
  if (it == formats_.end()) throw std::runtime_error(name_ + ": no format for '" + name + "'");
  if (it->second.resolved) return;
  if (depth > kMaxNesting) throw std::runtime_error(name_ + ": formats nested too deep");
  Format f;
  f.raw = it->second.raw;
  std::istringstream fields(f.raw);
  std::string field;
  while (std::getline(fields, field, ';')) {
    const std::size_t space = field.find(' ');
    if (space == std::string::npos) continue;
    std::string type = field.substr(0, space);
    const std::string member = field.substr(space + 1);
    std::size_t count = 1;
    bool array = false;
    if (const std::size_t open = type.find('['); open != std::string::npos) {
      count = static_cast<std::size_t>(std::strtoul(type.c_str() + open + 1, nullptr, 10));
      type.resize(open);
      array = true;
      if (count > kMaxArray)
        throw std::runtime_error(name_ + ": " + name + "." + member + ": an array of " +
                                 std::to_string(count) + " (at most " + std::to_string(kMaxArray) +
                                 ")");
    }
    const std::size_t primitive = primitive_size(type);
    for (std::size_t i = 0; i < count; ++i) {
      const std::string at_name = array ? member + "[" + std::to_string(i) + "]" : member;
      if (primitive > 0) {
        f.fields[at_name] = {type, f.size};
        f.size += primitive;
      } else {
        resolve(type, depth + 1);
        const Format& nested = formats_.at(type);
        for (const auto& [sub, where] : nested.fields)
          f.fields[at_name + "." + sub] = {where.type, f.size + where.offset};
        f.size += nested.size;
      }
      if (f.fields.size() > kMaxFields)
        throw std::runtime_error(name_ + ": " + name + " has more than " +
                                 std::to_string(kMaxFields) + " fields");
    }
  }
  f.resolved = true;
  formats_[name] = f;
}

bool Ulog::logged(const std::string& topic, int instance) const {
  for (const auto& [id, s] : subscriptions_)
    if (s.topic == topic && s.instance == instance && data_.count(id)) return true;
  return false;
}

bool Ulog::has_field(const std::string& topic, const std::string& field) const {
  if (!logged(topic)) return false;
  try {
    resolve(topic, 0);
  } catch (const std::runtime_error&) {
    return false;
  }
  return formats_.at(topic).fields.count(field) > 0;
}

std::vector<std::vector<double>> Ulog::samples(const std::string& topic,
                                               const std::vector<std::string>& fields,
                                               int instance) const {
  resolve(topic, 0);
  const Format& format = formats_.at(topic);
  std::vector<Field> wanted;
  for (const std::string& f : fields) {
    const auto it = format.fields.find(f);
    if (it == format.fields.end())
      throw std::runtime_error(name_ + ": " + topic + " has no field '" + f + "'");
    wanted.push_back(it->second);
  }
  std::vector<std::vector<double>> out;
  for (const auto& [id, s] : subscriptions_) {
    if (s.topic != topic || s.instance != instance) continue;
    const auto data = data_.find(id);
    if (data == data_.end()) continue;
    for (const std::string& payload : data->second) {
      std::vector<double> row;
      for (const Field& f : wanted) {
        if (f.offset + primitive_size(f.type) > payload.size()) break;
        row.push_back(value_of(f.type, payload.data() + f.offset));
      }
      if (row.size() == wanted.size()) out.push_back(std::move(row));
    }
  }
  if (out.empty() && !logged(topic, instance))
    throw std::runtime_error(name_ + ": " + topic + " (instance " + std::to_string(instance) +
                             ") was not logged");
  return out;
}

}  // namespace motormix::config
