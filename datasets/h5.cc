#include "datasets/h5.h"

#include <limits>
#include <mutex>
#include <numeric>

#include "core/error.h"

namespace flowplan::datasets::h5 {

Handle& Handle::operator=(Handle&& other) noexcept {
  if (this != &other) {
    Reset();
    id_ = other.id_;
    closer_ = other.closer_;
    other.id_ = -1;
  }
  return *this;
}

void Handle::Reset() {
  if (id_ >= 0 && closer_ != nullptr) closer_(id_);
  id_ = -1;
}

void SilenceLibraryErrors() {
  static std::once_flag once;
  std::call_once(once, [] { H5Eset_auto2(H5E_DEFAULT, nullptr, nullptr); });
}

namespace {

int64_t Product(const std::vector<int64_t>& shape) {
  return std::accumulate(shape.begin(), shape.end(), int64_t{1}, std::multiplies<int64_t>());
}

// Property lists that leave out modification times, so that the same content
// gives the same bytes.
Handle NoTimesDatasetProperties() {
  Handle plist(H5Pcreate(H5P_DATASET_CREATE), H5Pclose);
  H5Pset_obj_track_times(plist.get(), false);
  return plist;
}

Handle NoTimesGroupProperties() {
  Handle plist(H5Pcreate(H5P_GROUP_CREATE), H5Pclose);
  H5Pset_obj_track_times(plist.get(), false);
  return plist;
}

}  // namespace

void File::Fail(const std::string& object, const std::string& what) const {
  throw Error(path_ + (object.empty() ? "" : ": " + object) + ": " + what);
}

File File::Create(const std::string& path) {
  SilenceLibraryErrors();
  Handle fcpl(H5Pcreate(H5P_FILE_CREATE), H5Pclose);
  H5Pset_obj_track_times(fcpl.get(), false);
  Handle id(H5Fcreate(path.c_str(), H5F_ACC_TRUNC, fcpl.get(), H5P_DEFAULT), H5Fclose);
  if (!id.valid()) throw Error(path + ": cannot create HDF5 file");
  return File(std::move(id), path);
}

File File::OpenReadOnly(const std::string& path) {
  SilenceLibraryErrors();
  if (H5Fis_hdf5(path.c_str()) <= 0) {
    FILE* probe = std::fopen(path.c_str(), "rb");
    if (probe == nullptr) throw Error(path + ": cannot open: no such file or not readable");
    std::fclose(probe);
    throw Error(path + ": not an HDF5 file (truncated or foreign)");
  }
  Handle id(H5Fopen(path.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT), H5Fclose);
  if (!id.valid()) throw Error(path + ": cannot open HDF5 file (truncated or corrupt)");
  return File(std::move(id), path);
}

bool File::Exists(const std::string& object) const {
  if (object == "/") return true;
  // Check each prefix: H5Lexists fails on a missing intermediate group.
  size_t pos = 0;
  while ((pos = object.find('/', pos + 1)) != std::string::npos) {
    if (H5Lexists(file_.get(), object.substr(0, pos).c_str(), H5P_DEFAULT) <= 0) return false;
  }
  return H5Lexists(file_.get(), object.c_str(), H5P_DEFAULT) > 0;
}

void File::CreateGroup(const std::string& group) {
  Handle gcpl = NoTimesGroupProperties();
  Handle id(H5Gcreate2(file_.get(), group.c_str(), H5P_DEFAULT, gcpl.get(), H5P_DEFAULT), H5Gclose);
  if (!id.valid()) Fail(group, "cannot create group");
}

std::vector<std::string> File::ListGroup(const std::string& group) const {
  Handle id(H5Gopen2(file_.get(), group.c_str(), H5P_DEFAULT), H5Gclose);
  if (!id.valid()) Fail(group, "missing group");
  std::vector<std::string> names;
  auto collect = [](hid_t, const char* name, const H5L_info_t*, void* out) -> herr_t {
    static_cast<std::vector<std::string>*>(out)->push_back(name);
    return 0;
  };
  if (H5Literate(id.get(), H5_INDEX_NAME, H5_ITER_INC, nullptr, collect, &names) < 0) {
    Fail(group, "cannot list group");
  }
  return names;
}

void File::Write(const std::string& name, const std::vector<int64_t>& shape, hid_t mem_type,
                 hid_t file_type, const void* data) {
  std::vector<hsize_t> dims(shape.begin(), shape.end());
  Handle space(H5Screate_simple(static_cast<int>(dims.size()), dims.data(), nullptr), H5Sclose);
  Handle dcpl = NoTimesDatasetProperties();
  Handle set(H5Dcreate2(file_.get(), name.c_str(), file_type, space.get(), H5P_DEFAULT, dcpl.get(),
                        H5P_DEFAULT),
             H5Dclose);
  if (!set.valid()) Fail(name, "cannot create dataset");
  if (Product(shape) > 0 &&
      H5Dwrite(set.get(), mem_type, H5S_ALL, H5S_ALL, H5P_DEFAULT, data) < 0) {
    Fail(name, "cannot write dataset (disk full?)");
  }
}

void File::WriteFloat32(const std::string& name, const std::vector<int64_t>& shape, const float* data) {
  Write(name, shape, H5T_NATIVE_FLOAT, H5T_IEEE_F32LE, data);
}
void File::WriteFloat64(const std::string& name, const std::vector<int64_t>& shape, const double* data) {
  Write(name, shape, H5T_NATIVE_DOUBLE, H5T_IEEE_F64LE, data);
}
void File::WriteInt32(const std::string& name, const std::vector<int64_t>& shape, const int32_t* data) {
  Write(name, shape, H5T_NATIVE_INT32, H5T_STD_I32LE, data);
}

std::vector<int64_t> File::Shape(const std::string& name) const {
  if (!Exists(name)) Fail(name, "missing dataset");
  Handle set(H5Dopen2(file_.get(), name.c_str(), H5P_DEFAULT), H5Dclose);
  if (!set.valid()) Fail(name, "cannot open dataset");
  Handle space(H5Dget_space(set.get()), H5Sclose);
  const int rank = H5Sget_simple_extent_ndims(space.get());
  if (rank < 0) Fail(name, "cannot read dataset shape");
  std::vector<hsize_t> dims(rank);
  H5Sget_simple_extent_dims(space.get(), dims.data(), nullptr);
  // The shape is only a header: a corrupt one must not become an allocation of terabytes. Without filters
  // (compression) a dataset stores every element, so its bytes bound what its shape may claim.
  Handle type(H5Dget_type(set.get()), H5Tclose);
  Handle properties(H5Dget_create_plist(set.get()), H5Pclose);
  if (!type.valid() || !properties.valid()) Fail(name, "cannot read dataset type");
  uint64_t bytes = H5Tget_size(type.get());
  for (const hsize_t d : dims) {
    if (d > static_cast<hsize_t>(std::numeric_limits<int64_t>::max()) || __builtin_mul_overflow(bytes, d, &bytes)) {
      Fail(name, "dataset shape too large (corrupt file)");
    }
  }
  const int filters = H5Pget_nfilters(properties.get());
  const hsize_t stored = H5Dget_storage_size(set.get());
  if (filters == 0 && bytes > stored) {
    Fail(name, "dataset shape needs " + std::to_string(bytes) + " bytes but the file stores " + std::to_string(stored) +
                   " (truncated or corrupt file)");
  }
  return std::vector<int64_t>(dims.begin(), dims.end());
}

void File::Read(const std::string& name, hid_t mem_type, void* data) const {
  Handle set(H5Dopen2(file_.get(), name.c_str(), H5P_DEFAULT), H5Dclose);
  if (!set.valid()) Fail(name, "cannot open dataset");
  Handle type(H5Dget_type(set.get()), H5Tclose);
  const H5T_class_t stored = H5Tget_class(type.get());
  const H5T_class_t wanted = H5Tget_class(mem_type);
  if (stored != wanted) {
    Fail(name, std::string("expected ") + (wanted == H5T_FLOAT ? "floating-point" : "integer") +
                   " data, found another element type");
  }
  if (H5Dread(set.get(), mem_type, H5S_ALL, H5S_ALL, H5P_DEFAULT, data) < 0) {
    Fail(name, "cannot read dataset (truncated or corrupt file)");
  }
}

std::vector<float> File::ReadFloat32(const std::string& name, std::vector<int64_t>* shape) const {
  const auto dims = Shape(name);
  if (shape) *shape = dims;
  std::vector<float> out(static_cast<size_t>(Product(dims)));
  if (!out.empty()) Read(name, H5T_NATIVE_FLOAT, out.data());
  return out;
}

std::vector<float> File::ReadFloat32Rows(const std::string& name, const std::vector<int64_t>& rows,
                                         std::vector<int64_t>* shape) const {
  const auto dims = Shape(name);
  if (shape) *shape = dims;
  if (dims.empty()) Fail(name, "cannot select rows of a scalar");
  const int64_t row_size = Product(dims) / std::max<int64_t>(dims[0], 1);
  std::vector<float> out(rows.size() * static_cast<size_t>(row_size));
  if (rows.empty() || row_size == 0) return out;
  for (size_t i = 0; i < rows.size(); ++i) {
    if (rows[i] < 0 || rows[i] >= dims[0] || (i > 0 && rows[i] <= rows[i - 1])) {
      Fail(name, "row " + std::to_string(rows[i]) + " is out of range or out of order");
    }
  }
  Handle set(H5Dopen2(file_.get(), name.c_str(), H5P_DEFAULT), H5Dclose);
  if (!set.valid()) Fail(name, "cannot open dataset");
  Handle file_space(H5Dget_space(set.get()), H5Sclose);
  // One hyperslab per run of consecutive rows.
  std::vector<hsize_t> start(dims.size(), 0), count(dims.begin(), dims.end());
  bool first = true;
  for (size_t i = 0; i < rows.size();) {
    size_t j = i + 1;
    while (j < rows.size() && rows[j] == rows[j - 1] + 1) ++j;
    start[0] = static_cast<hsize_t>(rows[i]);
    count[0] = static_cast<hsize_t>(j - i);
    if (H5Sselect_hyperslab(file_space.get(), first ? H5S_SELECT_SET : H5S_SELECT_OR, start.data(), nullptr,
                            count.data(), nullptr) < 0) {
      Fail(name, "cannot select rows");
    }
    first = false;
    i = j;
  }
  std::vector<hsize_t> memory_dims(dims.begin(), dims.end());
  memory_dims[0] = rows.size();
  Handle memory_space(H5Screate_simple(static_cast<int>(memory_dims.size()), memory_dims.data(), nullptr), H5Sclose);
  if (H5Dread(set.get(), H5T_NATIVE_FLOAT, memory_space.get(), file_space.get(), H5P_DEFAULT, out.data()) < 0) {
    Fail(name, "cannot read dataset (truncated or corrupt file)");
  }
  return out;
}

std::vector<double> File::ReadFloat64(const std::string& name, std::vector<int64_t>* shape) const {
  const auto dims = Shape(name);
  if (shape) *shape = dims;
  std::vector<double> out(static_cast<size_t>(Product(dims)));
  if (!out.empty()) Read(name, H5T_NATIVE_DOUBLE, out.data());
  return out;
}

std::vector<int32_t> File::ReadInt32(const std::string& name, std::vector<int64_t>* shape) const {
  const auto dims = Shape(name);
  if (shape) *shape = dims;
  std::vector<int32_t> out(static_cast<size_t>(Product(dims)));
  if (!out.empty()) Read(name, H5T_NATIVE_INT32, out.data());
  return out;
}

Handle File::OpenAttributeTarget(const std::string& object) const {
  Handle target(H5Oopen(file_.get(), object.c_str(), H5P_DEFAULT), H5Oclose);
  if (!target.valid()) Fail(object, "missing object");
  return target;
}

namespace {

void WriteAttribute(hid_t target, const std::string& name, hid_t file_type, hid_t mem_type,
                    const void* value, hid_t space) {
  if (H5Aexists(target, name.c_str()) > 0) H5Adelete(target, name.c_str());
  Handle attribute(H5Acreate2(target, name.c_str(), file_type, space, H5P_DEFAULT, H5P_DEFAULT),
                   H5Aclose);
  if (!attribute.valid() || H5Awrite(attribute.get(), mem_type, value) < 0) {
    throw Error("cannot write attribute " + name);
  }
}

}  // namespace

void File::SetAttribute(const std::string& object, const std::string& name, const std::string& value) {
  Handle target = OpenAttributeTarget(object);
  // Variable-length UTF-8 strings: h5py reads them back as str.
  Handle type(H5Tcopy(H5T_C_S1), H5Tclose);
  H5Tset_size(type.get(), H5T_VARIABLE);
  H5Tset_cset(type.get(), H5T_CSET_UTF8);
  Handle space(H5Screate(H5S_SCALAR), H5Sclose);
  const char* text = value.c_str();
  try {
    WriteAttribute(target.get(), name, type.get(), type.get(), &text, space.get());
  } catch (const Error&) {
    Fail(object, "cannot write attribute " + name);
  }
}

void File::SetAttribute(const std::string& object, const std::string& name, int64_t value) {
  Handle target = OpenAttributeTarget(object);
  Handle space(H5Screate(H5S_SCALAR), H5Sclose);
  try {
    WriteAttribute(target.get(), name, H5T_STD_I64LE, H5T_NATIVE_INT64, &value, space.get());
  } catch (const Error&) {
    Fail(object, "cannot write attribute " + name);
  }
}

void File::SetAttribute(const std::string& object, const std::string& name, double value) {
  Handle target = OpenAttributeTarget(object);
  Handle space(H5Screate(H5S_SCALAR), H5Sclose);
  try {
    WriteAttribute(target.get(), name, H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, &value, space.get());
  } catch (const Error&) {
    Fail(object, "cannot write attribute " + name);
  }
}

bool File::HasAttribute(const std::string& object, const std::string& name) const {
  if (!Exists(object)) return false;
  Handle target = OpenAttributeTarget(object);
  return H5Aexists(target.get(), name.c_str()) > 0;
}

Handle File::OpenScalarAttribute(const std::string& object, const std::string& name, H5T_class_t expected,
                                 const char* what) const {
  if (!HasAttribute(object, name)) Fail(object, "missing attribute '" + name + "'");
  Handle target = OpenAttributeTarget(object);
  Handle attribute(H5Aopen(target.get(), name.c_str(), H5P_DEFAULT), H5Aclose);
  Handle space(H5Aget_space(attribute.get()), H5Sclose);
  Handle stored(H5Aget_type(attribute.get()), H5Tclose);
  if (!attribute.valid() || H5Sget_simple_extent_npoints(space.get()) != 1 ||
      H5Tget_class(stored.get()) != expected) {
    Fail(object, "attribute '" + name + "': expected a single " + what);
  }
  return attribute;
}

std::string File::GetStringAttribute(const std::string& object, const std::string& name) const {
  Handle attribute = OpenScalarAttribute(object, name, H5T_STRING, "string");
  Handle stored(H5Aget_type(attribute.get()), H5Tclose);
  if (H5Tis_variable_str(stored.get()) > 0) {
    Handle type(H5Tcopy(H5T_C_S1), H5Tclose);
    H5Tset_size(type.get(), H5T_VARIABLE);
    H5Tset_cset(type.get(), H5Tget_cset(stored.get()));
    char* text = nullptr;
    if (H5Aread(attribute.get(), type.get(), &text) < 0) Fail(object, "cannot read attribute " + name);
    std::string value = text ? text : "";
    Handle space(H5Aget_space(attribute.get()), H5Sclose);
    H5Dvlen_reclaim(type.get(), space.get(), H5P_DEFAULT, &text);
    return value;
  }
  const size_t size = H5Tget_size(stored.get());
  std::string value(size, '\0');
  if (H5Aread(attribute.get(), stored.get(), value.data()) < 0) Fail(object, "cannot read attribute " + name);
  value.resize(value.find('\0') == std::string::npos ? size : value.find('\0'));
  return value;
}

int64_t File::GetIntAttribute(const std::string& object, const std::string& name) const {
  Handle attribute = OpenScalarAttribute(object, name, H5T_INTEGER, "integer");
  int64_t value = 0;
  if (H5Aread(attribute.get(), H5T_NATIVE_INT64, &value) < 0) Fail(object, "cannot read attribute " + name);
  return value;
}

double File::GetDoubleAttribute(const std::string& object, const std::string& name) const {
  Handle attribute = OpenScalarAttribute(object, name, H5T_FLOAT, "floating-point number");
  double value = 0;
  if (H5Aread(attribute.get(), H5T_NATIVE_DOUBLE, &value) < 0) Fail(object, "cannot read attribute " + name);
  return value;
}

void File::Close() {
  if (!file_.valid()) return;
  if (H5Fflush(file_.get(), H5F_SCOPE_LOCAL) < 0) Fail("", "cannot flush file (disk full?)");
  const hid_t id = file_.get();
  file_.Release();
  if (H5Fclose(id) < 0) Fail("", "cannot close file (disk full?)");
}

}  // namespace flowplan::datasets::h5
