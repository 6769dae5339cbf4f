#include <motormix/signing_policy.hpp>

namespace motormix::signing {

Policy::Policy(Mode mode, const Key& key, std::uint8_t link_id, double max_skew_s) : mode_(mode) {
  if (mode_ == Mode::kOff) return;
  signer_ = std::make_unique<Signer>(key, link_id);
  verifier_ = std::make_unique<Verifier>(key, max_skew_s);
}

Inbound Policy::check(const std::string& channel, const std::uint8_t* data, std::size_t size,
                      std::int64_t now_unix_us) {
  Inbound in;
  if (mode_ == Mode::kOff) {
    in.accept = true;
    in.payload_size = has_trailer(data, size) ? size - kTrailerBytes : size;
    return in;
  }
  in.verdict = verifier_->verify(channel, data, size, now_unix_us, &in.payload_size);
  switch (in.verdict) {
    case Verdict::kSigned:
      in.accept = true;
      ++counts_.signed_accepted;
      break;
    case Verdict::kUnsigned:
      in.accept = mode_ == Mode::kSign;
      ++(in.accept ? counts_.unsigned_accepted : counts_.rejected_unsigned);
      break;
    case Verdict::kBadSignature:
      ++counts_.rejected_bad_signature;
      break;
    case Verdict::kReplayed:
      ++counts_.rejected_replayed;
      break;
    case Verdict::kStale:
      ++counts_.rejected_stale;
      break;
    case Verdict::kUnknownChannel:
      ++counts_.rejected_other;
      break;
  }
  return in;
}

std::size_t Policy::seal(const std::string& channel, std::uint8_t* buffer, std::size_t size,
                         std::int64_t now_unix_us) {
  if (mode_ == Mode::kOff) return size;
  signer_->sign(channel, buffer, size, now_unix_us, buffer + size);
  return size + kTrailerBytes;
}

}  // namespace motormix::signing
