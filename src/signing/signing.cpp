#include <motormix/signing.hpp>

#include <sodium.h>

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>
#include <algorithm>
#include <cerrno>
#include <cstring>

namespace motormix::signing {

namespace {

constexpr std::uint8_t kMagic[4] = {'M', 'M', 'S', '1'};
constexpr std::int64_t kEpoch2015Us = 1420070400LL * 1000000LL;

void ensure_sodium() {
  // Idempotent and thread-safe; fails only if the system has no entropy
  // source at all.
  if (sodium_init() < 0) throw KeyError("libsodium could not start (no random source)");
}

std::uint64_t read48(const std::uint8_t* p) {
  std::uint64_t v = 0;
  for (int i = 5; i >= 0; --i) v = (v << 8) | p[i];
  return v;
}

}  // namespace

Key::~Key() { sodium_memzero(bytes_.data(), bytes_.size()); }

static_assert(sizeof(crypto_auth_hmacsha256_state) <= 256, "KeyedHash::state_ too small");

KeyedHash::KeyedHash(const Key& key) {
  ensure_sodium();
  auto* state = reinterpret_cast<crypto_auth_hmacsha256_state*>(state_.data());
  crypto_auth_hmacsha256_init(state, key.data(), kKeyBytes);
}

KeyedHash::~KeyedHash() { sodium_memzero(state_.data(), state_.size()); }

void KeyedHash::tag(const std::string& channel, const std::uint8_t* payload, std::size_t size,
                    const std::uint8_t* header, std::uint8_t* out) const {
  crypto_auth_hmacsha256_state state;
  std::memcpy(&state, state_.data(), sizeof state);
  crypto_auth_hmacsha256_update(&state, reinterpret_cast<const unsigned char*>(channel.data()),
                                channel.size());
  const unsigned char zero = 0;
  crypto_auth_hmacsha256_update(&state, &zero, 1);
  crypto_auth_hmacsha256_update(&state, payload, size);
  crypto_auth_hmacsha256_update(&state, header, kHeaderBytes);
  unsigned char full[crypto_auth_hmacsha256_BYTES];
  crypto_auth_hmacsha256_final(&state, full);
  std::memcpy(out, full, kTagBytes);
  sodium_memzero(full, sizeof full);
  sodium_memzero(&state, sizeof state);
}

Key load_key(const std::string& path) {
  ensure_sodium();
  const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC | O_NOFOLLOW);
  if (fd < 0) throw KeyError("cannot open the key file " + path + ": " + std::strerror(errno));
  struct stat st {};
  if (::fstat(fd, &st) != 0 || !S_ISREG(st.st_mode)) {
    ::close(fd);
    throw KeyError("the key file " + path + " is not a regular file");
  }
  if ((st.st_mode & 077) != 0) {
    ::close(fd);
    throw KeyError("the key file " + path + " can be read by group or others; refused (chmod 600 " +
                   path + ")");
  }
  char text[130];
  const ssize_t n = ::read(fd, text, sizeof text);
  ::close(fd);
  std::size_t len = n > 0 ? static_cast<std::size_t>(n) : 0;
  while (len > 0 && (text[len - 1] == '\n' || text[len - 1] == '\r' || text[len - 1] == ' ')) --len;
  std::array<std::uint8_t, kKeyBytes> bytes{};
  std::size_t got = 0;
  const bool ok =
      len == 2 * kKeyBytes &&
      sodium_hex2bin(bytes.data(), bytes.size(), text, len, nullptr, &got, nullptr) == 0 &&
      got == kKeyBytes;
  sodium_memzero(text, sizeof text);
  if (!ok) {
    sodium_memzero(bytes.data(), bytes.size());
    throw KeyError("the key file " + path +
                   " does not hold a key (64 hexadecimal digits; "
                   "motormix keygen makes one)");
  }
  Key key(bytes);
  sodium_memzero(bytes.data(), bytes.size());
  return key;
}

void write_new_key(const std::string& path) {
  ensure_sodium();
  const int fd = ::open(path.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC | O_NOFOLLOW, 0600);
  if (fd < 0) throw KeyError("cannot create the key file " + path + ": " + std::strerror(errno));
  unsigned char key[kKeyBytes];
  randombytes_buf(key, sizeof key);
  char hex[2 * kKeyBytes + 2];
  sodium_bin2hex(hex, sizeof hex - 1, key, sizeof key);
  sodium_memzero(key, sizeof key);
  hex[2 * kKeyBytes] = '\n';
  const ssize_t w = ::write(fd, hex, 2 * kKeyBytes + 1);
  sodium_memzero(hex, sizeof hex);
  const bool ok = w == static_cast<ssize_t>(2 * kKeyBytes + 1) && ::fsync(fd) == 0;
  ::close(fd);
  if (!ok) {
    ::unlink(path.c_str());
    throw KeyError("cannot write the key file " + path);
  }
}

std::uint64_t timestamp_of(std::int64_t unix_us) {
  if (unix_us <= kEpoch2015Us) return 1;
  return std::min<std::uint64_t>(static_cast<std::uint64_t>(unix_us - kEpoch2015Us) / 10,
                                 kTimestampMax);
}

Signer::Signer(const Key& key, std::uint8_t link_id) : hash_(key), link_id_(link_id) {}

void Signer::sign(const std::string& channel, const std::uint8_t* payload, std::size_t size,
                  std::int64_t now_unix_us, std::uint8_t* out) {
  std::uint64_t ts = std::max(timestamp_of(now_unix_us), last_ + 1);
  ts = std::min(ts, kTimestampMax);
  last_ = ts;
  std::memcpy(out, kMagic, 4);
  out[4] = link_id_;
  for (int i = 0; i < 6; ++i) out[5 + i] = static_cast<std::uint8_t>(ts >> (8 * i));
  hash_.tag(channel, payload, size, out, out + kHeaderBytes);
}

std::vector<std::uint8_t> Signer::signed_copy(const std::string& channel,
                                              const std::uint8_t* payload, std::size_t size,
                                              std::int64_t now_unix_us) {
  std::vector<std::uint8_t> out(size + kTrailerBytes);
  std::memcpy(out.data(), payload, size);
  sign(channel, payload, size, now_unix_us, out.data() + size);
  return out;
}

bool has_trailer(const std::uint8_t* data, std::size_t size) {
  return size >= kTrailerBytes && std::memcmp(data + size - kTrailerBytes, kMagic, 4) == 0;
}

Verifier::Verifier(const Key& key, double max_skew_s)
    : hash_(key),
      max_skew_(static_cast<std::uint64_t>(std::max(0.0, max_skew_s) * 1e5)),
      last_(256) {}

int Verifier::channel_index(const std::string& channel) {
  for (int i = 0; i < channel_count_; ++i)
    if (channels_[static_cast<std::size_t>(i)] == channel) return i;
  if (channel_count_ == kMaxChannels) return -1;
  channels_[static_cast<std::size_t>(channel_count_)] = channel;
  return channel_count_++;
}

Verdict Verifier::verify(const std::string& channel, const std::uint8_t* data, std::size_t size,
                         std::int64_t now_unix_us, std::size_t* payload_size,
                         std::uint8_t* link_id) {
  const auto count = [this](Verdict v) {
    ++counts_[static_cast<std::size_t>(v)];
    return v;
  };
  if (!has_trailer(data, size)) {
    *payload_size = size;
    return count(Verdict::kUnsigned);
  }
  const std::size_t n = size - kTrailerBytes;
  *payload_size = n;
  const std::uint8_t* trailer = data + n;
  std::uint8_t expected[kTagBytes];
  hash_.tag(channel, data, n, trailer, expected);
  const bool good = sodium_memcmp(expected, trailer + kHeaderBytes, kTagBytes) == 0;
  sodium_memzero(expected, sizeof expected);
  if (!good) return count(Verdict::kBadSignature);
  const std::uint8_t link = trailer[4];
  if (link_id) *link_id = link;
  const std::uint64_t ts = read48(trailer + 5);
  const int index = channel_index(channel);
  if (index < 0) return count(Verdict::kUnknownChannel);
  std::uint64_t& last = last_[link][static_cast<std::size_t>(index)];
  if (last == 0) {
    const std::uint64_t now = timestamp_of(now_unix_us);
    const std::uint64_t skew = ts > now ? ts - now : now - ts;
    if (skew > max_skew_) return count(Verdict::kStale);
  } else if (ts <= last) {
    return count(Verdict::kReplayed);
  }
  last = ts;
  return count(Verdict::kSigned);
}

}  // namespace motormix::signing
