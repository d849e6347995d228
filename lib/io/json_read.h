// The checked JSON reading shared by fact_io's formats (lib/io/json_io.cpp: fact-rounds-v1,
// fact-result-v1, fact-truth-v1; lib/io/world_io.cpp: fact-world-v1). Every accessor carries the
// JSON path of the value it reads, so every error (fact::FormatError) names the path and the value.
// Internal to fact_io: not installed, not in include/.
#pragma once

#include "fact/json_io.h"

#include <Eigen/Core>
#include <nlohmann/json.hpp>

#include <cstddef>
#include <initializer_list>
#include <string>

namespace fact::json_read {

using Json = nlohmann::ordered_json;

bool is_identifier(const std::string& key);
// `path.key` for identifier keys, `path["key"]` for any other key (drone ids, odd names).
std::string member(const std::string& path, const std::string& key);
// The entry for `key` in an object keyed by drone id: always `path["key"]`, whatever the key.
std::string drone_member(const std::string& path, const std::string& key);
std::string element(const std::string& path, std::size_t index);
// A value as it would appear in the text, shortened for a one-line message.
std::string describe(const Json& value);
std::string describe(double x);
// Throws FormatError("<path or 'top level'>: <what>").
[[noreturn]] void fail(const std::string& path, const std::string& what);

// Parses a document; a key repeated within one object and a syntax error are FormatErrors naming
// the path where they happened.
Json parse_text(const std::string& text);

void expect_object(const Json& value, const std::string& path);
void expect_array(const Json& value, const std::string& path);
std::string key_list(std::initializer_list<const char*> keys);
// Nested objects are closed: a key the format does not define is an error.
void allow_only(const Json& object, const std::string& path, std::initializer_list<const char*> keys);
const Json& need(const Json& object, const std::string& path, const char* key);
double number(const Json& value, const std::string& path);          // finite
double number_or_null(const Json& value, const std::string& path);  // null → NaN
int integer(const Json& value, const std::string& path);            // fits an int
bool boolean(const Json& value, const std::string& path);
std::string text(const Json& value, const std::string& path);
Eigen::Vector3d vec3(const Json& value, const std::string& path);          // 3 finite numbers
Eigen::Vector3d vec3_or_null(const Json& value, const std::string& path);  // each may be null (NaN)

}  // namespace fact::json_read
