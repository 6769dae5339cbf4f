// The regression flights signed (motormix sign-log) and replayed offline
// under security.mode require give outputs identical, byte for byte, to the
// unsigned flights replayed with security off: signing changes nothing a
// mixer does with the messages it takes. --verify finds every event of a
// signed flight good, and exactly the one event changed in a copy bad.

#include "log/log_replay.hpp"
#include "log/log_signing.hpp"
#include "test_support.hpp"

#include <motormix/signing.hpp>

#include <gtest/gtest.h>
#include <lcm/lcm-cpp.hpp>

#include <unistd.h>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

namespace motormix::test {
namespace {

namespace fs = std::filesystem;

struct Combo {
  std::string name, flight, config;
  std::vector<std::string> overrides;
};

// The regression suite's pairs (test/data/golden/combos.txt).
std::vector<Combo> regression_combos() {
  std::vector<Combo> out;
  std::ifstream in(source_path("test/data/golden/combos.txt"));
  for (std::string line; std::getline(in, line);) {
    if (line.empty() || line[0] == '#') continue;
    std::stringstream fields(line);
    Combo c;
    std::string overrides;
    std::getline(fields, c.name, '|');
    std::getline(fields, c.flight, '|');
    std::getline(fields, c.config, '|');
    std::getline(fields, overrides, '|');
    std::stringstream words(overrides);
    for (std::string w; words >> w;) c.overrides.push_back(w);
    out.push_back(c);
  }
  return out;
}

// The events on `channel`, each as its bytes.
std::vector<std::vector<std::uint8_t>> events_on(const std::string& log,
                                                 const std::string& channel) {
  std::vector<std::vector<std::uint8_t>> out;
  lcm::LogFile file(log, "r");
  while (const lcm::LogEvent* ev = file.readNextEvent()) {
    if (ev->channel != channel) continue;
    const auto* d = static_cast<const std::uint8_t*>(ev->data);
    out.emplace_back(d, d + ev->datalen);
  }
  return out;
}

class SignedReplay : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("motormix_signed_replay_" + std::to_string(getpid()));
    fs::remove_all(dir_);
    fs::create_directories(dir_);
    key_ = (dir_ / "bus.key").string();
    signing::write_new_key(key_);
  }
  void TearDown() override { fs::remove_all(dir_); }
  config::Config load(const Combo& c, const std::string& mode) {
    std::vector<std::string> o = c.overrides;
    o.push_back("security.key_file=" + key_);
    o.push_back("security.mode=" + mode);
    return config::load_config_file(source_path("config/" + c.config), o);
  }
  std::string path(const std::string& name) const { return (dir_ / name).string(); }

  fs::path dir_;
  std::string key_;
};

TEST_F(SignedReplay, RegressionFlightsSignedGiveTheSameOutputs) {
  const std::vector<Combo> combos = regression_combos();
  ASSERT_GE(combos.size(), 10U);
  std::ostringstream log;
  for (const Combo& c : combos) {
    SCOPED_TRACE(c.name);
    const std::string flight = source_path("test/data/flights/" + c.flight + ".lcmlog");
    const config::Config off = load(c, "off");
    const config::Config require = load(c, "require");
    lcmlog::SignLogSummary signed_summary;
    ASSERT_TRUE(lcmlog::sign_log(require, flight, path("signed.lcmlog"), lcmlog::SignLogOptions{},
                                 signed_summary, log))
        << log.str();
    ASSERT_GT(signed_summary.signed_events, 1000);
    lcmlog::ReplayOptions options;
    options.cycle_on_every_input = true;  // as the golden files are made
    lcmlog::ReplaySummary plain, with_signatures;
    ASSERT_TRUE(lcmlog::replay_log(off, flight, path("plain.out"), options, plain, log))
        << log.str();
    ASSERT_TRUE(lcmlog::replay_log(require, path("signed.lcmlog"), path("signed.out"), options,
                                   with_signatures, log))
        << log.str();
    const auto a = events_on(path("plain.out"), off.channels.motor_pwm);
    const auto b = events_on(path("signed.out"), off.channels.motor_pwm);
    ASSERT_GT(a.size(), 1000U);
    EXPECT_TRUE(a == b) << a.size() << " outputs unsigned, " << b.size() << " signed";
    EXPECT_EQ(with_signatures.rejected, plain.rejected);
    EXPECT_EQ(with_signatures.armed_s, plain.armed_s);
    // The unsigned flight under require: nothing taken, never armed.
    lcmlog::ReplaySummary refused;
    ASSERT_TRUE(lcmlog::replay_log(require, flight, path("refused.out"), options, refused, log));
    EXPECT_EQ(refused.armed_s, 0.0);
    EXPECT_EQ(refused.rejected, refused.input_events);
  }
}

TEST_F(SignedReplay, VerifyFindsExactlyTheEventThatWasChanged) {
  const Combo c = regression_combos().front();
  const config::Config config = load(c, "off");  // --verify needs only the key file
  const std::string flight = source_path("test/data/flights/" + c.flight + ".lcmlog");
  std::ostringstream log;
  lcmlog::SignLogSummary s;
  ASSERT_TRUE(lcmlog::sign_log(config, flight, path("signed.lcmlog"), {}, s, log)) << log.str();
  lcmlog::ReplayOptions verify;
  verify.verify = true;
  lcmlog::ReplaySummary good;
  ASSERT_TRUE(
      lcmlog::replay_log(config, path("signed.lcmlog"), path("good.out"), verify, good, log));
  EXPECT_EQ(good.unverified, 0);
  std::int64_t verified = 0;
  for (const auto& v : good.verification)
    verified += static_cast<std::int64_t>(v.counts.signed_accepted);
  EXPECT_EQ(verified, s.signed_events);
  // One byte of one event changed, in a copy written with LCM's own writer.
  {
    lcm::LogFile in(path("signed.lcmlog"), "r");
    lcm::LogFile out(path("tampered.lcmlog"), "w");
    int k = 0;
    while (const lcm::LogEvent* ev = in.readNextEvent()) {
      lcm::LogEvent copy = *ev;
      std::vector<std::uint8_t> bytes(static_cast<const std::uint8_t*>(ev->data),
                                      static_cast<const std::uint8_t*>(ev->data) + ev->datalen);
      if (++k == 500) bytes[8] ^= 1;
      copy.data = bytes.data();
      out.writeEvent(&copy);
    }
  }
  lcmlog::ReplaySummary bad;
  ASSERT_TRUE(
      lcmlog::replay_log(config, path("tampered.lcmlog"), path("bad.out"), verify, bad, log));
  EXPECT_EQ(bad.unverified, 1);
  std::uint64_t bad_signatures = 0;
  for (const auto& v : bad.verification) bad_signatures += v.counts.rejected_bad_signature;
  EXPECT_EQ(bad_signatures, 1U);
}

}  // namespace
}  // namespace motormix::test
