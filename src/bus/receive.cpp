#include "bus/receive.hpp"

namespace motormix::bus {

void Refusals::count(Refusal r) {
  switch (r) {
    case Refusal::kNone:
      ++taken;
      return;
    case Refusal::kSignature:
      ++signature;
      return;
    case Refusal::kTruncated:
      ++truncated;
      return;
    case Refusal::kTrailing:
      ++trailing;
      return;
    case Refusal::kWrongType:
      ++wrong_type;
      return;
    case Refusal::kBadLength:
      ++bad_length;
      return;
    case Refusal::kUndecodable:
      ++undecodable;
      return;
  }
}

void Refusals::refuse_taken(Refusal r) {
  if (taken > 0) --taken;
  count(r);
}

Refusals& Refusals::operator+=(const Refusals& o) {
  taken += o.taken;
  signature += o.signature;
  truncated += o.truncated;
  trailing += o.trailing;
  wrong_type += o.wrong_type;
  bad_length += o.bad_length;
  undecodable += o.undecodable;
  return *this;
}

std::string describe(const Refusals& r) {
  return std::to_string(r.refused()) + " refused: " + std::to_string(r.signature) + " signature, " +
         std::to_string(r.truncated) + " truncated, " + std::to_string(r.trailing) +
         " trailing bytes, " + std::to_string(r.wrong_type) + " wrong type, " +
         std::to_string(r.bad_length) + " bad length, " + std::to_string(r.undecodable) +
         " undecodable";
}

}  // namespace motormix::bus
