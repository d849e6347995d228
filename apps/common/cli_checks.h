// Checks on command-line values that CLI11 itself lets through. Header-only, so that the offline
// tools, which do not link LCM (fact_app_common), use them too.
#pragma once

#include <CLI/CLI.hpp>

#include <charconv>
#include <cstdint>
#include <string>

namespace fact::app {

// For flags read into std::uint64_t (seeds). CLI11 itself turned "-1" into 2^64 − 1 and saturated
// larger numbers, so two different seeds ran as the same one (review, session 32).
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

// Every option of `app` that takes a value refuses an empty value and an integer written with a
// leading zero. CLI11 assigns a default-constructed value for an empty string ("--drone-id ''" ran
// the app as drone 0, "--rounds ''" used every round, "--noise-floor ''" set 0): a script whose
// variable was unset would run on a number nobody gave. And it reads integers in C's bases:
// "--drone-id 010" ran as drone 8 and "--port 010" listened on port 8 (review, session 33). No
// flag gives "" a meaning; a file literally named 010 is still reachable as ./010. Call after the
// options are added, before parsing; flags (no value) and --help are left alone.
inline void refuse_unclear_values(CLI::App& app) {
  const CLI::Validator clear(
      [](std::string& s) {
        if (s.empty()) return std::string("expected a value, got an empty string");
        const size_t digits = s.find_first_not_of("+-");
        const bool leading_zero = digits != std::string::npos && s.size() > digits + 1 && s[digits] == '0' &&
                                  s.find_first_not_of("0123456789", digits) == std::string::npos;
        if (leading_zero) return "'" + s + "' has a leading zero, which would read as octal: write it without (./" + s +
                                 " for a file)";
        return std::string();
      },
      "");
  for (CLI::Option* option : app.get_options())
    if (option->get_type_size() != 0) option->check(clear);
}

}  // namespace fact::app
