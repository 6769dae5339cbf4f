// A bus attack without the key (security.mode: require) on a running
// `motormix run`, on a private bus. A controller with the key arms the
// mixer and flies it briefly while lcm-logger records its messages; then it
// stops and the mixer disarms. From then on only an attacker talks:
// random bytes, valid messages signed with another key, unsigned armed
// inputs, an unsigned motor test, captured signed messages with a byte
// changed, a flood, and the recorded flight played back by lcm-logplayer.
// Nothing of it is taken: the outputs stay disarmed, no input is accepted,
// no motor test starts, and the mixer's counters by reason equal what was
// sent. Every output the mixer publishes verifies with the key.

#include "integration/mixer_fixture.hpp"
#include "integration/udp_drops.hpp"

#include <motormix/motor_test_t.hpp>
#include <motormix/signing.hpp>

#include <lcm/lcm-cpp.hpp>

#include <unistd.h>
#include <filesystem>
#include <random>
#include <thread>

namespace motormix::test {
namespace {

namespace fs = std::filesystem;

// What the mixer should count, by reason, from what the attacker sent.
struct Expected {
  std::int64_t unsigned_msgs = 0;
  std::int64_t bad_signature = 0;
  std::int64_t replayed = 0;
  std::int64_t total() const { return unsigned_msgs + bad_signature + replayed; }
};

class BusAttack : public MixerProcessTest {
 protected:
  void SetUp() override {
    MixerProcessTest::SetUp();
    dir_ = fs::temp_directory_path() / ("motormix_attack_" + std::to_string(getpid()));
    fs::remove_all(dir_);
    fs::create_directories(dir_);
    key_path_ = (dir_ / "bus.key").string();
    signing::write_new_key(key_path_);
    key_ = signing::load_key(key_path_);
  }
  void TearDown() override { fs::remove_all(dir_); }

  static std::int64_t rejected(const mixer_status_t& s) {
    return s.rejected_unsigned + s.rejected_bad_signature + s.rejected_replayed +
           s.rejected_stale_signature;
  }

  fs::path dir_;
  std::string key_path_;
  signing::Key key_;
};

TEST_F(BusAttack, WithoutTheKeyNothingIsTakenAndEveryRefusalIsCounted) {
  recorder_key_ = &key_;
  start({"security.mode=require", "security.key_file=" + key_path_});
  const std::string log_path = (dir_ / "captured.lcmlog").string();
  // The controller's messages only: played back later, they are what an
  // attacker who recorded the bus holds.
  auto logger = std::make_unique<ChildProcess>(std::vector<std::string>{
      "lcm-logger", "-q", "-c", config_.channels.setpoint + "|" + config_.channels.pid, log_path});
  std::this_thread::sleep_for(300ms);  // the logger subscribed

  // The controller with the key flies.
  pilot_->sign_with(signing::Policy(signing::Mode::kRequire, key_, 7));
  arm();  // a disarmed setpoint first, then armed at zero throttle, then flying
  // The status (10 Hz) that counts them comes a little later.
  ASSERT_TRUE(bus_->wait_until(
      [](const auto&, const auto& s) { return !s.empty() && s.back().signed_received > 0; }, 2s));
  std::vector<std::vector<std::uint8_t>> captured;  // signed setpoints, as an eavesdropper saw
  for (int k = 0; k < 50; ++k) {
    setpoint_t sp{};
    sp.utime = wall_us();
    sp.throttle = 0.5F;
    sp.armed = true;
    captured.push_back(pilot_->message(config_.channels.setpoint, sp));
    pid_t pid{};
    pid.utime = sp.utime;
    pilot_->message(config_.channels.pid, pid);
    std::this_thread::sleep_for(5ms);
  }
  // The controller goes silent: the failsafe disarms.
  const std::size_t before_silence = bus_->pwm().size();
  ASSERT_TRUE(first_disarmed_after(before_silence, 2s)) << "no disarmed output after silence";
  // The baseline: a status published after the disarmed output, so it
  // counts every message of the controller's (the last came a timeout ago).
  const std::size_t statuses = bus_->status().size();
  logger->signal(SIGINT);
  ASSERT_TRUE(logger->wait_for(5s).has_value());
  ASSERT_TRUE(
      bus_->wait_until([&](const auto&, const auto& s) { return s.size() > statuses; }, 2s));
  const mixer_status_t baseline = bus_->status().back();
  const std::size_t attack_from = bus_->pwm().size();
  EXPECT_EQ(rejected(baseline), 0);
  EXPECT_GT(baseline.signed_received, 100);
  const long drops_before = udp_receive_buffer_drops();
  ASSERT_GE(drops_before, 0);

  Expected expected;
  Pilot attacker(config_);  // no key: unsigned
  Pilot forger(config_);    // another key
  forger.sign_with(signing::Policy(signing::Mode::kRequire, signing::Key{}, 7));
  std::mt19937 rng(38);  // seeded: the same attack every run
  const std::vector<std::string> inputs = {config_.channels.setpoint, config_.channels.pid,
                                           config_.channels.motor_status,
                                           config_.channels.motor_test};
  // Random bytes on every input channel; a blob that happens to end in
  // something shaped like a signature is a bad signature, any other unsigned.
  for (int k = 0; k < 400; ++k) {
    std::vector<std::uint8_t> blob(std::uniform_int_distribution<std::size_t>(0, 120)(rng));
    for (auto& b : blob) b = static_cast<std::uint8_t>(rng());
    if (k % 4 == 0 && blob.size() >= signing::kTrailerBytes) {  // a quarter shaped like one
      std::copy_n("MMS1", 4, blob.end() - static_cast<std::ptrdiff_t>(signing::kTrailerBytes));
    }
    const bool shaped = signing::has_trailer(blob.data(), blob.size());
    ++(shaped ? expected.bad_signature : expected.unsigned_msgs);
    attacker.raw(inputs[static_cast<std::size_t>(k) % inputs.size()], blob);
    if (k % 20 == 0) std::this_thread::sleep_for(1ms);
  }
  // Well-formed armed inputs, unsigned and signed with another key.
  for (int k = 0; k < 200; ++k) {
    attacker.send(true, 0.6);
    forger.send(true, 0.6);
    expected.unsigned_msgs += 2;
    expected.bad_signature += 2;
    std::this_thread::sleep_for(1ms);
  }
  // An unsigned motor test.
  motor_test_t test{};
  test.utime = wall_us();
  test.motor = 1;
  test.throttle = 0.1F;
  test.duration_s = 2.0F;
  attacker.message(config_.channels.motor_test, test);
  ++expected.unsigned_msgs;
  // Captured signed messages with one byte changed (the throttle, or the
  // signature itself).
  for (std::size_t k = 0; k < captured.size(); ++k) {
    std::vector<std::uint8_t> bad = captured[k];
    bad[k % 2 == 0 ? 10 : bad.size() - 1] ^= 0x40;
    attacker.raw(config_.channels.setpoint, bad);
    ++expected.bad_signature;
  }
  // The captured messages as they were: replays.
  for (const auto& bytes : captured) {
    attacker.raw(config_.channels.setpoint, bytes);
    ++expected.replayed;
  }
  // A flood of unsigned armed pairs, as fast as this test's own receivers
  // keep up with.
  for (int k = 0; k < 3000; ++k) {
    attacker.send(true, 0.8);
    expected.unsigned_msgs += 2;
    if (k % 20 == 0) std::this_thread::sleep_for(1ms);
  }
  // The recorded flight played back onto the bus: every message a replay
  // (lcm-logger and lcm-logplayer carry the signature through untouched).
  std::int64_t logged = 0;
  {
    lcm::LogFile log(log_path, "r");
    ASSERT_TRUE(log.good());
    while (const lcm::LogEvent* ev = log.readNextEvent()) {
      ++logged;
      ASSERT_TRUE(signing::has_trailer(static_cast<const std::uint8_t*>(ev->data),
                                       static_cast<std::size_t>(ev->datalen)))
          << "lcm-logger kept the message without its signature";
    }
  }
  ASSERT_GT(logged, 100);
  ChildProcess player({"lcm-logplayer", "-s", "4", log_path});
  ASSERT_EQ(player.wait_for(30s), 0);
  expected.replayed += logged;

  const bool all_counted = bus_->wait_until(
      [&](const auto&, const auto& s) {
        return !s.empty() && rejected(s.back()) - rejected(baseline) >= expected.total();
      },
      5s);
  const long kernel_drops = udp_receive_buffer_drops() - drops_before;
  const mixer_status_t last = bus_->status().back();
  std::printf(
      "attack: sent %lld unsigned, %lld badly signed, %lld replayed; the mixer counted "
      "%lld, %lld, %lld; kernel drops %ld\n",
      static_cast<long long>(expected.unsigned_msgs),
      static_cast<long long>(expected.bad_signature), static_cast<long long>(expected.replayed),
      static_cast<long long>(last.rejected_unsigned - baseline.rejected_unsigned),
      static_cast<long long>(last.rejected_bad_signature - baseline.rejected_bad_signature),
      static_cast<long long>(last.rejected_replayed - baseline.rejected_replayed), kernel_drops);
  if (kernel_drops == 0) {
    EXPECT_TRUE(all_counted);
    EXPECT_EQ(last.rejected_unsigned - baseline.rejected_unsigned, expected.unsigned_msgs);
    EXPECT_EQ(last.rejected_bad_signature - baseline.rejected_bad_signature,
              expected.bad_signature);
    EXPECT_EQ(last.rejected_replayed - baseline.rejected_replayed, expected.replayed);
  } else {
    // Datagrams the kernel dropped never reached the mixer: at most that
    // many are missing from its counts (the test says so).
    std::printf("the kernel dropped %ld datagrams on the private bus\n", kernel_drops);
    EXPECT_LE(expected.total() - (rejected(last) - rejected(baseline)), kernel_drops);
  }
  EXPECT_EQ(last.rejected_stale_signature, baseline.rejected_stale_signature);
  // Nothing taken, nothing armed, no motor test.
  EXPECT_EQ(last.setpoint_received, baseline.setpoint_received);
  EXPECT_EQ(last.pid_received, baseline.pid_received);
  EXPECT_EQ(last.signed_received, baseline.signed_received);
  EXPECT_EQ(last.motor_status_received, baseline.motor_status_received);
  EXPECT_EQ(last.motor_tests_started, baseline.motor_tests_started);
  EXPECT_EQ(last.security_mode, mixer_status_t::SECURITY_REQUIRE);
  const auto pwm = bus_->pwm();
  ASSERT_GT(pwm.size(), attack_from + 100);
  for (std::size_t i = attack_from; i < pwm.size(); ++i) {
    ASSERT_FALSE(pwm[i].armed) << "output " << i << " armed during the attack";
  }
  for (const auto& s : bus_->status()) {
    ASSERT_EQ(s.motor_test_state, mixer_status_t::MOTOR_TEST_NONE);
  }
  mixer_->signal(SIGTERM);
  EXPECT_EQ(mixer_->wait_for(10s), 0);
  // Everything the mixer published was signed, and verified with the key
  // (counted once its last messages have reached the recorder; bounded).
  std::size_t published = 0;
  for (int k = 0; k < 100; ++k) {
    published = bus_->pwm().size() + bus_->status().size();
    if (static_cast<std::size_t>(bus_->signed_messages()) == published) break;
    std::this_thread::sleep_for(10ms);
  }
  EXPECT_EQ(static_cast<std::size_t>(bus_->signed_messages()), published);
  EXPECT_EQ(bus_->unverified(), 0);
}

}  // namespace
}  // namespace motormix::test
