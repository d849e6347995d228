// Reading the benchmarks' own CSV files back (fact-bench-e2e's runs, fact-bench-sdp-sweep's
// baselines): a line's comma-separated fields, and a field as a number with the column named
// when it is not one.
#pragma once

#include <cmath>
#include <cstddef>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

namespace fact::bench {

// The fields of one line (no quoting: the benchmarks write none); a trailing comma ends in an
// empty field.
inline std::vector<std::string> split_csv_line(const std::string& line) {
  std::vector<std::string> fields;
  std::stringstream ss(line);
  for (std::string f; std::getline(ss, f, ',');) fields.push_back(f);
  if (!line.empty() && line.back() == ',') fields.emplace_back();
  return fields;
}

// A whole field as a number ("nan" and "inf" are numbers here); throws std::invalid_argument
// naming the column and the value.
inline double parse_number(const std::string& field, const std::string& column) {
  std::size_t used = 0;
  double v = NAN;
  try {
    v = std::stod(field, &used);
  } catch (const std::exception&) {
    used = 0;
  }
  if (used == 0 || used != field.size())
    throw std::invalid_argument("column " + column + ": '" + field + "' is not a number");
  return v;
}

}  // namespace fact::bench
