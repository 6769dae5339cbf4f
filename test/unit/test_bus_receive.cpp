// The bus's one door (bus/receive.hpp): each message type's length field
// where WireShape says, sizes measured from the generated encoder equal to
// the .lcm file's arithmetic, every hostile variant refused for its reason
// before any vector is sized, seeded random and mutated bytes never thrown
// out, the signing policy first; the shutdown signals held and restored.

#include "bus/process.hpp"
#include "bus/receive.hpp"
#include "bus/shutdown_signals.hpp"
#include "integration/hostile_messages.hpp"

#include <motormix/signing.hpp>

#include <gtest/gtest.h>

#include <unistd.h>

#include <chrono>
#include <csignal>
#include <random>
#include <sstream>
#include <stdexcept>

namespace motormix {
namespace {

template <typename Message>
void expect_length_at_its_offset(int n) {
  Message m{};
  bus::WireShape<Message>::size(m, n);
  const std::vector<std::uint8_t> b = test::encode_plain(m);
  ASSERT_GE(b.size(), static_cast<std::size_t>(bus::WireShape<Message>::kLengthOffset + 4));
  EXPECT_EQ(bus::detail::int32_at(b.data() + bus::WireShape<Message>::kLengthOffset), n);
  EXPECT_EQ(bus::check_wire<Message>(b.data(), b.size()), bus::Refusal::kNone);
}

TEST(BusReceive, EachLengthFieldIsWhereItsShapeSays) {
  expect_length_at_its_offset<motor_pwm_t>(3);
  expect_length_at_its_offset<motor_status_t>(5);
  expect_length_at_its_offset<esc_telemetry_t>(7);
  expect_length_at_its_offset<vehicle_state_t>(6);
}

TEST(BusReceive, MeasuredSizesAreTheLcmFilesArithmetic) {
  // Written out from the .lcm files, independently of the encoder:
  // fingerprint 8, then each field's bytes.
  const auto& pwm = bus::detail::MeasuredSize<motor_pwm_t>::get();
  EXPECT_EQ(pwm.fixed, 8 + 8 + 4 + 1 + 8 + 8 + 4 + 4);
  EXPECT_EQ(pwm.per_element, 4 + 4 + 1);
  const auto& esc = bus::detail::MeasuredSize<esc_telemetry_t>::get();
  EXPECT_EQ(esc.fixed, 8 + 8 + 4);
  EXPECT_EQ(esc.per_element, 1 + 6 * 4);
  const auto& ms = bus::detail::MeasuredSize<motor_status_t>::get();
  EXPECT_EQ(ms.fixed, 8 + 8 + 4);
  EXPECT_EQ(ms.per_element, 1);
  EXPECT_EQ(bus::detail::MeasuredSize<setpoint_t>::get().fixed, 8 + 8 + 4 + 4 + 1);
}

motor_pwm_t good_pwm(int n = 4) {
  motor_pwm_t m{};
  bus::WireShape<motor_pwm_t>::size(m, n);
  m.utime = 1234;
  m.pwm.assign(static_cast<std::size_t>(n), 1500.0F);
  m.armed = true;
  return m;
}

template <typename Message>
void expect_each_variant_refused_for_its_reason(
    const Message& good, const std::function<void(Message&, float)>& poison = {}) {
  signing::Policy off;
  bus::Refusals counts;
  const auto variants = test::hostile_variants(good, poison);
  for (const test::Hostile& h : variants) {
    Message out{};
    EXPECT_EQ(bus::receive(off, "CH", h.bytes.data(), h.bytes.size(), 0, out, counts), h.refusal)
        << h.what;
  }
  EXPECT_EQ(counts.bad_length, test::count_of(variants, bus::Refusal::kBadLength));
  EXPECT_EQ(counts.truncated, test::count_of(variants, bus::Refusal::kTruncated));
  EXPECT_EQ(counts.trailing, test::count_of(variants, bus::Refusal::kTrailing));
  EXPECT_EQ(counts.wrong_type, 1u);
  EXPECT_EQ(counts.taken, test::count_of(variants, bus::Refusal::kNone));
  EXPECT_EQ(counts.refused() + counts.taken, variants.size());
}

TEST(BusReceive, EveryHostileVariantIsRefusedForItsReason) {
  expect_each_variant_refused_for_its_reason<motor_pwm_t>(
      good_pwm(), [](motor_pwm_t& m, float v) { m.pwm.assign(m.pwm.size(), v); });
  motor_status_t ms{};
  bus::WireShape<motor_status_t>::size(ms, 4);
  expect_each_variant_refused_for_its_reason(ms);
  esc_telemetry_t esc{};
  bus::WireShape<esc_telemetry_t>::size(esc, 4);
  expect_each_variant_refused_for_its_reason(esc);
  expect_each_variant_refused_for_its_reason(mixer_status_t{});
  expect_each_variant_refused_for_its_reason(setpoint_t{});
}

TEST(BusReceive, AGoodMessageDecodesWhole) {
  signing::Policy off;
  bus::Refusals counts;
  const motor_pwm_t sent = good_pwm(6);
  const auto b = test::encode_plain(sent);
  motor_pwm_t got{};
  ASSERT_EQ(bus::receive(off, "MOTOR_PWM", b.data(), b.size(), 0, got, counts),
            bus::Refusal::kNone);
  EXPECT_EQ(got.num_motors, 6);
  EXPECT_EQ(got.pwm, sent.pwm);
  EXPECT_EQ(counts.taken, 1u);
  EXPECT_EQ(bus::receive(off, "MOTOR_PWM", nullptr, 0, 0, got, counts), bus::Refusal::kTruncated);
}

TEST(BusReceive, AReusedMessageTakesTheNewLengthEvenZero) {
  // lcm-gen's decoder does not touch the arrays when the length is 0.
  signing::Policy off;
  bus::Refusals counts;
  motor_pwm_t reused{};
  const auto four = test::encode_plain(good_pwm(4));
  const auto none = test::encode_plain(good_pwm(0));
  ASSERT_EQ(bus::receive(off, "P", four.data(), four.size(), 0, reused, counts),
            bus::Refusal::kNone);
  ASSERT_EQ(bus::receive(off, "P", none.data(), none.size(), 0, reused, counts),
            bus::Refusal::kNone);
  EXPECT_EQ(reused.num_motors, 0);
  EXPECT_TRUE(reused.pwm.empty());
  EXPECT_TRUE(reused.command.empty());
  EXPECT_TRUE(reused.direction.empty());
}

TEST(BusReceive, ARefusalAfterTheGuardMovesTheCountFromTaken) {
  bus::Refusals r;
  r.count(bus::Refusal::kNone);
  r.refuse_taken(bus::Refusal::kBadLength);
  EXPECT_EQ(r.taken, 0u);
  EXPECT_EQ(r.bad_length, 1u);
  EXPECT_EQ(r.refused(), 1u);
}

TEST(BusReceive, TheSignatureIsJudgedFirst) {
  std::array<std::uint8_t, signing::kKeyBytes> bytes{};
  for (std::size_t i = 0; i < bytes.size(); ++i) bytes[i] = static_cast<std::uint8_t>(i * 7 + 1);
  const signing::Key key(bytes);
  const std::int64_t now = 1'700'000'000'000'000;
  signing::Policy require(signing::Mode::kRequire, key, 1);
  signing::Policy signer(signing::Mode::kRequire, key, 2);
  bus::Refusals counts;
  std::vector<std::uint8_t> buffer;
  const motor_pwm_t m = good_pwm();
  const std::size_t n = signing::encode_sealed(signer, "MOTOR_PWM", m, buffer, now);
  motor_pwm_t got{};
  EXPECT_EQ(bus::receive(require, "MOTOR_PWM", buffer.data(), n, now, got, counts),
            bus::Refusal::kNone);
  // Unsigned, and a hostile length under a signature from another key: the
  // signature refuses both, before the length is looked at.
  const auto plain = test::encode_plain(m);
  EXPECT_EQ(bus::receive(require, "MOTOR_PWM", plain.data(), plain.size(), now, got, counts),
            bus::Refusal::kSignature);
  EXPECT_EQ(counts.signature, 1u);
  EXPECT_EQ(require.counts().rejected_unsigned, 1u);
  // Signed with the key, hostile length inside: the signature verifies, the
  // guard refuses the length.
  std::vector<std::uint8_t> bad = plain;
  bad[16] = 0x7f;
  bad.resize(bad.size() + signing::kTrailerBytes);
  const std::size_t signed_bad = signer.seal("MOTOR_PWM", bad.data(), plain.size(), now + 10);
  EXPECT_EQ(bus::receive(require, "MOTOR_PWM", bad.data(), signed_bad, now + 10, got, counts),
            bus::Refusal::kBadLength);
}

TEST(BusReceive, SeededRandomAndMutatedBytesNeverThrowOrTakeALie) {
  std::mt19937 rng(46);
  signing::Policy off;
  bus::Refusals counts;
  const auto good = test::encode_plain(good_pwm());
  constexpr int kTries = 20000;
  for (int i = 0; i < kTries; ++i) {
    std::vector<std::uint8_t> b = good;
    if (i % 2 == 0) {
      b.resize(rng() % 96);
      for (auto& x : b) x = static_cast<std::uint8_t>(rng());
    } else {
      for (int k = 0; k < 3; ++k) b[rng() % b.size()] = static_cast<std::uint8_t>(rng());
      if (rng() % 4 == 0) b.resize(rng() % (b.size() + 8));
    }
    motor_pwm_t got{};
    if (bus::receive(off, "MOTOR_PWM", b.data(), b.size(), 0, got, counts) == bus::Refusal::kNone) {
      // Whatever was taken is a whole, consistent message.
      ASSERT_GE(got.num_motors, 0);
      ASSERT_LE(got.num_motors, kMaxMotors);
      ASSERT_EQ(got.pwm.size(), static_cast<std::size_t>(got.num_motors));
      ASSERT_EQ(static_cast<std::size_t>(got.getEncodedSize()), b.size());
    }
  }
  EXPECT_EQ(counts.taken + counts.refused(), static_cast<std::uint64_t>(kTries));
  EXPECT_GT(counts.refused(), 0u);
}

TEST(ShutdownSignals, ASignalIsReadFromTheDescriptorAndTheMaskRestored) {
  sigset_t before;
  pthread_sigmask(SIG_SETMASK, nullptr, &before);
  ASSERT_FALSE(sigismember(&before, SIGHUP));
  {
    bus::ShutdownSignals signals;
    ASSERT_TRUE(signals.good()) << signals.error();
    EXPECT_FALSE(signals.requested());
    pthread_kill(pthread_self(), SIGHUP);  // blocked: waits on the descriptor
    EXPECT_TRUE(signals.requested());
    EXPECT_EQ(signals.last_signal(), SIGHUP);
  }
  sigset_t after;
  pthread_sigmask(SIG_SETMASK, nullptr, &after);
  EXPECT_FALSE(sigismember(&after, SIGHUP));
}

// The wait every process is built on: watched descriptors report by their
// index, a negative one never, a signal wakes it, and a timeout finer than a
// millisecond is kept (the serial driver's frame slots).
TEST(BusProcess, WatchedDescriptorsWakeTheWaitByIndexAndTheTimeoutIsFine) {
  std::ostringstream log;
  bus::Process process("motormix test", "memq://", log);
  ASSERT_TRUE(process.good()) << log.str();
  int a[2];
  int b[2];
  ASSERT_EQ(pipe(a), 0);
  ASSERT_EQ(pipe(b), 0);
  const std::size_t never = process.watch(-1);
  const std::size_t first = process.watch(a[0]);
  const std::size_t second = process.watch(b[0]);
  EXPECT_EQ(never, 0u);
  EXPECT_EQ(first, 1u);
  EXPECT_EQ(second, 2u);
  ASSERT_EQ(write(b[1], "x", 1), 1);
  bus::Woke woke = process.wait(1000);
  EXPECT_EQ(woke.error, 0);
  EXPECT_FALSE(woke.bus);
  EXPECT_FALSE(woke.signal);
  EXPECT_FALSE(woke.own[never]);
  EXPECT_FALSE(woke.own[first]);
  EXPECT_TRUE(woke.own[second]);
  char c = 0;
  ASSERT_EQ(read(b[0], &c, 1), 1);

  // 200 us asked: back well before a millisecond-rounded wait would be.
  constexpr std::int64_t kFineWaitNs = 200'000;
  constexpr double kFineWaitBoundS = 0.05;  // generous: a loaded machine
  const auto t0 = std::chrono::steady_clock::now();
  woke = process.wait_ns(kFineWaitNs);
  const double waited =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  EXPECT_TRUE(woke.own.none());
  EXPECT_GE(waited, 1e-9 * static_cast<double>(kFineWaitNs));
  EXPECT_LT(waited, kFineWaitBoundS);

  pthread_kill(pthread_self(), SIGTERM);  // blocked by the process: read in the wait
  woke = process.wait(-1);
  EXPECT_TRUE(woke.signal);
  EXPECT_EQ(process.signals().last_signal(), SIGTERM);

  for (std::size_t i = process.watch(a[1]) + 1; i < bus::kMaxWatched; ++i) process.watch(-1);
  EXPECT_THROW(process.watch(a[0]), std::length_error);
  for (int fd : {a[0], a[1], b[0], b[1]}) close(fd);
}

}  // namespace
}  // namespace motormix
