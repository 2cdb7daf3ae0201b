#include "core/atomic_file.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include "core/error.h"
#include "tests/support/scratch_dir.h"

namespace flowplan {
namespace {

namespace fs = std::filesystem;
using ::testing::HasSubstr;
using ::testing::ThrowsMessage;

TEST(AtomicFileTest, UncommittedWriteLeavesOldFileAndNoTemporary) {
  const fs::path dir = flowplan::testing::ScratchDir();
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
  const std::string path = (flowplan::testing::ScratchDir() / "atomic_commit.txt").string();
  WriteFileAtomically(path, "one");
  WriteFileAtomically(path, "two");
  EXPECT_EQ(ReadFile(path), "two");
}

TEST(AtomicFileTest, MissingFolderIsAClearError) {
  EXPECT_THAT([] { AtomicFile file("/nonexistent_folder/x.h5"); },
              ThrowsMessage<Error>(AllOf(HasSubstr("/nonexistent_folder/x.h5"), HasSubstr("does not exist"))));
}

TEST(AtomicFileTest, FolderThatRefusesNewFilesIsAClearErrorBeforeAnyWrite) {
  // /proc takes no new files, even from root, whom access(W_OK) always allows.
  EXPECT_THAT([] { AtomicFile file("/proc/flowplan_atomic_file_test.h5"); },
              ThrowsMessage<Error>(AllOf(HasSubstr("/proc/flowplan_atomic_file_test.h5: cannot write"))));
}

}  // namespace
}  // namespace flowplan
