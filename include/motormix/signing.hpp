#pragma once
// Signed LCM messages: a fixed-size trailer after the LCM payload (which
// readers that do not verify never read: generated decoders stop at the end
// of the message), as MAVLink 2 signs its frames.
//
// Trailer (27 bytes): "MMS1", the sender's link id (1 byte), a timestamp
// (6 bytes, little-endian, 10 us units since 2015-01-01 UTC, as MAVLink),
// and a tag: HMAC-SHA256 over the channel name, a zero byte, the payload
// and the trailer's first 11 bytes, truncated to 16 bytes.
//
// A verifier keeps, per link id and channel, the newest timestamp it took;
// it refuses one that is not newer (a replay, or a log played back onto the
// bus) and, on a link's first message on a channel, one more than
// max_skew_s from its own clock. A publisher that restarts stamps from its
// clock again, which is newer than anything it sent before.
//
// The key is 32 random bytes in a file that only its owner may read
// (`motormix keygen`). Crypto is libsodium's (HMAC-SHA256, constant-time
// comparison, random bytes). Nothing here prints or logs a key.

#include <array>
#include <cstddef>
#include <cstdint>
#include <motormix/enum_names.hpp>
#include <stdexcept>
#include <string>
#include <vector>

namespace motormix::signing {

constexpr std::size_t kKeyBytes = 32;
constexpr std::size_t kTagBytes = 16;
constexpr std::size_t kHeaderBytes = 4 + 1 + 6;  // magic, link id, timestamp
constexpr std::size_t kTrailerBytes = kHeaderBytes + kTagBytes;
constexpr std::uint64_t kTimestampMax = (std::uint64_t{1} << 48) - 1;
constexpr int kMaxChannels = 16;  // channels one verifier keeps timestamps for

class KeyError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// A key in memory; wiped when destroyed.
class Key {
 public:
  Key() = default;
  explicit Key(const std::array<std::uint8_t, kKeyBytes>& bytes) : bytes_(bytes) {}
  ~Key();
  Key(const Key&) = default;
  Key& operator=(const Key&) = default;
  const std::uint8_t* data() const { return bytes_.data(); }

 private:
  std::array<std::uint8_t, kKeyBytes> bytes_{};
};

// Reads a key file: 64 hexadecimal digits (and an optional newline).
// Throws KeyError naming the path and what is wrong (missing, readable by
// group or others, not 64 hex digits), never the key.
Key load_key(const std::string& path);
// Writes a new random key to path (created, mode 0600; an existing file is
// never overwritten). Throws KeyError.
void write_new_key(const std::string& path);

// Unix microseconds to the trailer's 10 us units since 2015-01-01.
std::uint64_t timestamp_of(std::int64_t unix_us);

// The HMAC's keyed state, computed once per key (an opaque copy of
// libsodium's, wiped when destroyed): each message then costs the hash of
// its own bytes only.
class KeyedHash {
 public:
  explicit KeyedHash(const Key& key);
  ~KeyedHash();
  KeyedHash(const KeyedHash&) = default;
  KeyedHash& operator=(const KeyedHash&) = default;
  // The tag over channel, 0, payload, header (kTagBytes into tag).
  void tag(const std::string& channel, const std::uint8_t* payload, std::size_t size,
           const std::uint8_t* header, std::uint8_t* tag) const;

 private:
  alignas(16) std::array<unsigned char, 256> state_{};
};

class Signer {
 public:
  Signer(const Key& key, std::uint8_t link_id);
  // The trailer for one message on `channel` (kTrailerBytes into out). The
  // timestamp is the clock's, or one more than the last if the clock did
  // not move (or went back).
  void sign(const std::string& channel, const std::uint8_t* payload, std::size_t size,
            std::int64_t now_unix_us, std::uint8_t* out);
  // The payload with its trailer appended.
  std::vector<std::uint8_t> signed_copy(const std::string& channel, const std::uint8_t* payload,
                                        std::size_t size, std::int64_t now_unix_us);
  std::uint8_t link_id() const { return link_id_; }

 private:
  KeyedHash hash_;
  std::uint8_t link_id_;
  std::uint64_t last_ = 0;
};

enum class Verdict {
  kSigned,          // a good signature, newer than the last from its link
  kUnsigned,        // no trailer
  kBadSignature,    // a trailer whose tag does not match
  kReplayed,        // not newer than the last taken from its link on this channel
  kStale,           // a link's first message, too far from this host's clock
  kUnknownChannel,  // more channels than the verifier keeps
};
inline constexpr EnumName<Verdict> kVerdictNames[] = {
    {Verdict::kSigned, "signed"},
    {Verdict::kUnsigned, "unsigned"},
    {Verdict::kBadSignature, "bad signature"},
    {Verdict::kReplayed, "replayed"},
    {Verdict::kStale, "stale timestamp"},
    {Verdict::kUnknownChannel, "too many channels"},
};
inline const char* to_string(Verdict value) { return name_in(kVerdictNames, value); }
constexpr int kVerdicts = 6;

class Verifier {
 public:
  explicit Verifier(const Key& key, double max_skew_s = 60.0);
  // Checks data (payload, maybe a trailer). *payload_size gets the size
  // without the trailer (all of it for kUnsigned). On kSigned only, the
  // link's timestamp moves on. No heap: channels are remembered in a fixed
  // table of kMaxChannels.
  Verdict verify(const std::string& channel, const std::uint8_t* data, std::size_t size,
                 std::int64_t now_unix_us, std::size_t* payload_size,
                 std::uint8_t* link_id = nullptr);
  // Counts of each verdict so far.
  const std::array<std::uint64_t, kVerdicts>& counts() const { return counts_; }

 private:
  int channel_index(const std::string& channel);

  KeyedHash hash_;
  std::uint64_t max_skew_;
  std::array<std::string, kMaxChannels> channels_{};
  int channel_count_ = 0;
  // Newest timestamp taken per link and channel; 0: none yet.
  std::vector<std::array<std::uint64_t, kMaxChannels>> last_;
  std::array<std::uint64_t, kVerdicts> counts_{};
};

// True if data ends with something shaped like a trailer (the magic in
// place): what a reader that does not verify can use to strip it.
bool has_trailer(const std::uint8_t* data, std::size_t size);

}  // namespace motormix::signing
