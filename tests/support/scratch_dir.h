// A fresh directory for the running test, unique to this process and test, so
// that tests run in parallel (ctest -j) or by two checkouts at once never share
// a file.
#pragma once

#include <gtest/gtest.h>

#include "tests/support/scratch_dir.h"
#include <unistd.h>

#include <filesystem>
#include <set>
#include <string>

namespace flowplan::testing {

// <TempDir>/flowplan_<pid>_<suite>_<test>, created on first use; every call in
// one test returns the same directory. Parameterised names have their '/'
// replaced so the result is one directory. A directory of that name left by an
// earlier process with the same pid (pids are reused) is emptied on first use.
inline std::filesystem::path ScratchDir() {
  const ::testing::TestInfo* info = ::testing::UnitTest::GetInstance()->current_test_info();
  std::string name = "flowplan_" + std::to_string(::getpid()) + "_" + info->test_suite_name() + "_" + info->name();
  for (char& c : name) {
    if (c == '/') c = '_';
  }
  const std::filesystem::path dir = std::filesystem::path(::testing::TempDir()) / name;
  static std::set<std::string> made;  // this process's directories
  if (made.insert(name).second) std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  return dir;
}

}  // namespace flowplan::testing
