#pragma once
// Hostile messages for the bus's integration tests: from one good message of
// a type, the variants a careless or malicious publisher sends, each with the
// reason bus::receive must refuse it for (or, for messages whose bytes are a
// whole message of the type but whose values are poison, none: the process's
// own checks must refuse them).
//
//   array length -1, 0, 17 and 2^31-1 written over a good message's length
//   field (and a whole message of 17 elements); truncated; trailing bytes;
//   another type's fingerprint; empty; and NaN, inf and 1e30 in every value
//   a setter writes.

#include "bus/receive.hpp"

#include <cstdint>
#include <functional>
#include <limits>
#include <string>
#include <vector>

namespace motormix::test {

struct Hostile {
  std::string what;
  std::vector<std::uint8_t> bytes;
  bus::Refusal refusal;  // what bus::receive says; kNone: a whole message, poison values
};

template <typename Message>
std::vector<std::uint8_t> encode_plain(const Message& m) {
  std::vector<std::uint8_t> b(static_cast<std::size_t>(m.getEncodedSize()));
  m.encode(b.data(), 0, static_cast<int>(b.size()));
  return b;
}

// `poison(m, v)` writes v into the message's values (pwm, throttle, ...);
// empty: no value variants.
template <typename Message>
std::vector<Hostile> hostile_variants(const Message& good,
                                      const std::function<void(Message&, float)>& poison = {}) {
  std::vector<Hostile> out;
  const std::vector<std::uint8_t> bytes = encode_plain(good);
  if constexpr (bus::WireShape<Message>::kHasLength) {
    constexpr auto kAt = static_cast<std::size_t>(bus::WireShape<Message>::kLengthOffset);
    for (const std::int64_t n : {std::int64_t{-1}, std::int64_t{0}, std::int64_t{17},
                                 std::int64_t{std::numeric_limits<std::int32_t>::max()}}) {
      std::vector<std::uint8_t> b = bytes;
      const auto u = static_cast<std::uint32_t>(static_cast<std::int32_t>(n));
      for (int i = 0; i < 4; ++i)
        b[kAt + static_cast<std::size_t>(i)] = static_cast<std::uint8_t>(u >> (24 - 8 * i));
      // 0 leaves the arrays' bytes behind it; -1 and 2^31-1 are no length.
      const bus::Refusal r = n == 0 ? bus::Refusal::kTrailing
                             : (n < 0 || n > bus::WireShape<Message>::kMaxLength)
                                 ? bus::Refusal::kBadLength
                                 : bus::Refusal::kTruncated;
      out.push_back({"length " + std::to_string(n), b, r});
    }
    Message big = good;
    bus::WireShape<Message>::size(big, 17);
    out.push_back({"a whole message of 17 elements", encode_plain(big), bus::Refusal::kBadLength});
  }
  out.push_back({"truncated",
                 std::vector<std::uint8_t>(bytes.begin(),
                                           bytes.begin() + static_cast<long>(bytes.size() / 2)),
                 bus::Refusal::kTruncated});
  std::vector<std::uint8_t> trailing = bytes;
  trailing.insert(trailing.end(), {0xde, 0xad, 0xbe, 0xef, 0, 0, 0});
  out.push_back({"trailing bytes", trailing, bus::Refusal::kTrailing});
  std::vector<std::uint8_t> other = bytes;
  other[3] ^= 0x5a;
  out.push_back({"wrong fingerprint", other, bus::Refusal::kWrongType});
  out.push_back({"empty", {}, bus::Refusal::kTruncated});
  if (poison) {
    for (const float v :
         {std::numeric_limits<float>::quiet_NaN(), std::numeric_limits<float>::infinity(), 1e30f}) {
      Message m = good;
      poison(m, v);
      out.push_back({"value " + std::to_string(v), encode_plain(m), bus::Refusal::kNone});
    }
  }
  return out;
}

// How many of `variants` bus::receive refuses for reason r.
inline std::uint64_t count_of(const std::vector<Hostile>& variants, bus::Refusal r) {
  std::uint64_t n = 0;
  for (const Hostile& h : variants) n += h.refusal == r ? 1 : 0;
  return n;
}

}  // namespace motormix::test
