#pragma once
// What a process does with signatures on the bus (`security.mode`): the one
// place that decides whether an incoming message may be acted on and
// whether an outgoing one is signed, shared by `motormix run`, `motormix
// output`, the simulator on the bus, the bring-up clients and the offline
// replay, so they all treat the bus alike.
//
//   off      nothing is verified or signed; a trailer on an incoming message
//            is cut off so the message still decodes (a signing peer is
//            read as if it did not sign).
//   sign     everything published is signed; a signed incoming message must
//            verify (bad signatures, replays and stale timestamps are
//            refused), an unsigned one is still taken: the step while the
//            other publishers on the bus are moved to signing.
//   require  everything published is signed; only messages that verify are
//            taken.
//
// No heap per message (see Verifier); refusals are counted, never thrown.

#include <motormix/enum_names.hpp>
#include <motormix/signing.hpp>

#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

namespace motormix::signing {

enum class Mode { kOff, kSign, kRequire };
inline constexpr EnumName<Mode> kModeNames[] = {
    {Mode::kOff, "off"},
    {Mode::kSign, "sign"},
    {Mode::kRequire, "require"},
};
inline const char* to_string(Mode value) { return name_in(kModeNames, value); }

// Counts of what check() decided, by reason.
struct PolicyCounts {
  std::uint64_t signed_accepted = 0;    // verified and taken
  std::uint64_t unsigned_accepted = 0;  // no signature, taken (mode sign)
  std::uint64_t rejected_unsigned = 0;  // no signature (mode require)
  std::uint64_t rejected_bad_signature = 0;
  std::uint64_t rejected_replayed = 0;  // not newer than the last from its link on its channel
  std::uint64_t rejected_stale = 0;     // a link's first message, too far from this clock
  std::uint64_t rejected_other = 0;     // more channels than a verifier keeps
  std::uint64_t rejected() const {
    return rejected_unsigned + rejected_bad_signature + rejected_replayed + rejected_stale +
           rejected_other;
  }
  // Several policies' counts together (one per channel, in the replay).
  PolicyCounts& operator+=(const PolicyCounts& o) {
    signed_accepted += o.signed_accepted;
    unsigned_accepted += o.unsigned_accepted;
    rejected_unsigned += o.rejected_unsigned;
    rejected_bad_signature += o.rejected_bad_signature;
    rejected_replayed += o.rejected_replayed;
    rejected_stale += o.rejected_stale;
    rejected_other += o.rejected_other;
    return *this;
  }
};

// One incoming message's fate.
struct Inbound {
  bool accept = false;
  std::size_t payload_size = 0;  // the LCM message's bytes, without any trailer
  Verdict verdict = Verdict::kUnsigned;
};

class Policy {
 public:
  // Mode off: no key.
  Policy() = default;
  // Mode sign or require (off too, then the key is unused).
  Policy(Mode mode, const Key& key, std::uint8_t link_id, double max_skew_s = 60.0);

  Mode mode() const { return mode_; }
  bool signs() const { return mode_ != Mode::kOff; }

  // Whether the message on `channel` (data, size bytes as received) may be
  // acted on; now_unix_us is this host's wall clock (the replay passes the
  // log's receive time).
  Inbound check(const std::string& channel, const std::uint8_t* data, std::size_t size,
                std::int64_t now_unix_us);

  // Signs a message in place: when signing, writes the trailer after its
  // `size` bytes (the buffer must hold kTrailerBytes more) and returns the
  // size to publish; otherwise returns size.
  std::size_t seal(const std::string& channel, std::uint8_t* buffer, std::size_t size,
                   std::int64_t now_unix_us);

  const PolicyCounts& counts() const { return counts_; }

 private:
  Mode mode_ = Mode::kOff;
  // Held by pointer: a Policy moves into its owner, and the keyed states
  // are wiped when it goes.
  std::unique_ptr<Signer> signer_;
  std::unique_ptr<Verifier> verifier_;
  PolicyCounts counts_;
};

// Encodes an LCM message (anything with getEncodedSize() and encode(), as
// lcm-gen makes them) into `buffer`, grown only when too small for it and a
// trailer, and signs it when the policy signs. The bytes to publish are the
// first ones returned; 0 when the message does not encode.
template <typename Message>
std::size_t encode_sealed(Policy& policy, const std::string& channel, const Message& msg,
                          std::vector<std::uint8_t>& buffer, std::int64_t now_unix_us) {
  const std::size_t need = static_cast<std::size_t>(msg.getEncodedSize()) + kTrailerBytes;
  if (buffer.size() < need) buffer.resize(need);
  const int len = msg.encode(buffer.data(), 0, static_cast<int>(buffer.size()));
  if (len <= 0) return 0;
  return policy.seal(channel, buffer.data(), static_cast<std::size_t>(len), now_unix_us);
}

}  // namespace motormix::signing
