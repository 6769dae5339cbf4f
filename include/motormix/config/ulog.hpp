#pragma once
// A reader of PX4's ULog flight logs (the format PX4 documents: a 16-byte
// header, then messages of {uint16 size, uint8 type, payload}): the
// parameters as the flight started, and the samples of logged topics by
// field name. Enough for `motormix import px4-params` and for comparing
// motormix's mixing with PX4's on a logged flight; bounds-checked
// throughout (a log cut short keeps what came before the cut).

#include <cstdint>
#include <map>
#include <string>
#include <vector>

namespace motormix::config {

class Ulog {
 public:
  // Throws std::runtime_error naming the file: missing, or not a ULog.
  static Ulog read(const std::string& path);
  static bool is_ulog(const std::string& bytes);
  static Ulog parse(const std::string& bytes, const std::string& name);

  // Name -> value; the first value of each name (the airframe as the
  // flight started; later ones are changes in flight).
  const std::map<std::string, double>& parameters() const { return parameters_; }

  // The logged instances of `topic` (multi_id `instance`), each the values of
  // `fields` in order; a field names a primitive ("timestamp"), an array
  // element ("xyz[2]") or a nested one ("esc[0].esc_rpm"). Throws
  // std::runtime_error if the topic was not logged or has no such field.
  std::vector<std::vector<double>> samples(const std::string& topic,
                                           const std::vector<std::string>& fields,
                                           int instance = 0) const;
  bool logged(const std::string& topic, int instance = 0) const;
  // Whether `topic` was logged with `field` (PX4's messages change between
  // releases: a reader picks the fields the log has).
  bool has_field(const std::string& topic, const std::string& field) const;

 private:
  struct Field {
    std::string type;  // a primitive's name
    std::size_t offset = 0;
  };
  struct Format {
    std::string raw;                      // "type name;type[n] name;..."
    std::map<std::string, Field> fields;  // flattened, by full name
    std::size_t size = 0;
    bool resolved = false;
  };
  struct Subscription {
    std::string topic;
    int instance = 0;
  };
  // Flattens format `name` (and those it nests) into formats_, once.
  void resolve(const std::string& name, int depth) const;

  std::string name_;
  std::map<std::string, double> parameters_;
  mutable std::map<std::string, Format> formats_;  // resolved on first use
  std::map<std::uint16_t, Subscription> subscriptions_;
  // Payloads of data messages, by subscription id (without the id).
  std::map<std::uint16_t, std::vector<std::string>> data_;
};

}  // namespace motormix::config
