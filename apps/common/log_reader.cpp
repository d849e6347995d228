#include "common/log_reader.h"

#include <sys/stat.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <vector>

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

// The byte offset of the first sync word (0xEDA1DA01, big-endian) at or after `from`, or −1; reads
// `file` to its end in 1 MiB pieces (the file position is left there).
int64_t find_sync_word(std::FILE* file, int64_t from) {
  static const unsigned char kSync[4] = {0xED, 0xA1, 0xDA, 0x01};
  if (std::fseek(file, static_cast<long>(from), SEEK_SET) != 0) return -1;
  std::vector<unsigned char> buf(1 << 20);
  size_t kept = 0;  // the last 3 bytes of the previous piece, at the front of buf
  int64_t base = from;
  for (;;) {
    const size_t n = std::fread(buf.data() + kept, 1, buf.size() - kept, file);
    const size_t have = kept + n;
    const auto hit = std::search(buf.begin(), buf.begin() + static_cast<std::ptrdiff_t>(have), kSync, kSync + 4);
    if (hit != buf.begin() + static_cast<std::ptrdiff_t>(have)) return base + (hit - buf.begin());
    if (n == 0) return -1;
    kept = std::min<size_t>(3, have);
    std::copy(buf.begin() + static_cast<std::ptrdiff_t>(have - kept), buf.begin() + static_cast<std::ptrdiff_t>(have),
              buf.begin());
    base += static_cast<int64_t>(have - kept);
  }
}

// The byte offset of the first event header at or after `from`: a sync word followed by a channel
// length of 1 … 999 and a data length ≥ 0 (so that four bytes of a message's data that happen to
// read 0xEDA1DA01 are not taken for one), or −1.
int64_t next_event_header(std::FILE* file, int64_t from) {
  for (int64_t at = find_sync_word(file, from); at >= 0; at = find_sync_word(file, at + 1)) {
    unsigned char h[kHeaderBytes];
    if (std::fseek(file, static_cast<long>(at), SEEK_SET) != 0 || std::fread(h, 1, sizeof h, file) != sizeof h) return -1;
    const auto channel_len = static_cast<int32_t>(big_endian(h + 20, 4));
    const auto data_len = static_cast<int32_t>(big_endian(h + 24, 4));
    if (channel_len >= 1 && channel_len <= kLongestChannel && data_len >= 0) return at;
  }
  return -1;
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
    // messages, frames, are about 1 MB) and no event after it, that is a recorder stopped
    // mid-write; beyond it, or with another event's sync word in the bytes left, the length is
    // damaged (one flipped bit in a length in mid-log was taken for a torn end, and the rest of
    // the log dropped with a warning; review, session 33).
    if (data_len <= kLargestMessage) {
      const int64_t next = next_event_header(file_, offset_ + kHeaderBytes);
      if (next < 0)
        return tear(std::to_string(left) + " of its " + std::to_string(channel_len + static_cast<int64_t>(data_len)) +
                    " channel and data bytes");
      error_ = at + ": data length " + std::to_string(data_len) + " runs past the end of the file, but another event " +
               "starts at byte " + std::to_string(next) + " (a damaged length, not a torn last event)";
      return false;
    }
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
