// Checks on command-line values that CLI11 itself lets through. Header-only, so that the offline
// tools, which do not link LCM (fact_app_common), use them too.
#pragma once

#include <CLI/CLI.hpp>

#include <charconv>
#include <cstdint>
#include <string>

namespace fact::app {

// "" when `s` is a plain decimal integer (an optional sign, then digits, the first not 0 unless it
// is the only one), else why not. CLI11 converts integers with strtoll in base 0 after skipping
// white space: "010" was octal 8 (--drone-id 010 ran as drone 8, --port 010 listened on 8),
// " 010" too, and "0x10" 16 (review, session 33).
inline std::string decimal_integer_error(const std::string& s) {
  if (s.empty()) return "expected a value, got an empty string";  // (as refuse_empty_values says it)
  const size_t digits = s[0] == '+' || s[0] == '-' ? 1 : 0;
  if (digits == s.size() || s.find_first_not_of("0123456789", digits) != std::string::npos)
    return "expected a decimal integer, got '" + s + "'";
  if (s[digits] == '0' && s.size() > digits + 1)
    return "'" + s + "' has a leading zero, which would read as octal: write it without";
  return "";
}

// For every flag read into an integer: a plain decimal integer (decimal_integer_error).
inline CLI::Validator decimal_integer() {
  return CLI::Validator([](std::string& s) { return decimal_integer_error(s); }, "");
}

// For flags read into std::uint64_t (seeds): a decimal integer in [0, 2^64 − 1]. CLI11 itself
// turned "-1" into 2^64 − 1 and saturated larger numbers, so two different seeds ran as the same
// one (review, session 32), and read "010" as octal.
inline CLI::Validator uint64_text() {
  return CLI::Validator(
      [](std::string& s) {
        if (std::string e = decimal_integer_error(s); !e.empty()) return e;
        std::uint64_t v = 0;
        const auto [end, error] = std::from_chars(s.data(), s.data() + s.size(), v);
        if (error == std::errc() && end == s.data() + s.size()) return std::string();
        return "expected an integer in [0, 18446744073709551615], got '" + s + "'";
      },
      "UINT64");
}

// Every option of `app` that takes a value refuses an empty one. CLI11 assigns a
// default-constructed value for an empty string ("--drone-id ''" ran the app as drone 0,
// "--rounds ''" used every round, "--noise-floor ''" set 0): a script whose variable was unset
// would run on a number nobody gave. No flag gives "" a meaning. Call after the options are added,
// before parsing; flags (no value) and --help are left alone.
inline void refuse_empty_values(CLI::App& app) {
  const CLI::Validator non_empty(
      [](std::string& s) { return s.empty() ? std::string("expected a value, got an empty string") : std::string(); },
      "");
  for (CLI::Option* option : app.get_options())
    if (option->get_type_size() != 0) option->check(non_empty);
}

// refuse_empty_values, then CLI11's parse with the apps' exit codes: -1 when the program should go
// on, else the code to exit with, 0 after --help and 2 after a bad flag (CLI11's message on
// stderr). CLI11_PARSE would exit with CLI11's own codes instead (105 for a value a check refused,
// 109 for an unknown flag), which scripts that test for 2 took for success of another kind.
inline int parse_command_line(CLI::App& cli, int argc, char** argv) {
  try {
    refuse_empty_values(cli);
    cli.parse(argc, argv);
    return -1;
  } catch (const CLI::ParseError& e) {
    return cli.exit(e) == 0 ? 0 : 2;
  }
}

}  // namespace fact::app
