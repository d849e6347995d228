// fact_mavlink: MAVLink v2 written here (Debian ships no MAVLink package). Framing, the X.25 CRC
// with CRC_EXTRA, the messages the flight-controller bridge uses, and a stream parser. No I/O, no
// LCM: bytes in, bytes out. The FLU <-> NED conversions are in fact/mavlink_frames.h.
//
// A MAVLink v2 frame (all multi-byte values little-endian):
//   [0] STX 0xFD  [1] payload length  [2] incompat_flags  [3] compat_flags  [4] seq
//   [5] sysid  [6] compid  [7..9] msgid (24 bit)  [10..] payload  [+2] CRC  (+13 signature if
//   incompat_flags & 0x01).
// The CRC is CRC-16/MCRF4XX (the X.25 CRC of MAVLink: init 0xFFFF, reflected poly 0x8408) over
// the bytes after STX up to the payload's end, then the message's CRC_EXTRA byte.
// Payload fields are in wire order (sorted by type size, largest first, stable; extension
// fields after, in declaration order). A sender drops trailing zero bytes of the payload (never
// the first byte); a receiver fills them back with zeros.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

namespace fact::mavlink {

constexpr uint8_t kStx = 0xFD;               // MAVLink v2 start byte
constexpr std::size_t kHeaderLength = 10;    // STX .. msgid
constexpr std::size_t kCrcLength = 2;
constexpr std::size_t kSignatureLength = 13;
constexpr uint8_t kIncompatSigned = 0x01;    // incompat_flags bit: the frame carries a signature
constexpr std::size_t kMaxPayload = 255;

// --- Enum values used by the bridge (common.xml / minimal.xml) ---
constexpr uint8_t kMavTypeGeneric = 0;
constexpr uint8_t kMavTypeQuadrotor = 2;
constexpr uint8_t kMavTypeOnboardController = 18;   // MAV_TYPE_ONBOARD_CONTROLLER
constexpr uint8_t kMavAutopilotPx4 = 12;            // MAV_AUTOPILOT_PX4
constexpr uint8_t kMavAutopilotInvalid = 8;         // MAV_AUTOPILOT_INVALID: not a flight controller
constexpr uint8_t kMavStateActive = 4;              // MAV_STATE_ACTIVE
constexpr uint8_t kModeFlagCustomModeEnabled = 1;   // MAV_MODE_FLAG_CUSTOM_MODE_ENABLED
constexpr uint8_t kModeFlagSafetyArmed = 128;       // MAV_MODE_FLAG_SAFETY_ARMED
constexpr uint8_t kCompIdAutopilot = 1;             // MAV_COMP_ID_AUTOPILOT1
constexpr uint8_t kCompIdOnboardComputer = 191;     // MAV_COMP_ID_ONBOARD_COMPUTER
constexpr uint8_t kFrameLocalNed = 1;               // MAV_FRAME_LOCAL_NED
constexpr uint8_t kFrameBodyFrd = 12;               // MAV_FRAME_BODY_FRD
constexpr uint8_t kEstimatorVio = 3;                // MAV_ESTIMATOR_TYPE_VIO
constexpr uint16_t kCmdComponentArmDisarm = 400;    // MAV_CMD_COMPONENT_ARM_DISARM
constexpr uint16_t kCmdDoSetMode = 176;             // MAV_CMD_DO_SET_MODE
constexpr uint32_t kPx4MainModeOffboard = 6;        // PX4 custom main mode (custom_mode bits 16..23)

// PX4's main mode from a HEARTBEAT's custom_mode (bits 16..23).
inline uint32_t px4_main_mode(uint32_t custom_mode) { return (custom_mode >> 16) & 0xFFu; }

// --- CRC ---
// CRC-16/MCRF4XX: accumulate bytes into crc (start with kCrcInit).
constexpr uint16_t kCrcInit = 0xFFFF;
uint16_t crc_accumulate(uint8_t byte, uint16_t crc);
uint16_t crc_calculate(const uint8_t* data, std::size_t n, uint16_t crc = kCrcInit);

// --- Messages. Units and frames as in the MAVLink definitions; every field documented. ---

// HEARTBEAT (#0, minimal.xml): who is there and in which state.
struct Heartbeat {
  static constexpr uint32_t kId = 0;
  static constexpr uint8_t kCrcExtra = 50;
  static constexpr uint8_t kLength = 9;       // payload bytes (no extensions)
  uint32_t custom_mode = 0;                   // autopilot-specific mode (PX4: main mode in bits 16..23)
  uint8_t type = 0;                           // MAV_TYPE
  uint8_t autopilot = 0;                      // MAV_AUTOPILOT
  uint8_t base_mode = 0;                      // MAV_MODE_FLAG bits (128 = armed)
  uint8_t system_status = 0;                  // MAV_STATE
  uint8_t mavlink_version = 3;                // set by the protocol: 3 for MAVLink v1.0/v2
};

// ATTITUDE (#30): the vehicle's attitude, body FRD relative to local NED (ZYX Euler).
struct Attitude {
  static constexpr uint32_t kId = 30;
  static constexpr uint8_t kCrcExtra = 39;
  static constexpr uint8_t kLength = 28;
  uint32_t time_boot_ms = 0;                  // ms since the sender booted
  float roll = 0, pitch = 0, yaw = 0;         // rad (yaw 0 = north, positive clockwise from above)
  float rollspeed = 0, pitchspeed = 0, yawspeed = 0;  // rad/s, body FRD
};

// LOCAL_POSITION_NED (#32): the vehicle's position and velocity in local NED.
struct LocalPositionNed {
  static constexpr uint32_t kId = 32;
  static constexpr uint8_t kCrcExtra = 185;
  static constexpr uint8_t kLength = 28;
  uint32_t time_boot_ms = 0;                  // ms since the sender booted
  float x = 0, y = 0, z = 0;                  // m, local NED (north, east, down)
  float vx = 0, vy = 0, vz = 0;               // m/s, local NED
};

// COMMAND_LONG (#76): a command with up to seven float parameters.
struct CommandLong {
  static constexpr uint32_t kId = 76;
  static constexpr uint8_t kCrcExtra = 152;
  static constexpr uint8_t kLength = 33;
  std::array<float, 7> param{};               // param1..param7, meaning per command
  uint16_t command = 0;                       // MAV_CMD
  uint8_t target_system = 0;
  uint8_t target_component = 0;
  uint8_t confirmation = 0;                   // 0 first transmission, +1 per retry
};

// SET_POSITION_TARGET_LOCAL_NED (#84): an offboard setpoint.
struct SetPositionTargetLocalNed {
  static constexpr uint32_t kId = 84;
  static constexpr uint8_t kCrcExtra = 143;
  static constexpr uint8_t kLength = 53;
  uint32_t time_boot_ms = 0;                  // ms since the sender started
  float x = 0, y = 0, z = 0;                  // m, in coordinate_frame (LOCAL_NED: north, east, down)
  float vx = 0, vy = 0, vz = 0;               // m/s
  float afx = 0, afy = 0, afz = 0;            // m/s² (type_mask bit 512 clear: acceleration, not force)
  float yaw = 0;                              // rad, 0 = north, positive clockwise from above
  float yaw_rate = 0;                         // rad/s, positive clockwise from above
  uint16_t type_mask = 0;                     // POSITION_TARGET_TYPEMASK: set bits = ignore that field
  uint8_t target_system = 0;
  uint8_t target_component = 0;
  uint8_t coordinate_frame = kFrameLocalNed;  // MAV_FRAME
};

// ODOMETRY (#331, MAVLink 2 only): external odometry (VIO) for the flight controller's estimator.
struct Odometry {
  static constexpr uint32_t kId = 331;
  static constexpr uint8_t kCrcExtra = 91;
  static constexpr uint8_t kLength = 233;     // with the extensions reset_counter, estimator_type, quality
  uint64_t time_usec = 0;                     // µs
  float x = 0, y = 0, z = 0;                  // m, in frame_id
  std::array<float, 4> q{1, 0, 0, 0};         // w, x, y, z: rotation child (body) frame -> frame_id
  float vx = 0, vy = 0, vz = 0;               // m/s, in child_frame_id
  float rollspeed = 0, pitchspeed = 0, yawspeed = 0;  // rad/s, body
  std::array<float, 21> pose_covariance{};    // upper triangle of 6x6 (x y z roll pitch yaw); NaN first = unknown
  std::array<float, 21> velocity_covariance{};  // same for (vx vy vz rollspeed pitchspeed yawspeed)
  uint8_t frame_id = kFrameLocalNed;          // MAV_FRAME of the pose
  uint8_t child_frame_id = kFrameBodyFrd;     // MAV_FRAME of the velocity
  uint8_t reset_counter = 0;                  // extension: +1 on every estimate reset (jump)
  uint8_t estimator_type = 0;                 // extension: MAV_ESTIMATOR_TYPE
  int8_t quality = 0;                         // extension: %, 0 = unknown, -1 = failed
};

// Payload (full length, untruncated) of a message; and back from a full-length payload.
// unpack() reads exactly M::kLength bytes: give it a Frame's zero-filled payload.
void pack(const Heartbeat& m, uint8_t* out);
void pack(const Attitude& m, uint8_t* out);
void pack(const LocalPositionNed& m, uint8_t* out);
void pack(const CommandLong& m, uint8_t* out);
void pack(const SetPositionTargetLocalNed& m, uint8_t* out);
void pack(const Odometry& m, uint8_t* out);
void unpack(const uint8_t* in, Heartbeat* m);
void unpack(const uint8_t* in, Attitude* m);
void unpack(const uint8_t* in, LocalPositionNed* m);
void unpack(const uint8_t* in, CommandLong* m);
void unpack(const uint8_t* in, SetPositionTargetLocalNed* m);
void unpack(const uint8_t* in, Odometry* m);

// What the library knows about a message id: name, CRC_EXTRA and payload length.
struct MessageInfo {
  uint32_t id;
  const char* name;
  uint8_t crc_extra;
  uint8_t length;  // full payload length, extensions included
};
// nullptr for an id this library does not know (its CRC_EXTRA is unknown, so it cannot be checked).
const MessageInfo* message_info(uint32_t msgid);

// --- Frames ---

// Who sends: the header's system and component ids.
struct Endpoint {
  uint8_t sysid = 1;
  uint8_t compid = kCompIdOnboardComputer;
};

// A complete frame from a payload: truncates trailing zeros (keeps at least one byte), writes the
// header with seq, and the CRC with crc_extra. payload_length <= 255.
std::vector<uint8_t> frame_bytes(uint32_t msgid, uint8_t crc_extra, const uint8_t* payload,
                                 std::size_t payload_length, uint8_t seq, const Endpoint& from);

// Encodes messages into frames with a running sequence number (one per sending link).
class Encoder {
 public:
  explicit Encoder(Endpoint from) : from_(from) {}
  template <class M>
  std::vector<uint8_t> encode(const M& m) {
    std::array<uint8_t, kMaxPayload> payload{};
    pack(m, payload.data());
    return frame_bytes(M::kId, M::kCrcExtra, payload.data(), M::kLength, seq_++, from_);
  }
  const Endpoint& endpoint() const { return from_; }
  uint8_t next_seq() const { return seq_; }

 private:
  Endpoint from_;
  uint8_t seq_ = 0;
};

// A checked, received frame. payload holds the message's full length: the bytes received, then
// zeros for the truncated tail.
struct Frame {
  uint8_t seq = 0;
  uint8_t sysid = 0;
  uint8_t compid = 0;
  uint32_t msgid = 0;
  uint8_t wire_length = 0;  // payload bytes on the wire (after truncation)
  std::array<uint8_t, kMaxPayload> payload{};
};

// Decodes a frame's payload as M; false when the frame is another message.
template <class M>
bool decode(const Frame& f, M* m) {
  if (f.msgid != M::kId) return false;
  unpack(f.payload.data(), m);
  return true;
}

// Why a frame was rejected.
enum class Reject {
  bad_crc,          // the CRC does not match (corrupted bytes, or a different definition)
  bad_length,       // payload longer than the message's full length
  unknown_id,       // message id unknown here: no CRC_EXTRA to check it with
  signed_frame,     // incompat flag 0x01: signing is not supported
  unknown_flags,    // an incompat flag this implementation does not understand
  truncated,        // a frame (or false start) running past the end of its datagram
};
const char* to_string(Reject r);  // "bad_crc", "bad_length", ... (usable as a counter name)

struct Rejection {
  Reject reason;
  uint32_t msgid;
  uint8_t sysid, compid;
  std::string detail;  // e.g. "bad CRC on msgid 0 (HEARTBEAT): got 0x1234, expected 0xABCD"
};

// Splits a byte stream into frames. Bytes may arrive in any chunks; garbage before a start byte
// is skipped (counted in skipped_bytes()). After a bad CRC or unknown incompat flags the parser
// drops only the start byte and searches again (the frame may have been a false start inside
// garbage); a frame whose CRC holds but whose payload is too long is skipped whole. A frame it
// cannot verify (an unknown id: no CRC_EXTRA; a signed frame) waits for the byte after it and is
// skipped whole only when that is another start byte, as after a real frame; otherwise only its
// start byte goes, since a false start claiming up to 280 bytes would swallow the good frames
// behind it. (So an unverifiable frame that ends the stream stays buffered until more bytes come.)
// Over UDP a datagram holds whole frames: end_of_datagram() then settles what is left without
// waiting for bytes that will never continue it.
class Parser {
 public:
  using FrameHandler = std::function<void(const Frame&)>;
  using RejectHandler = std::function<void(const Rejection&)>;

  // Feeds n bytes; calls on_frame for each good frame and on_reject for each rejected one, in
  // stream order. Incomplete frames wait for more bytes.
  void feed(const uint8_t* data, std::size_t n, const FrameHandler& on_frame, const RejectHandler& on_reject);
  // The datagram just fed has ended: what is buffered is parsed as if nothing followed it (an
  // unverifiable frame that fills the rest is skipped whole), and a frame that runs past the end
  // is rejected (truncated) by its start byte, the search going on behind it, until nothing is
  // buffered. A false start in one datagram so no longer holds back the frames after it, nor the
  // next datagrams (review, session 32: 13 s of an FC's heartbeats held back by 10 bytes).
  void end_of_datagram(const FrameHandler& on_frame, const RejectHandler& on_reject);

  uint64_t frames() const { return frames_; }
  uint64_t rejected() const { return rejected_; }
  uint64_t skipped_bytes() const { return skipped_; }
  std::size_t buffered() const { return buffer_.size() - start_; }

 private:
  // Tries to take one frame at start_; false when more bytes are needed.
  bool take_one(const FrameHandler& on_frame, const RejectHandler& on_reject);
  void reject(Reject r, uint32_t msgid, std::string detail, std::size_t skip, const RejectHandler& on_reject);
  // Bytes to skip for an unverifiable frame of `total` bytes at start_ (total + 1 held): total or 1.
  std::size_t unverified_skip(std::size_t total) const;

  std::vector<uint8_t> buffer_;
  std::size_t start_ = 0;  // first unread byte of buffer_
  bool at_end_ = false;    // inside end_of_datagram: no byte follows the buffer
  uint64_t frames_ = 0, rejected_ = 0, skipped_ = 0;
};

}  // namespace fact::mavlink
