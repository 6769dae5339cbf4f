#pragma once
// A reader of LCM event logs that survives damage. LCM's own reader stops at
// the first broken event header (printing "Invalid header after log data")
// and its caller cannot tell a damaged log from a complete one. This one
// checks every header (sync word, channel and data lengths that fit the file,
// a printable channel name), and when one is broken it searches forward for
// the next valid event and reports the byte range it skipped. A last event cut
// short is reported the same way.
//
// Format (big-endian): u32 sync 0xEDA1DA01, i64 event number, i64 timestamp
// (microseconds), i32 channel length, i32 data length, channel, data.

#include <cstdint>
#include <cstdio>
#include <deque>
#include <string>
#include <vector>

namespace motormix::lcmlog {

struct LogEventView {
  std::int64_t eventnum = 0;
  std::int64_t timestamp = 0;  // microseconds
  std::string channel;
  std::vector<std::uint8_t> data;
  std::uint64_t offset = 0;  // byte position of the event's header in the file
};

// A byte range [begin, end) of the file that held no valid event.
struct SkippedRange {
  std::uint64_t begin = 0;
  std::uint64_t end = 0;
};

class LogReader {
 public:
  // Longest channel name accepted (LCM itself allows 63).
  static constexpr std::int32_t kMaxChannelLength = 255;
  // Largest event accepted: far above any LCM message, far below memory limits.
  static constexpr std::int32_t kMaxDataLength = 256 * 1024 * 1024;

  explicit LogReader(const std::string& path);
  ~LogReader();
  LogReader(const LogReader&) = delete;
  LogReader& operator=(const LogReader&) = delete;

  bool good() const { return file_ != nullptr; }
  std::uint64_t size() const { return size_; }

  // The next valid event, or nullptr at the end of the file. Damaged stretches
  // on the way are skipped and recorded in skipped().
  const LogEventView* next();
  // The event next() will return, without consuming it.
  const LogEventView* peek();
  // Reads ahead until an event on `channel` is among the events waiting,
  // or they span `span_us` of log time from the first, or number
  // `max_events`, or the file ends; next() still returns every one of them
  // in order (the file is read once). Whether one on `channel` was found.
  bool look_ahead_for(const std::string& channel, std::int64_t span_us, std::size_t max_events);

  const std::vector<SkippedRange>& skipped() const { return skipped_; }
  std::uint64_t skipped_bytes() const;

 private:
  // Reads a valid event at `offset` into `ev`; false if none starts there.
  bool read_at(std::uint64_t offset, LogEventView& ev);
  bool fill(LogEventView& ev);

  std::FILE* file_ = nullptr;
  std::uint64_t size_ = 0;
  // Where the stdio stream stands (kUnknownPosition after a failed read).
  static constexpr std::uint64_t kUnknownPosition = ~std::uint64_t{0};
  std::uint64_t stream_at_ = 0;
  std::uint64_t position_ = 0;  // where the next event is expected
  LogEventView current_;
  std::deque<LogEventView> ahead_;  // read, not yet returned by next()
  LogEventView spare_;              // buffers to read the next event into
  bool at_end_ = false;             // fill() found no more events
  std::vector<SkippedRange> skipped_;
};

}  // namespace motormix::lcmlog
