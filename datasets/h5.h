#pragma once

// A thin RAII layer over the HDF5 C API: only what flowplan's files need.
// Every failure throws flowplan::Error naming the file and the object.

#include <hdf5.h>

#include <cstdint>
#include <string>
#include <vector>

namespace flowplan::datasets::h5 {

/// Owns one hid_t and closes it with the right H5*close function.
class Handle {
 public:
  using Closer = herr_t (*)(hid_t);
  Handle() = default;
  Handle(hid_t id, Closer closer) : id_(id), closer_(closer) {}
  ~Handle() { Reset(); }
  Handle(Handle&& other) noexcept : id_(other.id_), closer_(other.closer_) { other.id_ = -1; }
  Handle& operator=(Handle&& other) noexcept;
  Handle(const Handle&) = delete;
  Handle& operator=(const Handle&) = delete;

  hid_t get() const { return id_; }
  bool valid() const { return id_ >= 0; }
  void Reset();
  /// Gives up ownership without closing.
  void Release() { id_ = -1; }

 private:
  hid_t id_ = -1;
  Closer closer_ = nullptr;
};

/// Element types stored in flowplan files.
enum class Type { kFloat32, kFloat64, kInt32, kInt64 };

/// An open HDF5 file. Paths of objects are absolute ("/states", "/eval/test_start").
class File {
 public:
  /// Creates (truncating) a file for writing.
  static File Create(const std::string& path);
  /// Opens a file read-only. @throws flowplan::Error if it is missing or not HDF5.
  static File OpenReadOnly(const std::string& path);

  const std::string& path() const { return path_; }

  bool Exists(const std::string& object) const;
  void CreateGroup(const std::string& group);
  /// Names of the members of a group, in name order.
  std::vector<std::string> ListGroup(const std::string& group) const;

  /// Writes a contiguous array of `shape` (row-major). `data` holds prod(shape) elements.
  void WriteFloat32(const std::string& name, const std::vector<int64_t>& shape, const float* data);
  void WriteFloat64(const std::string& name, const std::vector<int64_t>& shape, const double* data);
  void WriteInt32(const std::string& name, const std::vector<int64_t>& shape, const int32_t* data);

  /// Shape of a dataset. @throws if it is missing.
  std::vector<int64_t> Shape(const std::string& name) const;
  /// Reads a whole dataset converted to the requested element type; `shape` receives its shape.
  std::vector<float> ReadFloat32(const std::string& name, std::vector<int64_t>* shape) const;
  std::vector<double> ReadFloat64(const std::string& name, std::vector<int64_t>* shape) const;
  std::vector<int32_t> ReadInt32(const std::string& name, std::vector<int64_t>* shape) const;
  /// Reads the rows `rows` (ascending, along the first axis) of a dataset;
  /// `shape` receives its whole shape. @throws for rows out of range or not ascending.
  std::vector<float> ReadFloat32Rows(const std::string& name, const std::vector<int64_t>& rows,
                                     std::vector<int64_t>* shape) const;

  /// Attributes on an object ("/" for the file itself).
  void SetAttribute(const std::string& object, const std::string& name, const std::string& value);
  void SetAttribute(const std::string& object, const std::string& name, int64_t value);
  void SetAttribute(const std::string& object, const std::string& name, double value);
  bool HasAttribute(const std::string& object, const std::string& name) const;
  std::string GetStringAttribute(const std::string& object, const std::string& name) const;
  int64_t GetIntAttribute(const std::string& object, const std::string& name) const;
  double GetDoubleAttribute(const std::string& object, const std::string& name) const;

  /// Flushes and closes; later calls fail. Errors are reported here, not in the destructor.
  void Close();

 private:
  File(Handle file, std::string path) : file_(std::move(file)), path_(std::move(path)) {}
  void Write(const std::string& name, const std::vector<int64_t>& shape, hid_t mem_type,
             hid_t file_type, const void* data);
  void Read(const std::string& name, hid_t mem_type, void* data) const;
  Handle OpenAttributeTarget(const std::string& object) const;
  /// Opens an attribute after checking that it holds one value of class `expected`.
  Handle OpenScalarAttribute(const std::string& object, const std::string& name, H5T_class_t expected,
                             const char* what) const;
  [[noreturn]] void Fail(const std::string& object, const std::string& what) const;

  Handle file_;
  std::string path_;
};

/// Turns off HDF5's own error printing (flowplan reports errors itself). Idempotent.
void SilenceLibraryErrors();

}  // namespace flowplan::datasets::h5
