#pragma once
// Publishes motormix messages onto LCM, signed when the process's signing
// policy signs (security:). One buffer, grown only when a message is larger
// than any before it: size it at set-up with reserve() and the per-cycle
// publish allocates nothing.

#include "bus/clock.hpp"

#include <motormix/signing_policy.hpp>

#include <lcm/lcm-cpp.hpp>

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

namespace motormix::bus {

class SealedPublisher {
 public:
  SealedPublisher(lcm::LCM& lcm, signing::Policy& policy) : lcm_(lcm), policy_(policy) {}

  // Room for a message of `encoded` bytes and its signature.
  void reserve(std::size_t encoded) {
    if (buffer_.size() < encoded + signing::kTrailerBytes)
      buffer_.resize(encoded + signing::kTrailerBytes);
  }

  // False when the message does not encode or LCM refuses it.
  template <typename Message>
  bool publish(const std::string& channel, const Message& msg,
               std::int64_t now_unix_us = wall_us()) {
    const std::size_t size = signing::encode_sealed(policy_, channel, msg, buffer_, now_unix_us);
    if (size == 0) return false;
    return lcm_.publish(channel, buffer_.data(), static_cast<unsigned>(size)) == 0;
  }

 private:
  lcm::LCM& lcm_;
  signing::Policy& policy_;
  std::vector<std::uint8_t> buffer_;
};

}  // namespace motormix::bus
