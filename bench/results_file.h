// The benchmarks' results files, written whole or not at all (fact::write_file_atomically): a run
// that fails or is interrupted leaves the previous figures in place, where the files used to be
// truncated when a run began and left half-written (review, session 34).
#pragma once

#include <filesystem>
#include <stdexcept>
#include <string>

#include "fact/file_write.h"

namespace fact::bench {

// Writes `text` to `path` as a whole, making path's folder first; throws std::runtime_error with
// the reason (naming the path) when it cannot.
inline void write_results_file(const std::string& path, const std::string& text) {
  const std::filesystem::path parent = std::filesystem::path(path).parent_path();
  std::error_code ec;
  if (!parent.empty()) std::filesystem::create_directories(parent, ec);
  if (const std::string e = fact::write_file_atomically(path, text); !e.empty()) throw std::runtime_error(e);
}

}  // namespace fact::bench
