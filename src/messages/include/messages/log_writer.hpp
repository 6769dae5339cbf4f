#pragma once
// Writes LCM event logs in LCM's own format (log/log_reader.hpp), byte for
// byte what lcm::LogFile writes, through one large buffer: an event costs a
// few copies instead of several stdio calls. The one log writer: the
// offline replay, `motormix sign-log`, the PX4 import and the simulator's
// logs.

#include <cstdint>
#include <cstdio>
#include <string>
#include <vector>

namespace motormix::messages {

class LogWriter {
 public:
  explicit LogWriter(const std::string& path) : file_(std::fopen(path.c_str(), "wb")) {
    if (file_ != nullptr) std::setvbuf(file_, nullptr, _IOFBF, kBufferBytes);
  }
  ~LogWriter() {
    if (file_ != nullptr) std::fclose(file_);
  }
  LogWriter(const LogWriter&) = delete;
  LogWriter& operator=(const LogWriter&) = delete;
  bool good() const { return file_ != nullptr; }
  // False if anything could not be written (disk full, I/O error).
  bool close() {
    if (file_ == nullptr) return false;
    const bool ok = std::fflush(file_) == 0 && !std::ferror(file_);
    const bool closed = std::fclose(file_) == 0;
    file_ = nullptr;
    return ok && closed;
  }

  template <typename Message>
  void write(const std::string& channel, std::int64_t utime, const Message& msg) {
    buffer_.resize(static_cast<std::size_t>(msg.getEncodedSize()));
    msg.encode(buffer_.data(), 0, static_cast<int>(buffer_.size()));
    raw(channel, utime, buffer_.data(), static_cast<int>(buffer_.size()));
  }
  void raw(const std::string& channel, std::int64_t utime, const void* data, int size) {
    std::uint8_t header[28];
    put_be(header, 0xEDA1DA01U, 4);
    put_be(header + 4, static_cast<std::uint64_t>(eventnum_++), 8);
    put_be(header + 12, static_cast<std::uint64_t>(utime), 8);
    put_be(header + 20, static_cast<std::uint32_t>(channel.size()), 4);
    put_be(header + 24, static_cast<std::uint32_t>(size), 4);
    std::fwrite(header, 1, sizeof header, file_);
    std::fwrite(channel.data(), 1, channel.size(), file_);
    std::fwrite(data, 1, static_cast<std::size_t>(size), file_);
  }

 private:
  static constexpr std::size_t kBufferBytes = 1 << 20;
  static void put_be(std::uint8_t* out, std::uint64_t v, int bytes) {
    for (int i = bytes - 1; i >= 0; --i, v >>= 8) out[i] = static_cast<std::uint8_t>(v & 0xFFU);
  }

  std::FILE* file_;
  std::vector<std::uint8_t> buffer_;
  std::int64_t eventnum_ = 0;
};

}  // namespace motormix::messages
