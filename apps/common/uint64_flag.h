// A CLI11 check for flags read into std::uint64_t (seeds), header-only so that the offline tools,
// which do not link LCM, use it too. CLI11 itself turned "-1" into 2^64 − 1 and saturated larger
// numbers, so two different seeds ran as the same one (review, session 32).
#pragma once

#include <CLI/CLI.hpp>

#include <charconv>
#include <cstdint>
#include <string>

namespace fact::app {

inline CLI::Validator uint64_text() {
  return CLI::Validator(
      [](std::string& s) {
        std::uint64_t v = 0;
        const auto [end, error] = std::from_chars(s.data(), s.data() + s.size(), v);
        if (!s.empty() && error == std::errc() && end == s.data() + s.size()) return std::string();
        return "expected an integer in [0, 18446744073709551615], got '" + s + "'";
      },
      "UINT64");
}

}  // namespace fact::app
