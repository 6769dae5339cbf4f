// The signing policy (motormix/signing_policy.hpp) and the `security:`
// section that configures it: off cuts a trailer off unread, sign takes
// unsigned messages but refuses forged and replayed ones, require takes only
// what verifies; each refusal counted by its reason. The section's errors
// name key, value and range; a relative key file is the configuration
// file's neighbour; the key is read only when a policy is made.

#include <motormix/config/load_config.hpp>
#include <motormix/config/security.hpp>
#include <motormix/signing_policy.hpp>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <sys/stat.h>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

namespace motormix::test {
namespace {

constexpr std::int64_t kPolicyNowUs = 1764806400LL * 1000000LL;  // a fixed time
constexpr std::size_t kRoom = signing::kTrailerBytes;

signing::Key policy_key(std::uint8_t seed) {
  std::array<std::uint8_t, signing::kKeyBytes> bytes{};
  for (std::size_t i = 0; i < bytes.size(); ++i) bytes[i] = static_cast<std::uint8_t>(seed ^ i);
  return signing::Key(bytes);
}

// A message of `n` bytes, with room for a trailer behind it.
std::vector<std::uint8_t> message_with_room(std::size_t n) {
  std::vector<std::uint8_t> m(n + kRoom);
  for (std::size_t i = 0; i < n; ++i) m[i] = static_cast<std::uint8_t>(3 * i + 1);
  return m;
}

TEST(SigningPolicy, OffCutsATrailerOffUnreadAndSignsNothing) {
  signing::Policy off;
  signing::Policy signer(signing::Mode::kRequire, policy_key(1), 3);
  std::vector<std::uint8_t> m = message_with_room(40);
  EXPECT_EQ(off.seal("SETPOINT", m.data(), 40, kPolicyNowUs), 40U);
  const std::size_t n = signer.seal("SETPOINT", m.data(), 40, kPolicyNowUs);
  ASSERT_EQ(n, 40 + kRoom);
  const signing::Inbound in = off.check("SETPOINT", m.data(), n, kPolicyNowUs);
  EXPECT_TRUE(in.accept);
  EXPECT_EQ(in.payload_size, 40U);
  const signing::Inbound plain = off.check("SETPOINT", m.data(), 40, kPolicyNowUs);
  EXPECT_TRUE(plain.accept);
  EXPECT_EQ(plain.payload_size, 40U);
  EXPECT_EQ(off.counts().rejected(), 0U);
  EXPECT_FALSE(off.signs());
}

TEST(SigningPolicy, SignTakesUnsignedButRefusesForgedAndReplayed) {
  signing::Policy publisher(signing::Mode::kSign, policy_key(1), 5);
  signing::Policy reader(signing::Mode::kSign, policy_key(1), 9);
  signing::Policy stranger(signing::Mode::kSign, policy_key(2), 5);
  std::vector<std::uint8_t> m = message_with_room(30);
  EXPECT_TRUE(reader.check("PID", m.data(), 30, kPolicyNowUs).accept);  // unsigned
  const std::size_t n = publisher.seal("PID", m.data(), 30, kPolicyNowUs);
  EXPECT_TRUE(reader.check("PID", m.data(), n, kPolicyNowUs).accept);
  EXPECT_FALSE(reader.check("PID", m.data(), n, kPolicyNowUs).accept);  // the same again
  std::vector<std::uint8_t> f = message_with_room(30);
  const std::size_t fn = stranger.seal("PID", f.data(), 30, kPolicyNowUs + 10);
  const signing::Inbound forged = reader.check("PID", f.data(), fn, kPolicyNowUs + 10);
  EXPECT_FALSE(forged.accept);
  EXPECT_EQ(forged.verdict, signing::Verdict::kBadSignature);
  const signing::PolicyCounts& c = reader.counts();
  EXPECT_EQ(c.unsigned_accepted, 1U);
  EXPECT_EQ(c.signed_accepted, 1U);
  EXPECT_EQ(c.rejected_replayed, 1U);
  EXPECT_EQ(c.rejected_bad_signature, 1U);
  EXPECT_EQ(c.rejected(), 2U);
}

TEST(SigningPolicy, RequireTakesOnlyWhatVerifiesCountingEachReason) {
  signing::Policy publisher(signing::Mode::kRequire, policy_key(1), 5);
  signing::Policy reader(signing::Mode::kRequire, policy_key(1), 9);
  std::vector<std::uint8_t> m = message_with_room(30);
  EXPECT_FALSE(reader.check("SETPOINT", m.data(), 30, kPolicyNowUs).accept);
  // A first message stamped two minutes ago: a log played back later.
  const std::size_t n = publisher.seal("SETPOINT", m.data(), 30, kPolicyNowUs - 120'000'000);
  const signing::Inbound old = reader.check("SETPOINT", m.data(), n, kPolicyNowUs);
  EXPECT_FALSE(old.accept);
  EXPECT_EQ(old.verdict, signing::Verdict::kStale);
  std::vector<std::uint8_t> fresh = message_with_room(30);
  const std::size_t fn = publisher.seal("SETPOINT", fresh.data(), 30, kPolicyNowUs);
  const signing::Inbound ok = reader.check("SETPOINT", fresh.data(), fn, kPolicyNowUs);
  EXPECT_TRUE(ok.accept);
  EXPECT_EQ(ok.payload_size, 30U);
  const signing::PolicyCounts& c = reader.counts();
  EXPECT_EQ(c.rejected_unsigned, 1U);
  EXPECT_EQ(c.rejected_stale, 1U);
  EXPECT_EQ(c.signed_accepted, 1U);
  EXPECT_EQ(c.unsigned_accepted, 0U);
}

const char* const kQuad = "geometry: {preset: quad_x}\n";

std::string security_error(const std::string& yaml) {
  try {
    config::load_config_text(std::string(kQuad) + yaml, "test.yaml");
  } catch (const config::ConfigError& e) {
    return e.what();
  }
  return "(accepted)";
}

TEST(SecurityConfig, ErrorsNameKeyValueAndRange) {
  using ::testing::HasSubstr;
  EXPECT_EQ(config::load_config_text(kQuad, "t.yaml").security.mode, signing::Mode::kOff);
  EXPECT_THAT(security_error("security: {mode: sometimes}\n"),
              AllOf(HasSubstr("security.mode"), HasSubstr("sometimes"), HasSubstr("require")));
  EXPECT_THAT(security_error("security: {mode: require}\n"),
              AllOf(HasSubstr("security.key_file"), HasSubstr("keygen")));
  EXPECT_THAT(security_error("security: {mode: sign, key_file: k, link_id: 256}\n"),
              AllOf(HasSubstr("security.link_id"), HasSubstr("256"), HasSubstr("255")));
  EXPECT_THAT(security_error("security: {mode: sign, key_file: k, link_id: 1.5}\n"),
              AllOf(HasSubstr("security.link_id"), HasSubstr("1.5"), HasSubstr("whole")));
  EXPECT_THAT(security_error("security: {mode: sign, key_file: k, max_skew_s: 0}\n"),
              HasSubstr("security.max_skew_s"));
  EXPECT_THAT(security_error("security: {mode: sign, key: k}\n"), HasSubstr("security.key"));
}

TEST(SecurityConfig, KeyFileBesideTheConfigReadOnlyForAPolicy) {
  namespace fs = std::filesystem;
  const fs::path dir =
      fs::temp_directory_path() / ("motormix_security_" + std::to_string(getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir);
  const std::string config_path = (dir / "vehicle.yaml").string();
  std::ofstream(config_path) << kQuad
                             << "security: {mode: require, key_file: bus.key, link_id: 4}\n";
  // Loading never reads the key: matrix, mix and check run without it.
  const config::Config c = config::load_config_file(config_path);
  EXPECT_EQ(c.security.key_file, (dir / "bus.key").string());
  EXPECT_EQ(c.security.link_id, 4);
  EXPECT_THAT(config::describe(c.security), ::testing::HasSubstr("require"));
  try {
    config::signing_policy(c);
    ADD_FAILURE() << "a missing key file was taken";
  } catch (const config::ConfigError& e) {
    EXPECT_THAT(e.what(), ::testing::HasSubstr("security.key_file"));
  }
  signing::write_new_key((dir / "bus.key").string());
  EXPECT_EQ(config::signing_policy(c).mode(), signing::Mode::kRequire);
  ::chmod((dir / "bus.key").c_str(), 0640);
  EXPECT_THROW(config::signing_policy(c), config::ConfigError);
  fs::remove_all(dir);
}

}  // namespace
}  // namespace motormix::test
