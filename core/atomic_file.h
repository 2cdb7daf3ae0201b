#pragma once

#include <string>

namespace flowplan {

/// Writes a file under a temporary name in the same folder and renames it into
/// place on Commit(), so that a crash or an error never leaves a half-written
/// file where a good one was. Without Commit() the temporary file is removed.
///
///   AtomicFile file("run/ckpt.pt");
///   archive.save_to(file.temp_path());
///   file.Commit();
class AtomicFile {
 public:
  /// Creates the (empty) temporary file.
  /// @throws flowplan::Error if the destination folder does not exist or the file cannot be created there.
  explicit AtomicFile(std::string path);
  ~AtomicFile();
  AtomicFile(const AtomicFile&) = delete;
  AtomicFile& operator=(const AtomicFile&) = delete;

  const std::string& path() const { return path_; }
  const std::string& temp_path() const { return temp_path_; }

  /// Renames the temporary file onto path().
  /// @throws flowplan::Error if the rename fails.
  void Commit();

 private:
  std::string path_;
  std::string temp_path_;
  bool committed_ = false;
};

/// Writes `text` to `path` atomically.
void WriteFileAtomically(const std::string& path, const std::string& text);

/// Reads a whole file. @throws flowplan::Error if it cannot be opened.
std::string ReadFile(const std::string& path);

/// Creates a folder and its parents. @throws flowplan::Error naming the folder on failure.
void MakeDirectories(const std::string& path);

}  // namespace flowplan
