// A test fixture with a fresh temporary directory per test (mkdtemp: no two tests, processes or
// concurrent ctest runs share one), removed with everything in it afterwards.
#pragma once

#include <gtest/gtest.h>
#include <stdlib.h>

#include <filesystem>
#include <string>
#include <utility>

namespace fact::test {

// dir_ is <tmp>/<prefix>-XXXXXX. A fixture that overrides SetUp or TearDown calls these.
class TempDirTest : public ::testing::Test {
 protected:
  explicit TempDirTest(std::string prefix) : prefix_(std::move(prefix)) {}
  void SetUp() override {
    std::string pattern = (std::filesystem::temp_directory_path() / (prefix_ + "-XXXXXX")).string();
    ASSERT_NE(mkdtemp(pattern.data()), nullptr);
    dir_ = pattern;
  }
  void TearDown() override {
    if (!dir_.empty()) std::filesystem::remove_all(dir_);
  }
  std::filesystem::path dir_;

 private:
  std::string prefix_;
};

}  // namespace fact::test
