// Signed messages (motormix/signing.hpp): a signed message verifies; any
// changed byte, another key or another channel does not; a replay, a log
// played back later and a first message far from the clock are refused; a
// publisher that restarts is taken again; links keep their own timestamps.
// Key files: made 0600 by write_new_key, refused when group or others can
// read them or when they hold no key, and never echoed. A generated C++
// decoder reads a signed message as if the trailer were not there.

#include <motormix/signing.hpp>

#include <motormix/motor_pwm_t.hpp>

#include <gtest/gtest.h>

#include <sys/stat.h>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <random>
#include <string>
#include <vector>

namespace motormix::test {
namespace {

using signing::Verdict;

constexpr std::int64_t kNowUs = 1764806400LL * 1000000LL;  // 2025-12-04, any fixed time
constexpr std::int64_t kCycleUs = 2500;

signing::Key test_key(std::uint8_t seed) {
  std::array<std::uint8_t, signing::kKeyBytes> bytes{};
  for (std::size_t i = 0; i < bytes.size(); ++i) bytes[i] = static_cast<std::uint8_t>(seed + 7 * i);
  return signing::Key(bytes);
}

std::vector<std::uint8_t> some_payload(int n) {
  std::vector<std::uint8_t> p(static_cast<std::size_t>(n));
  for (int i = 0; i < n; ++i)
    p[static_cast<std::size_t>(i)] = static_cast<std::uint8_t>(i * 31 + 5);
  return p;
}

TEST(Signing, ASignedMessageVerifiesAndAnyChangeDoesNot) {
  signing::Signer signer(test_key(1), 7);
  signing::Verifier verifier(test_key(1));
  const std::vector<std::uint8_t> payload = some_payload(57);
  const std::vector<std::uint8_t> msg =
      signer.signed_copy("SETPOINT", payload.data(), payload.size(), kNowUs);
  ASSERT_EQ(msg.size(), payload.size() + signing::kTrailerBytes);
  std::size_t n = 0;
  std::uint8_t link = 0;
  EXPECT_EQ(verifier.verify("SETPOINT", msg.data(), msg.size(), kNowUs, &n, &link),
            Verdict::kSigned);
  EXPECT_EQ(n, payload.size());
  EXPECT_EQ(link, 7);
  // Every byte, every bit: nothing but the original verifies.
  for (std::size_t i = 0; i < msg.size(); ++i) {
    for (int bit = 0; bit < 8; ++bit) {
      std::vector<std::uint8_t> bad = msg;
      bad[i] ^= static_cast<std::uint8_t>(1u << bit);
      signing::Verifier fresh(test_key(1));
      const Verdict v = fresh.verify("SETPOINT", bad.data(), bad.size(), kNowUs, &n);
      EXPECT_TRUE(v == Verdict::kBadSignature || v == Verdict::kUnsigned) << i << ":" << bit;
    }
  }
  signing::Verifier other_key(test_key(2));
  EXPECT_EQ(other_key.verify("SETPOINT", msg.data(), msg.size(), kNowUs, &n),
            Verdict::kBadSignature);
  signing::Verifier fresh(test_key(1));
  EXPECT_EQ(fresh.verify("PID", msg.data(), msg.size(), kNowUs, &n), Verdict::kBadSignature);
  EXPECT_EQ(fresh.verify("SETPOINT", payload.data(), payload.size(), kNowUs, &n),
            Verdict::kUnsigned);
  EXPECT_EQ(n, payload.size());
}

// The trailer for a fixed key, payload, link and time, as Python's
// standard hmac module computes it (python/motormix_signing.py, checked
// there against the same bytes): the two implementations agree.
TEST(Signing, KnownAnswerFromAnIndependentImplementation) {
  signing::Signer signer(test_key(1), 7);
  const std::vector<std::uint8_t> payload = some_payload(57);
  std::uint8_t trailer[signing::kTrailerBytes];
  signer.sign("SETPOINT", payload.data(), payload.size(), kNowUs, trailer);
  std::string hex;
  for (std::uint8_t b : trailer) {
    char two[3];
    std::snprintf(two, sizeof two, "%02x", b);
    hex += two;
  }
  EXPECT_EQ(hex, "4d4d53310700a0ae825a1f605eecc7ad0c271c0c0df9aa86d6bc27");
}

TEST(Signing, ReplaysOldLogsAndFarClocksAreRefusedARestartedPublisherIsNot) {
  signing::Verifier verifier(test_key(1));
  const std::vector<std::uint8_t> payload = some_payload(40);
  std::size_t n = 0;
  std::vector<std::vector<std::uint8_t>> sent;
  {
    signing::Signer signer(test_key(1), 3);
    for (int k = 0; k < 100; ++k) {
      sent.push_back(
          signer.signed_copy("PID", payload.data(), payload.size(), kNowUs + k * kCycleUs));
      EXPECT_EQ(
          verifier.verify("PID", sent.back().data(), sent.back().size(), kNowUs + k * kCycleUs, &n),
          Verdict::kSigned);
    }
  }
  // Every one of them again: replays.
  for (const auto& m : sent)
    EXPECT_EQ(verifier.verify("PID", m.data(), m.size(), kNowUs + 300000, &n), Verdict::kReplayed);
  // The publisher restarts a second later: its clock is newer than all it sent.
  signing::Signer restarted(test_key(1), 3);
  const auto again = restarted.signed_copy("PID", payload.data(), payload.size(), kNowUs + 1000000);
  EXPECT_EQ(verifier.verify("PID", again.data(), again.size(), kNowUs + 1000000, &n),
            Verdict::kSigned);
  // A log recorded an hour ago, played to a verifier that never heard the
  // link: too far from the clock. And a clock an hour ahead.
  signing::Verifier later(test_key(1));
  EXPECT_EQ(later.verify("PID", sent[0].data(), sent[0].size(), kNowUs + 3600LL * 1000000, &n),
            Verdict::kStale);
  signing::Signer ahead(test_key(1), 4);
  const auto future =
      ahead.signed_copy("PID", payload.data(), payload.size(), kNowUs + 3600LL * 1000000);
  EXPECT_EQ(later.verify("PID", future.data(), future.size(), kNowUs, &n), Verdict::kStale);
  // Links and channels keep their own timestamps.
  signing::Signer link5(test_key(1), 5);
  const auto a = link5.signed_copy("PID", payload.data(), payload.size(), kNowUs);
  const auto b = link5.signed_copy("SETPOINT", payload.data(), payload.size(), kNowUs);
  EXPECT_EQ(verifier.verify("PID", a.data(), a.size(), kNowUs + 1000000, &n), Verdict::kSigned);
  EXPECT_EQ(verifier.verify("SETPOINT", b.data(), b.size(), kNowUs + 1000000, &n),
            Verdict::kSigned);
  EXPECT_EQ(verifier.counts()[static_cast<std::size_t>(Verdict::kReplayed)], 100u);
}

TEST(Signing, TheSignerNeverRepeatsATimestampWhenItsClockStandsStillOrGoesBack) {
  signing::Signer signer(test_key(1), 1);
  signing::Verifier verifier(test_key(1));
  const std::vector<std::uint8_t> payload = some_payload(10);
  std::size_t n = 0;
  for (int k = 0; k < 50; ++k) {
    const std::int64_t clock = kNowUs - (k % 7) * 1000;  // still, then back
    const auto m = signer.signed_copy("X", payload.data(), payload.size(), clock);
    EXPECT_EQ(verifier.verify("X", m.data(), m.size(), kNowUs, &n), Verdict::kSigned) << k;
  }
}

TEST(Signing, AGeneratedDecoderReadsASignedMessageAsAnUnsignedOne) {
  motormix::motor_pwm_t m{};
  m.utime = 123;
  m.num_motors = 2;
  m.command = {0.25f, 0.5f};
  m.pwm = {1250.0f, 1500.0f};
  m.direction = {0, 0};
  m.armed = 1;
  std::vector<std::uint8_t> buf(static_cast<std::size_t>(m.getEncodedSize()));
  ASSERT_EQ(m.encode(buf.data(), 0, static_cast<int>(buf.size())), static_cast<int>(buf.size()));
  signing::Signer signer(test_key(9), 1);
  const auto with = signer.signed_copy("MOTOR_PWM", buf.data(), buf.size(), kNowUs);
  motormix::motor_pwm_t got{};
  EXPECT_EQ(got.decode(with.data(), 0, static_cast<int>(with.size())),
            static_cast<int>(buf.size()));
  EXPECT_EQ(got.pwm[1], 1500.0f);
  EXPECT_TRUE(signing::has_trailer(with.data(), with.size()));
}

struct TempDir {
  TempDir() {
    char tmpl[] = "/tmp/motormix-key-XXXXXX";
    path = mkdtemp(tmpl);
  }
  ~TempDir() { std::filesystem::remove_all(path); }
  std::string path;
};

std::string key_error(const std::string& path) {
  try {
    signing::load_key(path);
  } catch (const signing::KeyError& e) {
    return e.what();
  }
  return "";
}

TEST(SigningKeys, KeygenMakesAPrivateFileAndLoadRefusesWhatIsNotOne) {
  TempDir dir;
  const std::string path = dir.path + "/bus.key";
  signing::write_new_key(path);
  struct stat st {};
  ASSERT_EQ(::stat(path.c_str(), &st), 0);
  EXPECT_EQ(st.st_mode & 0777, 0600u);
  EXPECT_NO_THROW(signing::load_key(path));
  std::ifstream in(path);
  std::string hex;
  in >> hex;
  EXPECT_EQ(hex.size(), 64u);
  EXPECT_THROW(signing::write_new_key(path), signing::KeyError);  // never overwritten
  ::chmod(path.c_str(), 0640);
  const std::string e = key_error(path);
  EXPECT_NE(e.find("group or others"), std::string::npos) << e;
  EXPECT_EQ(e.find(hex), std::string::npos) << "the key in a message";
  const std::string short_key = dir.path + "/short.key";
  std::ofstream(short_key) << hex.substr(0, 60) << "\n";
  ::chmod(short_key.c_str(), 0600);
  EXPECT_NE(key_error(short_key).find("64 hexadecimal"), std::string::npos);
  EXPECT_NE(key_error(dir.path + "/none.key").find("cannot open"), std::string::npos);
  // Two keys made one after the other differ.
  const std::string second = dir.path + "/second.key";
  signing::write_new_key(second);
  std::ifstream in2(second);
  std::string hex2;
  in2 >> hex2;
  EXPECT_NE(hex, hex2);
}

}  // namespace
}  // namespace motormix::test
