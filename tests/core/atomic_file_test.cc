#include "core/atomic_file.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include "core/error.h"

namespace flowplan {
namespace {

namespace fs = std::filesystem;
using ::testing::HasSubstr;
using ::testing::ThrowsMessage;

TEST(AtomicFileTest, UncommittedWriteLeavesOldFileAndNoTemporary) {
  const fs::path dir = fs::path(::testing::TempDir()) / "atomic_uncommitted";
  fs::create_directories(dir);
  const std::string path = (dir / "data.txt").string();
  WriteFileAtomically(path, "good");
  {
    AtomicFile file(path);
    std::ofstream(file.temp_path()) << "half-writ";
    // No Commit(): as if an error was thrown mid-write.
  }
  EXPECT_EQ(ReadFile(path), "good");
  int entries = 0;
  for (const auto& e : fs::directory_iterator(dir)) entries += e.is_regular_file();
  EXPECT_EQ(entries, 1);
}

TEST(AtomicFileTest, CommitReplaces) {
  const std::string path = ::testing::TempDir() + "/atomic_commit.txt";
  WriteFileAtomically(path, "one");
  WriteFileAtomically(path, "two");
  EXPECT_EQ(ReadFile(path), "two");
}

TEST(AtomicFileTest, MissingFolderIsAClearError) {
  EXPECT_THAT([] { AtomicFile file("/nonexistent_folder/x.h5"); },
              ThrowsMessage<Error>(AllOf(HasSubstr("/nonexistent_folder/x.h5"), HasSubstr("does not exist"))));
}

}  // namespace
}  // namespace flowplan
