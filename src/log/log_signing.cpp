#include "log/log_signing.hpp"

#include "bus/clock.hpp"
#include "messages/log_writer.hpp"

#include <motormix/signing.hpp>

#include <algorithm>
#include <optional>
#include <ostream>
#include <vector>

namespace motormix::lcmlog {

bool sign_log(const config::Config& config, const std::string& in_path, const std::string& out_path,
              const SignLogOptions& options, SignLogSummary& summary, std::ostream& log) {
  const config::Security& security = config.security;
  if (security.key_file.empty()) {
    log << "motormix sign-log: no key: set security.key_file\n";
    return false;
  }
  std::optional<signing::Signer> signer;
  try {
    signer.emplace(signing::load_key(security.key_file),
                   static_cast<std::uint8_t>(security.link_id));
  } catch (const signing::KeyError& e) {
    log << "motormix sign-log: security.key_file: " << e.what() << "\n";
    return false;
  }
  LogReader in(in_path);
  if (!in.good()) {
    log << "motormix sign-log: cannot read " << in_path << "\n";
    return false;
  }
  messages::LogWriter out(out_path);
  if (!out.good()) {
    log << "motormix sign-log: cannot write " << out_path << "\n";
    return false;
  }
  const std::int64_t now = bus::wall_us();
  std::int64_t first = -1;
  std::vector<std::uint8_t> buffer;
  while (const LogEventView* ev = in.next()) {
    if (first < 0) first = ev->timestamp;
    const std::size_t size = ev->data.size();
    if (signing::has_trailer(ev->data.data(), size)) {
      out.raw(ev->channel, ev->timestamp, ev->data.data(), static_cast<int>(size));
      ++summary.already_signed;
      continue;
    }
    const std::int64_t stamp = options.from_now ? now + (ev->timestamp - first) : ev->timestamp;
    buffer.resize(size + signing::kTrailerBytes);
    std::copy(ev->data.begin(), ev->data.end(), buffer.begin());
    signer->sign(ev->channel, buffer.data(), size, stamp, buffer.data() + size);
    out.raw(ev->channel, ev->timestamp, buffer.data(), static_cast<int>(buffer.size()));
    ++summary.signed_events;
  }
  summary.skipped = in.skipped();
  for (const SkippedRange& r : summary.skipped) {
    log << "motormix sign-log: warning: " << in_path << " is damaged: bytes " << r.begin << ".."
        << r.end << " hold no valid event and were skipped\n";
  }
  if (!out.close()) {
    log << "motormix sign-log: cannot write " << out_path << " (disk full or I/O error)\n";
    return false;
  }
  return true;
}

}  // namespace motormix::lcmlog
