// The log reader and `replay` on arbitrary bytes: every event found is
// whole, the damaged ranges do not overlap and stay inside the file, and the
// replay's output is bounded by the time its segments cover.

#include "log/log_reader.hpp"
#include "log/log_replay.hpp"

#include <motormix/config/load_config.hpp>

#include <unistd.h>

#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <sstream>
#include <string>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace motormix;
  static const std::string dir = [] {
    const char* tmp = std::getenv("TMPDIR");
    return std::string(tmp ? tmp : "/tmp");
  }();
  static const std::string in_path = dir + "/motormix-fuzz-" + std::to_string(getpid()) + ".lcmlog";
  static const std::string out_path = in_path + ".out";
  static const config::Config config = config::load_config_text(
      "geometry: {preset: quad_x}\nloop_rate_hz: 50\nstatus_rate_hz: 5\n"
      "channels: {setpoint: S, pid: P}\n",
      "fuzz");
  if (std::FILE* f = std::fopen(in_path.c_str(), "wb")) {
    std::fwrite(data, 1, size, f);
    std::fclose(f);
  } else {
    std::abort();
  }

  lcmlog::LogReader reader(in_path);
  std::uint64_t last_end = 0;
  std::size_t checked_ranges = 0;
  while (const lcmlog::LogEventView* ev = reader.next()) {
    if (ev->offset + 28 + ev->channel.size() + ev->data.size() > size) std::abort();
    for (; checked_ranges < reader.skipped().size(); ++checked_ranges) {
      const lcmlog::SkippedRange& r = reader.skipped()[checked_ranges];
      if (r.begin < last_end || r.end <= r.begin || r.end > size) std::abort();
      last_end = r.end;
    }
  }

  lcmlog::ReplaySummary s;
  std::ostringstream log;
  if (lcmlog::replay_log(config, in_path, out_path, lcmlog::ReplayOptions{}, s, log)) {
    const double segments = static_cast<double>(s.discontinuities + 1);
    if (static_cast<double>(s.outputs) > config.loop_rate_hz * s.duration_s + segments)
      std::abort();
  }
  return 0;
}
