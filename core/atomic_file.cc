#include "core/atomic_file.h"

#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "core/error.h"

namespace flowplan {
namespace fs = std::filesystem;

AtomicFile::AtomicFile(std::string path) : path_(std::move(path)) {
  const fs::path target(path_);
  const fs::path folder = target.has_parent_path() ? target.parent_path() : fs::path(".");
  std::error_code ec;
  if (!fs::is_directory(folder, ec)) {
    throw Error(path_ + ": cannot write: folder " + folder.string() + " does not exist");
  }
  if (fs::is_directory(target, ec)) throw Error(path_ + ": cannot write: it is a folder");
  if (::access(folder.c_str(), W_OK) != 0) {
    throw Error(path_ + ": cannot write: folder " + folder.string() + " is not writable");
  }
  temp_path_ = (folder / ("." + target.filename().string() + ".tmp-" + std::to_string(::getpid())))
                   .string();
  // Creating the temporary file now catches what access() cannot see (a
  // read-only file system, a pseudo file system, root's W_OK on any folder)
  // before any work is done; writers truncate it.
  std::FILE* probe = std::fopen(temp_path_.c_str(), "wb");
  if (probe == nullptr) throw Error(path_ + ": cannot write: " + std::strerror(errno));
  std::fclose(probe);
}

AtomicFile::~AtomicFile() {
  if (!committed_) std::remove(temp_path_.c_str());
}

void AtomicFile::Commit() {
  if (std::rename(temp_path_.c_str(), path_.c_str()) != 0) {
    throw Error(path_ + ": cannot write: " + std::strerror(errno));
  }
  committed_ = true;
}

void WriteFileAtomically(const std::string& path, const std::string& text) {
  AtomicFile file(path);
  {
    std::ofstream out(file.temp_path(), std::ios::binary);
    out << text;
    out.flush();
    if (!out) throw Error(path + ": cannot write");
  }
  file.Commit();
}

std::string ReadFile(const std::string& path) {
  if (fs::is_directory(path)) throw Error(path + ": is a folder, not a file");
  std::ifstream in(path, std::ios::binary);
  if (!in) throw Error(path + ": cannot open");
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

void MakeDirectories(const std::string& path) {
  std::error_code ec;
  fs::create_directories(path, ec);
  if (ec || !fs::is_directory(path)) {
    throw Error(path + ": cannot create folder: " + (ec ? ec.message() : "not a folder"));
  }
}

}  // namespace flowplan
