#pragma once
// The one way a motormix process takes a message off the bus.
//
//   1. the signing policy's verdict (security:), before anything else is
//      read: a refused message is counted there, by reason;
//   2. the type's fingerprint;
//   3. the array length, if the type has one, checked against the bytes
//      received: within 0..the type's largest, and exactly as many bytes as
//      it says (nothing short, nothing trailing) before any vector is sized;
//   4. LCM's decoder, whose exceptions are caught, and which must consume
//      the whole payload.
// Nothing here throws and nothing is allocated beyond the message's own
// arrays, sized from a length already checked. Every refusal has a reason,
// counted by the caller's Refusals.

#include <motormix/enum_names.hpp>
#include "bus/wire_shape.hpp"

#include <motormix/signing_policy.hpp>

#include <lcm/lcm-cpp.hpp>

#include <cstddef>
#include <cstdint>
#include <cstring>
#include <string>

namespace motormix::bus {

enum class Refusal : std::uint8_t {
  kNone,         // taken
  kSignature,    // the signing policy refused it (its counts say why)
  kTruncated,    // fewer bytes than the type (or its length field) needs; empty
  kTrailing,     // more bytes than the type (or its length field) says
  kWrongType,    // another type's fingerprint
  kBadLength,    // an array length below 0 or above the type's largest
  kUndecodable,  // LCM's decoder failed or threw all the same
};
inline constexpr EnumName<Refusal> kRefusalNames[] = {
    {Refusal::kNone, "taken"},
    {Refusal::kSignature, "signature"},
    {Refusal::kTruncated, "truncated"},
    {Refusal::kTrailing, "trailing bytes"},
    {Refusal::kWrongType, "wrong type"},
    {Refusal::kBadLength, "bad length"},
    {Refusal::kUndecodable, "undecodable"},
};
inline const char* to_string(Refusal value) { return name_in(kRefusalNames, value); }

// How many messages were taken and refused, by reason.
struct Refusals {
  std::uint64_t taken = 0;
  std::uint64_t signature = 0;
  std::uint64_t truncated = 0;
  std::uint64_t trailing = 0;
  std::uint64_t wrong_type = 0;
  std::uint64_t bad_length = 0;
  std::uint64_t undecodable = 0;
  void count(Refusal r);
  // A message the guard took and the caller then refuses for what it holds
  // (a motor count no mixer has): moved from taken to reason r.
  void refuse_taken(Refusal r);
  // Refused for what the bytes are (everything but the signature).
  std::uint64_t malformed() const {
    return truncated + trailing + wrong_type + bad_length + undecodable;
  }
  std::uint64_t refused() const { return signature + malformed(); }
  Refusals& operator+=(const Refusals& o);
};
// "7 refused: 0 signature, 2 truncated, 1 trailing bytes, 1 wrong type,
// 3 bad length, 0 undecodable": the one wording every process logs.
std::string describe(const Refusals& r);

namespace detail {

// The big-endian int32 at `b`, as LCM encodes an array length.
inline std::int32_t int32_at(const std::uint8_t* b) {
  const std::uint32_t raw = (std::uint32_t{b[0]} << 24) | (std::uint32_t{b[1]} << 16) |
                            (std::uint32_t{b[2]} << 8) | std::uint32_t{b[3]};
  std::int32_t n = 0;
  std::memcpy(&n, &raw, sizeof n);
  return n;
}

// The big-endian int64 at `b`, as LCM encodes a type's fingerprint.
inline std::int64_t int64_at(const std::uint8_t* b) {
  std::uint64_t raw = 0;
  for (int i = 0; i < 8; ++i) raw = (raw << 8) | b[i];
  std::int64_t v = 0;
  std::memcpy(&v, &raw, sizeof v);
  return v;
}

// The encoded size of a message of the type with `n` array elements:
// the fixed part and the bytes per element are measured once from the
// generated encoder, so they cannot drift from the .lcm file.
template <typename Message>
struct MeasuredSize {
  int fixed = 0;
  int per_element = 0;
  MeasuredSize() {
    Message m{};
    if constexpr (WireShape<Message>::kHasLength) {
      WireShape<Message>::size(m, 0);
      fixed = m.getEncodedSize();
      WireShape<Message>::size(m, 1);
      per_element = m.getEncodedSize() - fixed;
    } else {
      fixed = m.getEncodedSize();
    }
  }
  static const MeasuredSize& get() {
    static const MeasuredSize measured;  // once, before the first cycle needs it
    return measured;
  }
};

// check_wire, also giving the array length read (0 for a type without).
template <typename Message>
Refusal check_wire_length(const void* data, std::size_t size, std::int32_t& length) noexcept {
  const auto& measured = MeasuredSize<Message>::get();
  const auto* bytes = static_cast<const std::uint8_t*>(data);
  length = 0;
  if (data == nullptr || size < 8) return Refusal::kTruncated;
  if (int64_at(bytes) != Message::getHash()) return Refusal::kWrongType;
  std::size_t expected = static_cast<std::size_t>(measured.fixed);
  if constexpr (WireShape<Message>::kHasLength) {
    constexpr auto kAt = static_cast<std::size_t>(WireShape<Message>::kLengthOffset);
    if (size < kAt + 4) return Refusal::kTruncated;
    const std::int32_t n = int32_at(bytes + kAt);
    if (n < 0 || n > WireShape<Message>::kMaxLength) return Refusal::kBadLength;
    expected += static_cast<std::size_t>(n) * static_cast<std::size_t>(measured.per_element);
    length = n;
  }
  if (size < expected) return Refusal::kTruncated;
  if (size > expected) return Refusal::kTrailing;
  return Refusal::kNone;
}
}  // namespace detail

// Checks the bytes of one message (no signature trailer) as the type's;
// Refusal::kNone when `decode` may be called on exactly these bytes.
template <typename Message>
Refusal check_wire(const void* data, std::size_t size) noexcept {
  std::int32_t length = 0;
  return detail::check_wire_length<Message>(data, size, length);
}

// Decodes `size` bytes (no trailer) into `out` after check_wire; never
// throws. `out` is unspecified unless kNone is returned. Its arrays are
// sized from the checked length first: lcm-gen's decoder leaves them alone
// when the length is 0, so a reused message would keep the last one's
// elements (found by fuzz_output_reader). Reusing `out` allocates nothing
// once its arrays have held the largest length.
template <typename Message>
Refusal decode_exact(const void* data, std::size_t size, Message& out) noexcept {
  std::int32_t length = 0;
  const Refusal wire = detail::check_wire_length<Message>(data, size, length);
  if (wire != Refusal::kNone) return wire;
  try {
    if constexpr (WireShape<Message>::kHasLength) WireShape<Message>::size(out, length);
    const int n = static_cast<int>(size);
    return out.decode(data, 0, n) == n ? Refusal::kNone : Refusal::kUndecodable;
  } catch (...) {
    return Refusal::kUndecodable;
  }
}

// The signing policy's verdict, then decode_exact; counted in `counts`.
// `now_unix_us` is this host's wall clock (the replay passes the log's time).
template <typename Message>
Refusal receive(signing::Policy& policy, const std::string& channel, const void* data,
                std::size_t size, std::int64_t now_unix_us, Message& out,
                Refusals& counts) noexcept {
  Refusal r = Refusal::kSignature;
  try {
    const signing::Inbound in =
        policy.check(channel, static_cast<const std::uint8_t*>(data), size, now_unix_us);
    if (in.accept) r = decode_exact(data, in.payload_size, out);
  } catch (...) {
    r = Refusal::kUndecodable;  // the policy does not throw; nothing escapes all the same
  }
  counts.count(r);
  return r;
}

// The same for what an LCM callback is handed.
template <typename Message>
Refusal receive(signing::Policy& policy, const lcm::ReceiveBuffer* rbuf, const std::string& channel,
                std::int64_t now_unix_us, Message& out, Refusals& counts) noexcept {
  if (rbuf == nullptr) {
    counts.count(Refusal::kTruncated);
    return Refusal::kTruncated;
  }
  return receive(policy, channel, rbuf->data, rbuf->data_size, now_unix_us, out, counts);
}

}  // namespace motormix::bus
