// MAVLink v2: CRC, message packing in wire order, framing and the stream parser.
#include "fact/mavlink.h"

#include <cstdio>
#include <cstring>

namespace fact::mavlink {

// ---------------------------------------------------------------- CRC (CRC-16/MCRF4XX)

uint16_t crc_accumulate(uint8_t byte, uint16_t crc) {
  uint8_t t = byte ^ static_cast<uint8_t>(crc & 0xFF);
  t ^= static_cast<uint8_t>(t << 4);
  return static_cast<uint16_t>((crc >> 8) ^ (t << 8) ^ (t << 3) ^ (t >> 4));
}

uint16_t crc_calculate(const uint8_t* data, std::size_t n, uint16_t crc) {
  for (std::size_t i = 0; i < n; ++i) crc = crc_accumulate(data[i], crc);
  return crc;
}

// ---------------------------------------------------------------- little-endian field access

namespace {

class Writer {
 public:
  explicit Writer(uint8_t* out) : p_(out) {}
  void u8(uint8_t v) { *p_++ = v; }
  void i8(int8_t v) { *p_++ = static_cast<uint8_t>(v); }
  void u16(uint16_t v) { bytes(v, 2); }
  void u32(uint32_t v) { bytes(v, 4); }
  void u64(uint64_t v) { bytes(v, 8); }
  void f32(float v) {
    uint32_t bits;
    std::memcpy(&bits, &v, 4);
    u32(bits);
  }
  template <std::size_t N>
  void f32s(const std::array<float, N>& a) {
    for (float v : a) f32(v);
  }

 private:
  void bytes(uint64_t v, int n) {
    for (int i = 0; i < n; ++i) *p_++ = static_cast<uint8_t>(v >> (8 * i));
  }
  uint8_t* p_;
};

class Reader {
 public:
  explicit Reader(const uint8_t* in) : p_(in) {}
  uint8_t u8() { return *p_++; }
  int8_t i8() { return static_cast<int8_t>(*p_++); }
  uint16_t u16() { return static_cast<uint16_t>(bytes(2)); }
  uint32_t u32() { return static_cast<uint32_t>(bytes(4)); }
  uint64_t u64() { return bytes(8); }
  float f32() {
    const uint32_t bits = u32();
    float v;
    std::memcpy(&v, &bits, 4);
    return v;
  }
  template <std::size_t N>
  void f32s(std::array<float, N>* a) {
    for (float& v : *a) v = f32();
  }

 private:
  uint64_t bytes(int n) {
    uint64_t v = 0;
    for (int i = 0; i < n; ++i) v |= static_cast<uint64_t>(*p_++) << (8 * i);
    return v;
  }
  const uint8_t* p_;
};

}  // namespace

// ---------------------------------------------------------------- messages (wire order)

void pack(const Heartbeat& m, uint8_t* out) {
  Writer w(out);
  w.u32(m.custom_mode);
  w.u8(m.type);
  w.u8(m.autopilot);
  w.u8(m.base_mode);
  w.u8(m.system_status);
  w.u8(m.mavlink_version);
}

void unpack(const uint8_t* in, Heartbeat* m) {
  Reader r(in);
  m->custom_mode = r.u32();
  m->type = r.u8();
  m->autopilot = r.u8();
  m->base_mode = r.u8();
  m->system_status = r.u8();
  m->mavlink_version = r.u8();
}

void pack(const Attitude& m, uint8_t* out) {
  Writer w(out);
  w.u32(m.time_boot_ms);
  for (float v : {m.roll, m.pitch, m.yaw, m.rollspeed, m.pitchspeed, m.yawspeed}) w.f32(v);
}

void unpack(const uint8_t* in, Attitude* m) {
  Reader r(in);
  m->time_boot_ms = r.u32();
  for (float* v : {&m->roll, &m->pitch, &m->yaw, &m->rollspeed, &m->pitchspeed, &m->yawspeed}) *v = r.f32();
}

void pack(const LocalPositionNed& m, uint8_t* out) {
  Writer w(out);
  w.u32(m.time_boot_ms);
  for (float v : {m.x, m.y, m.z, m.vx, m.vy, m.vz}) w.f32(v);
}

void unpack(const uint8_t* in, LocalPositionNed* m) {
  Reader r(in);
  m->time_boot_ms = r.u32();
  for (float* v : {&m->x, &m->y, &m->z, &m->vx, &m->vy, &m->vz}) *v = r.f32();
}

void pack(const CommandLong& m, uint8_t* out) {
  Writer w(out);
  w.f32s(m.param);
  w.u16(m.command);
  w.u8(m.target_system);
  w.u8(m.target_component);
  w.u8(m.confirmation);
}

void unpack(const uint8_t* in, CommandLong* m) {
  Reader r(in);
  r.f32s(&m->param);
  m->command = r.u16();
  m->target_system = r.u8();
  m->target_component = r.u8();
  m->confirmation = r.u8();
}

void pack(const SetPositionTargetLocalNed& m, uint8_t* out) {
  Writer w(out);
  w.u32(m.time_boot_ms);
  for (float v : {m.x, m.y, m.z, m.vx, m.vy, m.vz, m.afx, m.afy, m.afz, m.yaw, m.yaw_rate}) w.f32(v);
  w.u16(m.type_mask);
  w.u8(m.target_system);
  w.u8(m.target_component);
  w.u8(m.coordinate_frame);
}

void unpack(const uint8_t* in, SetPositionTargetLocalNed* m) {
  Reader r(in);
  m->time_boot_ms = r.u32();
  for (float* v : {&m->x, &m->y, &m->z, &m->vx, &m->vy, &m->vz, &m->afx, &m->afy, &m->afz, &m->yaw, &m->yaw_rate})
    *v = r.f32();
  m->type_mask = r.u16();
  m->target_system = r.u8();
  m->target_component = r.u8();
  m->coordinate_frame = r.u8();
}

void pack(const Odometry& m, uint8_t* out) {
  Writer w(out);
  w.u64(m.time_usec);
  for (float v : {m.x, m.y, m.z}) w.f32(v);
  w.f32s(m.q);
  for (float v : {m.vx, m.vy, m.vz, m.rollspeed, m.pitchspeed, m.yawspeed}) w.f32(v);
  w.f32s(m.pose_covariance);
  w.f32s(m.velocity_covariance);
  w.u8(m.frame_id);
  w.u8(m.child_frame_id);
  w.u8(m.reset_counter);   // extensions from here, in declaration order
  w.u8(m.estimator_type);
  w.i8(m.quality);
}

void unpack(const uint8_t* in, Odometry* m) {
  Reader r(in);
  m->time_usec = r.u64();
  for (float* v : {&m->x, &m->y, &m->z}) *v = r.f32();
  r.f32s(&m->q);
  for (float* v : {&m->vx, &m->vy, &m->vz, &m->rollspeed, &m->pitchspeed, &m->yawspeed}) *v = r.f32();
  r.f32s(&m->pose_covariance);
  r.f32s(&m->velocity_covariance);
  m->frame_id = r.u8();
  m->child_frame_id = r.u8();
  m->reset_counter = r.u8();
  m->estimator_type = r.u8();
  m->quality = r.i8();
}

// ---------------------------------------------------------------- registry

namespace {
template <class M>
constexpr MessageInfo info(const char* name) {
  return {M::kId, name, M::kCrcExtra, M::kLength};
}
const MessageInfo kMessages[] = {
    info<Heartbeat>("HEARTBEAT"),
    info<Attitude>("ATTITUDE"),
    info<LocalPositionNed>("LOCAL_POSITION_NED"),
    info<CommandLong>("COMMAND_LONG"),
    info<SetPositionTargetLocalNed>("SET_POSITION_TARGET_LOCAL_NED"),
    info<Odometry>("ODOMETRY"),
};
}  // namespace

const MessageInfo* message_info(uint32_t msgid) {
  for (const MessageInfo& m : kMessages)
    if (m.id == msgid) return &m;
  return nullptr;
}

// ---------------------------------------------------------------- framing

std::vector<uint8_t> frame_bytes(uint32_t msgid, uint8_t crc_extra, const uint8_t* payload,
                                 std::size_t payload_length, uint8_t seq, const Endpoint& from) {
  std::size_t len = payload_length > kMaxPayload ? kMaxPayload : payload_length;
  while (len > 1 && payload[len - 1] == 0) --len;  // MAVLink 2 truncation; the first byte stays
  std::vector<uint8_t> out(kHeaderLength + len + kCrcLength);
  out[0] = kStx;
  out[1] = static_cast<uint8_t>(len);
  out[2] = 0;  // incompat_flags: not signed
  out[3] = 0;  // compat_flags
  out[4] = seq;
  out[5] = from.sysid;
  out[6] = from.compid;
  out[7] = static_cast<uint8_t>(msgid);
  out[8] = static_cast<uint8_t>(msgid >> 8);
  out[9] = static_cast<uint8_t>(msgid >> 16);
  if (len > 0) std::memcpy(out.data() + kHeaderLength, payload, len);
  uint16_t crc = crc_calculate(out.data() + 1, kHeaderLength - 1 + len);
  crc = crc_accumulate(crc_extra, crc);
  out[kHeaderLength + len] = static_cast<uint8_t>(crc);
  out[kHeaderLength + len + 1] = static_cast<uint8_t>(crc >> 8);
  return out;
}

// ---------------------------------------------------------------- parser

const char* to_string(Reject r) {
  switch (r) {
    case Reject::bad_crc: return "bad_crc";
    case Reject::bad_length: return "bad_length";
    case Reject::unknown_id: return "unknown_id";
    case Reject::signed_frame: return "signed_frame";
    case Reject::unknown_flags: return "unknown_flags";
    case Reject::truncated: return "truncated";
  }
  return "unknown";
}

namespace {
std::string hex16(unsigned v) {
  char s[8];
  std::snprintf(s, sizeof s, "0x%04X", v & 0xFFFFu);
  return s;
}
std::string describe(uint32_t msgid) {
  const MessageInfo* m = message_info(msgid);
  return "msgid " + std::to_string(msgid) + (m ? std::string(" (") + m->name + ")" : std::string());
}
}  // namespace

void Parser::feed(const uint8_t* data, std::size_t n, const FrameHandler& on_frame, const RejectHandler& on_reject) {
  buffer_.insert(buffer_.end(), data, data + n);
  while (take_one(on_frame, on_reject)) {
  }
  buffer_.erase(buffer_.begin(), buffer_.begin() + static_cast<std::ptrdiff_t>(start_));
  start_ = 0;
}

void Parser::reject(Reject r, uint32_t msgid, std::string detail, std::size_t skip, const RejectHandler& on_reject) {
  ++rejected_;
  const uint8_t* b = buffer_.data() + start_;
  Rejection j{r, msgid, b[5], b[6], std::move(detail)};
  start_ += skip;
  if (on_reject) on_reject(j);
}

std::size_t Parser::unverified_skip(std::size_t total) const {
  // At the end of a datagram nothing follows it: skipped whole. (Skipping only its start byte let
  // a frame inside an unknown message's payload through, and rescanned every unknown message
  // that ends a datagram; a crafted false start ending exactly there can still hide the frame it
  // covers, as on a stream: review, session 32.)
  if (start_ + total == buffer_.size()) return total;
  return buffer_[start_ + total] == kStx ? total : 1;  // (take_one holds total + 1 bytes)
}

void Parser::end_of_datagram(const FrameHandler& on_frame, const RejectHandler& on_reject) {
  at_end_ = true;
  while (buffered() > 0) {
    if (take_one(on_frame, on_reject)) continue;
    const std::size_t left = buffered();
    if (left == 0) break;  // only garbage was left (skipped)
    const uint8_t* b = buffer_.data() + start_;
    const uint32_t msgid = left >= kHeaderLength ? (b[7] | (b[8] << 8) | (static_cast<uint32_t>(b[9]) << 16)) : 0;
    const std::string claim = left >= 2 ? ", its header claims a " + std::to_string(b[1]) + "-byte payload" : "";
    Rejection j{Reject::truncated, msgid, static_cast<uint8_t>(left > 5 ? b[5] : 0), static_cast<uint8_t>(left > 6 ? b[6] : 0),
                "frame cut short by the end of its datagram: " + std::to_string(left) + " byte(s) left" + claim};
    ++rejected_;
    ++start_;
    if (on_reject) on_reject(j);
  }
  at_end_ = false;
  buffer_.clear();
  start_ = 0;
}

bool Parser::take_one(const FrameHandler& on_frame, const RejectHandler& on_reject) {
  std::size_t at = start_;
  while (at < buffer_.size() && buffer_[at] != kStx) ++at;
  skipped_ += at - start_;
  start_ = at;
  const std::size_t available = buffer_.size() - start_;
  if (available < kHeaderLength) return false;
  const uint8_t* b = buffer_.data() + start_;
  const std::size_t len = b[1];
  const uint8_t incompat = b[2];
  const uint32_t msgid = b[7] | (b[8] << 8) | (static_cast<uint32_t>(b[9]) << 16);
  if (incompat & ~kIncompatSigned) {
    reject(Reject::unknown_flags, msgid, "unsupported incompat_flags " + hex16(incompat) + " on " + describe(msgid), 1,
           on_reject);
    return true;
  }
  const bool is_signed = (incompat & kIncompatSigned) != 0;
  const std::size_t total = kHeaderLength + len + kCrcLength + (is_signed ? kSignatureLength : 0);
  if (available < total) return false;
  const MessageInfo* m = message_info(msgid);
  // A frame that cannot be verified waits for the byte after it (unverified_skip reads it): the
  // bytes held may end where a false start's claimed length does, one byte at a time on a serial
  // line (review, session 30).
  if ((is_signed || m == nullptr) && available < total + 1 && !at_end_) return false;
  if (is_signed) {
    reject(Reject::signed_frame, msgid, "signed frame (" + describe(msgid) + "): signing is not supported",
           unverified_skip(total), on_reject);
    return true;
  }
  if (m == nullptr) {
    reject(Reject::unknown_id, msgid, "unknown msgid " + std::to_string(msgid) + " (no CRC_EXTRA to check it)",
           unverified_skip(total), on_reject);
    return true;
  }
  const uint16_t got = static_cast<uint16_t>(b[kHeaderLength + len] | (b[kHeaderLength + len + 1] << 8));
  const uint16_t want = crc_accumulate(m->crc_extra, crc_calculate(b + 1, kHeaderLength - 1 + len));
  if (got != want) {
    reject(Reject::bad_crc, msgid, "bad CRC on " + describe(msgid) + ": got " + hex16(got) + ", expected " + hex16(want),
           1, on_reject);
    return true;
  }
  if (len > m->length) {
    reject(Reject::bad_length, msgid,
           "bad length on " + describe(msgid) + ": payload " + std::to_string(len) + " bytes, at most " +
               std::to_string(m->length),
           total, on_reject);
    return true;
  }
  Frame f;
  f.seq = b[4];
  f.sysid = b[5];
  f.compid = b[6];
  f.msgid = msgid;
  f.wire_length = static_cast<uint8_t>(len);
  std::memcpy(f.payload.data(), b + kHeaderLength, len);  // the tail stays zero (un-truncation)
  start_ += total;
  ++frames_;
  if (on_frame) on_frame(f);
  return true;
}

}  // namespace fact::mavlink
