#include "log/log_reader.hpp"

#include <sys/stat.h>

#include <algorithm>
#include <array>

namespace motormix::lcmlog {

namespace {

constexpr std::uint32_t kSyncWord = 0xEDA1DA01U;
constexpr std::uint64_t kHeaderSize = 4 + 8 + 8 + 4 + 4;
// While searching for the next event after damage, read this much at a time.
constexpr std::size_t kScanChunk = 64 * 1024;

std::uint64_t big_endian(const std::uint8_t* p, int bytes) {
  std::uint64_t v = 0;
  for (int i = 0; i < bytes; ++i) v = (v << 8) | p[i];
  return v;
}

}  // namespace

LogReader::LogReader(const std::string& path) {
  struct stat st {};
  if (stat(path.c_str(), &st) != 0 || !S_ISREG(st.st_mode)) return;
  file_ = std::fopen(path.c_str(), "rb");
  size_ = static_cast<std::uint64_t>(st.st_size);
}

LogReader::~LogReader() {
  if (file_) std::fclose(file_);
}

std::uint64_t LogReader::skipped_bytes() const {
  std::uint64_t total = 0;
  for (const SkippedRange& r : skipped_) total += r.end - r.begin;
  return total;
}

bool LogReader::read_at(std::uint64_t offset, LogEventView& ev) {
  if (offset + kHeaderSize > size_) return false;
  std::array<std::uint8_t, kHeaderSize> h{};
  // Events are read in order: seek only after damage (a seek drops stdio's
  // buffer). The position is tracked here: ftell() is a system call.
  if (stream_at_ != offset) {
    if (std::fseek(file_, static_cast<long>(offset), SEEK_SET) != 0) {
      stream_at_ = kUnknownPosition;
      return false;
    }
    stream_at_ = offset;
  }
  if (std::fread(h.data(), 1, h.size(), file_) != h.size()) {
    stream_at_ = kUnknownPosition;
    return false;
  }
  stream_at_ += h.size();
  if (big_endian(h.data(), 4) != kSyncWord) return false;
  const auto channel_len = static_cast<std::int32_t>(big_endian(h.data() + 20, 4));
  const auto data_len = static_cast<std::int32_t>(big_endian(h.data() + 24, 4));
  if (channel_len < 1 || channel_len > kMaxChannelLength || data_len < 0 ||
      data_len > kMaxDataLength ||
      offset + kHeaderSize + static_cast<std::uint64_t>(channel_len) +
              static_cast<std::uint64_t>(data_len) >
          size_) {
    return false;
  }
  ev.channel.resize(static_cast<std::size_t>(channel_len));
  ev.data.resize(static_cast<std::size_t>(data_len));
  if (std::fread(ev.channel.data(), 1, ev.channel.size(), file_) != ev.channel.size() ||
      std::fread(ev.data.data(), 1, ev.data.size(), file_) != ev.data.size()) {
    stream_at_ = kUnknownPosition;
    return false;
  }
  stream_at_ += ev.channel.size() + ev.data.size();
  // Channel names are printable: a "header" found inside message data rarely is.
  if (!std::all_of(ev.channel.begin(), ev.channel.end(),
                   [](char c) { return c > ' ' && c < 0x7f; })) {
    return false;
  }
  ev.eventnum = static_cast<std::int64_t>(big_endian(h.data() + 4, 8));
  ev.timestamp = static_cast<std::int64_t>(big_endian(h.data() + 12, 8));
  ev.offset = offset;
  return true;
}

bool LogReader::fill(LogEventView& ev) {
  if (!file_ || position_ >= size_) return false;
  if (read_at(position_, ev)) {
    position_ = ev.offset + kHeaderSize + ev.channel.size() + ev.data.size();
    return true;
  }
  // Damage at position_: find the next offset where a valid event starts.
  const std::uint64_t damage = position_;
  std::vector<std::uint8_t> chunk(kScanChunk + 3);
  for (std::uint64_t base = damage + 1; base < size_; base += kScanChunk) {
    const std::size_t want =
        static_cast<std::size_t>(std::min<std::uint64_t>(kScanChunk + 3, size_ - base));
    if (std::fseek(file_, static_cast<long>(base), SEEK_SET) != 0) {
      stream_at_ = kUnknownPosition;
      break;
    }
    const std::size_t got = std::fread(chunk.data(), 1, want, file_);
    stream_at_ = got == want ? base + got : kUnknownPosition;
    for (std::size_t i = 0; i + 4 <= got; ++i) {
      if (big_endian(chunk.data() + i, 4) != kSyncWord) continue;
      if (read_at(base + i, ev)) {
        skipped_.push_back({damage, base + i});
        position_ = ev.offset + kHeaderSize + ev.channel.size() + ev.data.size();
        return true;
      }
    }
  }
  skipped_.push_back({damage, size_});
  position_ = size_;
  return false;
}

const LogEventView* LogReader::peek() {
  if (ahead_.empty() && !at_end_) {
    // The buffers of the event next() returned before last: no allocation
    // per event in the replay's loop.
    LogEventView ev = std::move(spare_);
    if (fill(ev)) {
      ahead_.push_back(std::move(ev));
    } else {
      at_end_ = true;
    }
  }
  return ahead_.empty() ? nullptr : &ahead_.front();
}

const LogEventView* LogReader::next() {
  if (!peek()) return nullptr;
  std::swap(current_, ahead_.front());
  spare_ = std::move(ahead_.front());
  ahead_.pop_front();
  return &current_;
}

bool LogReader::look_ahead_for(const std::string& channel, std::int64_t span_us,
                               std::size_t max_events) {
  if (!peek()) return false;
  for (const LogEventView& ev : ahead_)
    if (ev.channel == channel) return true;
  const std::int64_t first = ahead_.front().timestamp;
  // A damaged timestamp may be anywhere in int64: the span in unsigned.
  const auto spanned = [&]() {
    const std::int64_t last = ahead_.back().timestamp;
    return last > first && static_cast<std::uint64_t>(last) - static_cast<std::uint64_t>(first) >=
                               static_cast<std::uint64_t>(span_us);
  };
  while (!at_end_ && ahead_.size() < max_events && !spanned()) {
    LogEventView ev;
    if (!fill(ev)) {
      at_end_ = true;
      break;
    }
    const bool found = ev.channel == channel;
    ahead_.push_back(std::move(ev));
    if (found) return true;
  }
  return false;
}

}  // namespace motormix::lcmlog
