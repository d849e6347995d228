#include "common/log_reader.h"

#include <sys/stat.h>

#include <cerrno>
#include <cstring>

namespace fact::app {

namespace {
constexpr uint32_t kSyncWord = 0xEDA1DA01;
constexpr int32_t kLongestChannel = 999;
constexpr int64_t kHeaderBytes = 4 + 8 + 8 + 4 + 4;
constexpr int32_t kLargestMessage = 64 << 20;  // bytes

uint64_t big_endian(const unsigned char* p, int bytes) {
  uint64_t v = 0;
  for (int i = 0; i < bytes; ++i) v = (v << 8) | p[i];
  return v;
}
}  // namespace

LogReader::~LogReader() {
  if (file_) std::fclose(file_);
}

std::string LogReader::open(const std::string& path) {
  path_ = path;
  struct stat st {};
  if (::stat(path.c_str(), &st) != 0) return "cannot read the LCM log " + path + ": " + std::strerror(errno);
  if (!S_ISREG(st.st_mode)) return "cannot read the LCM log " + path + ": not a regular file";
  file_ = std::fopen(path.c_str(), "rb");
  if (!file_) return "cannot read the LCM log " + path + ": " + std::strerror(errno);
  size_ = static_cast<int64_t>(st.st_size);
  return "";
}

bool LogReader::next(lcm::LogEvent* event) {
  if (!file_ || !error_.empty() || torn_ || offset_ >= size_) return false;
  const std::string at = path_ + ": event " + std::to_string(events_) + " at byte " + std::to_string(offset_);
  const auto tear = [&](const std::string& what) {
    torn_ = true;
    note_ = at + ": the log ends inside it (" + what + "): a torn last event, ignored";
    return false;
  };
  unsigned char header[kHeaderBytes];
  if (size_ - offset_ < kHeaderBytes) return tear(std::to_string(size_ - offset_) + " of its 28 header bytes");
  if (std::fread(header, 1, sizeof header, file_) != sizeof header) {
    error_ = at + ": read failed";
    return false;
  }
  const uint32_t sync = static_cast<uint32_t>(big_endian(header, 4));
  const int64_t eventnum = static_cast<int64_t>(big_endian(header + 4, 8));
  const int64_t timestamp = static_cast<int64_t>(big_endian(header + 12, 8));
  const int32_t channel_len = static_cast<int32_t>(big_endian(header + 20, 4));
  const int32_t data_len = static_cast<int32_t>(big_endian(header + 24, 4));
  char hex[16];
  std::snprintf(hex, sizeof hex, "0x%08X", sync);
  if (sync != kSyncWord) {
    error_ = at + ": sync word " + hex + ", expected 0xEDA1DA01 (not an LCM log, or damaged)";
    return false;
  }
  if (channel_len < 1 || channel_len > kLongestChannel) {
    error_ = at + ": channel length " + std::to_string(channel_len) + " (must be 1 … 999)";
    return false;
  }
  if (data_len < 0) {
    error_ = at + ": data length " + std::to_string(data_len) + " is negative";
    return false;
  }
  const int64_t left = size_ - offset_ - kHeaderBytes;
  if (static_cast<int64_t>(channel_len) + data_len > left) {
    // The file ends inside this event. With a plausible length (at most 64 MiB: the largest
    // messages, frames, are about 1 MB) that is a recorder stopped mid-write; beyond it, damage.
    if (data_len <= kLargestMessage)
      return tear(std::to_string(left) + " of its " + std::to_string(channel_len + static_cast<int64_t>(data_len)) +
                  " channel and data bytes");
    error_ = at + ": data length " + std::to_string(data_len) + " is beyond the " + std::to_string(left) +
             " bytes left in the file";
    return false;
  }
  channel_.resize(static_cast<size_t>(channel_len));
  data_.resize(static_cast<size_t>(data_len));
  if (std::fread(channel_.data(), 1, channel_.size(), file_) != channel_.size() ||
      std::fread(data_.data(), 1, data_.size(), file_) != data_.size()) {
    error_ = at + ": read failed";
    return false;
  }
  offset_ += kHeaderBytes + channel_len + data_len;
  event->eventnum = eventnum;
  event->timestamp = timestamp;
  event->channel = channel_;
  event->datalen = data_len;
  event->data = data_.data();
  ++events_;
  return true;
}

std::string for_each_log_event(const std::string& path, const std::string& app,
                               const std::function<void(const lcm::LogEvent&)>& on_event) {
  LogReader log;
  if (std::string e = log.open(path); !e.empty()) return e;
  lcm::LogEvent e;
  while (log.next(&e)) on_event(e);
  if (!log.error().empty()) return "the LCM log is damaged: " + log.error();
  if (log.torn()) std::cerr << app << ": warning: " << log.note() << "\n";
  if (log.events() == 0) return "the LCM log " + path + " holds no events (empty or not an LCM log)";
  return "";
}

}  // namespace fact::app
