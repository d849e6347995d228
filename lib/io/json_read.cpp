#include "io/json_read.h"

#include <algorithm>
#include <cctype>
#include <climits>
#include <cmath>
#include <cstdint>
#include <limits>
#include <set>
#include <vector>

namespace fact::json_read {

// ---------------------------------------------------------------------------------------------
// Paths and messages

bool is_identifier(const std::string& key) {
  if (key.empty() || std::isdigit(static_cast<unsigned char>(key[0]))) return false;
  return std::all_of(key.begin(), key.end(), [](char c) {
    return std::isalnum(static_cast<unsigned char>(c)) || c == '_';
  });
}

// `path.key` for identifier keys, `path["key"]` for any other key (drone ids, odd names).
std::string member(const std::string& path, const std::string& key) {
  if (!is_identifier(key)) return path + "[" + Json(key).dump() + "]";
  return path.empty() ? key : path + "." + key;
}

// The entry for `key` in an object keyed by drone id: always `path["key"]`, whatever the key.
std::string drone_member(const std::string& path, const std::string& key) {
  return path + "[" + Json(key).dump() + "]";
}

std::string element(const std::string& path, std::size_t index) {
  return path + "[" + std::to_string(index) + "]";
}

// A value as it would appear in the text, shortened for a one-line message.
std::string describe(const Json& value) {
  if (value.is_number_float()) {
    const double x = value.get<double>();
    if (std::isnan(x)) return "nan";
    if (std::isinf(x)) return x > 0 ? "inf" : "-inf";
  }
  std::string text = value.dump();
  const std::size_t limit = 60;
  if (text.size() <= limit) return text;
  std::size_t cut = limit;
  while (cut > 0 && (static_cast<unsigned char>(text[cut]) & 0xC0) == 0x80) --cut;  // UTF-8 boundary
  return text.substr(0, cut) + "...";
}

std::string describe(double x) { return describe(Json(x)); }

[[noreturn]] void fail(const std::string& path, const std::string& what) {
  throw FormatError((path.empty() ? std::string("top level") : path) + ": " + what);
}

// ---------------------------------------------------------------------------------------------
// Parsing the text

// Follows the parser through the document so that (1) a key repeated within one object, which
// nlohmann would silently resolve by keeping the last value, is an error naming its path, and
// (2) a syntax error or an out-of-range number (1e999) can be reported near the path where it
// happened; (3) a document nested deeper than kMaxDepth is refused (no format here nests more
// than 5 levels, and printing or destroying a 100 000-level value recursed until the stack
// overflowed: review, session 32).
namespace {
constexpr std::size_t kMaxDepth = 64;

class PathTracker {
 public:
  bool on_event(Json::parse_event_t event, const Json& parsed) {
    using Event = Json::parse_event_t;
    if ((event == Event::object_start || event == Event::array_start) && levels_.size() >= kMaxDepth)
      fail(path(), "nested deeper than " + std::to_string(kMaxDepth) + " levels");
    switch (event) {
      case Event::object_start: levels_.push_back({false, 0, "", {}}); break;
      case Event::array_start: levels_.push_back({true, 0, "", {}}); break;
      case Event::key: enter_key(parsed.get<std::string>()); break;
      case Event::value: finish_child(); break;
      case Event::object_end:
      case Event::array_end:
        levels_.pop_back();
        finish_child();
        break;
    }
    return true;
  }

  std::string path() const {
    std::string path;
    for (const Level& level : levels_)
      path = level.array ? element(path, level.next_index) : member(path, level.key);
    return path;
  }

 private:
  struct Level {
    bool array;
    std::size_t next_index;  // arrays: index of the element being read
    std::string key;         // objects: key of the member being read
    std::set<std::string> keys;
  };

  void enter_key(const std::string& key) {
    Level& level = levels_.back();
    level.key = key;
    if (!level.keys.insert(key).second) fail(path(), "duplicate key " + Json(key).dump());
  }

  void finish_child() {
    if (!levels_.empty() && levels_.back().array) ++levels_.back().next_index;
  }

  std::vector<Level> levels_;
};

}  // namespace

Json parse_text(const std::string& text) {
  PathTracker tracker;
  Json::parser_callback_t callback = [&tracker](int, Json::parse_event_t event, Json& parsed) {
    return tracker.on_event(event, parsed);
  };
  try {
    return Json::parse(text, callback);
  } catch (const Json::exception& e) {
    std::string message = e.what();  // "[json.exception.parse_error.101] parse error at …"
    const std::size_t tag_end = message.find("] ");
    if (tag_end != std::string::npos) message = message.substr(tag_end + 2);
    const std::string near = tracker.path();
    throw FormatError("invalid JSON" + (near.empty() ? "" : " near " + near) + ": " + message);
  }
}

// ---------------------------------------------------------------------------------------------
// Checked accessors. `path` is the JSON path of the value being read.

void expect_object(const Json& value, const std::string& path) {
  if (!value.is_object()) fail(path, "expected an object, got " + describe(value));
}

void expect_array(const Json& value, const std::string& path) {
  if (!value.is_array()) fail(path, "expected an array, got " + describe(value));
}

std::string key_list(std::initializer_list<const char*> keys) {
  std::string list;
  for (const char* key : keys) list += (list.empty() ? "" : ", ") + Json(key).dump();
  return list;
}

// Nested objects are closed: a key the format does not define is an error (most likely a typo
// that would otherwise drop data silently).
void allow_only(const Json& object, const std::string& path, std::initializer_list<const char*> keys) {
  for (const auto& item : object.items()) {
    const bool known = std::any_of(keys.begin(), keys.end(),
                                   [&](const char* key) { return item.key() == key; });
    if (!known) fail(member(path, item.key()), "unknown key (allowed: " + key_list(keys) + ")");
  }
}

const Json& need(const Json& object, const std::string& path, const char* key) {
  const auto it = object.find(key);
  if (it == object.end()) fail(member(path, key), "required key is missing");
  return *it;
}

double number(const Json& value, const std::string& path) {
  if (!value.is_number()) fail(path, "expected a number, got " + describe(value));
  const double x = value.get<double>();
  if (!std::isfinite(x)) fail(path, "expected a finite number, got " + describe(value));
  return x;
}

// A number, or null for a value that does not exist (read back as NaN).
double number_or_null(const Json& value, const std::string& path) {
  if (value.is_null()) return std::numeric_limits<double>::quiet_NaN();
  if (!value.is_number()) fail(path, "expected a number or null, got " + describe(value));
  return number(value, path);
}

int integer(const Json& value, const std::string& path) {
  if (!value.is_number_integer()) fail(path, "expected an integer, got " + describe(value));
  const bool fits = value.is_number_unsigned()
                        ? value.get<std::uint64_t>() <= static_cast<std::uint64_t>(INT_MAX)
                        : value.get<std::int64_t>() >= INT_MIN && value.get<std::int64_t>() <= INT_MAX;
  if (!fits) fail(path, "integer out of range, got " + describe(value));
  return value.get<int>();
}

bool boolean(const Json& value, const std::string& path) {
  if (!value.is_boolean()) fail(path, "expected true or false, got " + describe(value));
  return value.get<bool>();
}

std::string text(const Json& value, const std::string& path) {
  if (!value.is_string()) fail(path, "expected a string, got " + describe(value));
  return value.get<std::string>();
}

Eigen::Vector3d vec3(const Json& value, const std::string& path) {
  if (!value.is_array()) fail(path, "expected 3 numbers, got " + describe(value));
  if (value.size() != 3)
    fail(path, "expected 3 numbers, got " + std::to_string(value.size()) + ": " + describe(value));
  return {number(value[0], element(path, 0)), number(value[1], element(path, 1)),
          number(value[2], element(path, 2))};
}

// Like vec3, but each component may be null (NaN).
Eigen::Vector3d vec3_or_null(const Json& value, const std::string& path) {
  if (!value.is_array() || value.size() != 3)
    fail(path, "expected 3 numbers or nulls, got " + describe(value));
  return {number_or_null(value[0], element(path, 0)), number_or_null(value[1], element(path, 1)),
          number_or_null(value[2], element(path, 2))};
}

}  // namespace fact::json_read
