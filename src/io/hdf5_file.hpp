#pragma once
// The HDF5 C API as perishell's writers and readers use it (private to src/io): errors
// become exceptions naming the file and HDF5's most specific reason (its own stack is not
// printed), identifiers close on scope exit, files are written atomically (atomic_file.hpp).
#include <perishell/io/atomic_file.hpp>

#include <hdf5.h>

#include <functional>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

namespace perishell::io::hdf5 {

// HDF5 prints its error stack to stderr by default; while perishell calls it, the stack is
// read into the exception message instead.
class QuietHdf5Errors {
 public:
  QuietHdf5Errors() {
    H5Eget_auto2(H5E_DEFAULT, &savedHandler_, &savedData_);
    H5Eset_auto2(H5E_DEFAULT, nullptr, nullptr);
  }
  ~QuietHdf5Errors() { H5Eset_auto2(H5E_DEFAULT, savedHandler_, savedData_); }
  QuietHdf5Errors(const QuietHdf5Errors&) = delete;
  QuietHdf5Errors& operator=(const QuietHdf5Errors&) = delete;

 private:
  H5E_auto2_t savedHandler_ = nullptr;
  void* savedData_ = nullptr;
};

// The innermost entry of HDF5's error stack: the most specific reason (for a file that
// cannot be created it carries the errno text, e.g. "No such file or directory").
inline std::string innermostHdf5Error() {
  std::string description = "no HDF5 error detail";
  const auto takeFirst = [](unsigned entry, const H5E_error2_t* error, void* result) -> herr_t {
    if (entry == 0 && error->desc) *static_cast<std::string*>(result) = error->desc;
    return 0;
  };
  H5Ewalk2(H5E_DEFAULT, H5E_WALK_UPWARD, takeFirst, &description);
  return description;
}

template <class StatusT>
StatusT checkHdf5(StatusT status, const std::string& what, const std::string& path) {
  if (status < 0)
    throw std::runtime_error("HDF5 file '" + path + "': cannot " + what + ": " + innermostHdf5Error());
  return status;
}

// An HDF5 identifier closed on scope exit; closeChecked() for the file, whose close flushes
// the data and so can fail.
class Hdf5Handle {
 public:
  Hdf5Handle(hid_t id, herr_t (*close)(hid_t)) : id_(id), close_(close) {}
  ~Hdf5Handle() {
    if (id_ >= 0) close_(id_);
  }
  Hdf5Handle(const Hdf5Handle&) = delete;
  Hdf5Handle& operator=(const Hdf5Handle&) = delete;

  hid_t get() const { return id_; }
  void closeChecked(const std::string& path) {
    const hid_t id = std::exchange(id_, -1);
    checkHdf5(close_(id), "close the file", path);
  }

 private:
  hid_t id_;
  herr_t (*close_)(hid_t);
};

// Creates the HDF5 file `path` atomically; fill(file, temporaryPath) adds the datasets.
inline void writeHdf5FileAtomically(const std::string& path,
                             const std::function<void(hid_t, const std::string&)>& fill) {
  replaceFileAtomically(path, [&fill](const std::string& temporary) {
    const QuietHdf5Errors quiet;
    Hdf5Handle file(checkHdf5(H5Fcreate(temporary.c_str(), H5F_ACC_TRUNC, H5P_DEFAULT, H5P_DEFAULT),
                              "create the file", temporary),
                    H5Fclose);
    fill(file.get(), temporary);
    file.closeChecked(temporary);
  });
}

inline void writeDataset(hid_t location, const std::string& name, hid_t memoryType, hid_t fileType,
                  const std::vector<hsize_t>& dimensions, const void* data, const std::string& path) {
  Hdf5Handle space(
      checkHdf5(H5Screate_simple(static_cast<int>(dimensions.size()), dimensions.data(), nullptr),
                "create the dataspace of '" + name + "'", path),
      H5Sclose);
  Hdf5Handle dataset(checkHdf5(H5Dcreate2(location, name.c_str(), fileType, space.get(), H5P_DEFAULT,
                                          H5P_DEFAULT, H5P_DEFAULT),
                               "create dataset '" + name + "'", path),
                     H5Dclose);
  checkHdf5(H5Dwrite(dataset.get(), memoryType, H5S_ALL, H5S_ALL, H5P_DEFAULT, data),
            "write dataset '" + name + "'", path);
}

// Opens an existing file for reading; the handle closes it.
inline Hdf5Handle openForReading(const std::string& path) {
  return Hdf5Handle(checkHdf5(H5Fopen(path.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT), "open the file", path), H5Fclose);
}

inline bool hasLink(hid_t location, const std::string& name) { return H5Lexists(location, name.c_str(), H5P_DEFAULT) > 0; }

// The extents of dataset `name`.
inline std::vector<hsize_t> datasetExtents(hid_t location, const std::string& name, const std::string& path) {
  Hdf5Handle dataset(checkHdf5(H5Dopen2(location, name.c_str(), H5P_DEFAULT), "open dataset '" + name + "'", path),
                     H5Dclose);
  Hdf5Handle space(checkHdf5(H5Dget_space(dataset.get()), "read the extents of '" + name + "'", path), H5Sclose);
  const int rank = checkHdf5(H5Sget_simple_extent_ndims(space.get()), "read the rank of '" + name + "'", path);
  std::vector<hsize_t> extents(static_cast<std::size_t>(rank));
  checkHdf5(H5Sget_simple_extent_dims(space.get(), extents.data(), nullptr), "read the extents of '" + name + "'",
            path);
  return extents;
}

// Dataset `name` whole, converted to memoryType, into `data` (its size the product of the extents).
inline void readDataset(hid_t location, const std::string& name, hid_t memoryType, void* data,
                        const std::string& path) {
  Hdf5Handle dataset(checkHdf5(H5Dopen2(location, name.c_str(), H5P_DEFAULT), "open dataset '" + name + "'", path),
                     H5Dclose);
  checkHdf5(H5Dread(dataset.get(), memoryType, H5S_ALL, H5S_ALL, H5P_DEFAULT, data), "read dataset '" + name + "'",
            path);
}

// The names of the links in a group, in name order.
inline std::vector<std::string> linkNames(hid_t group, const std::string& path) {
  std::vector<std::string> names;
  const auto collect = [](hid_t, const char* name, const H5L_info_t*, void* result) -> herr_t {
    static_cast<std::vector<std::string>*>(result)->push_back(name);
    return 0;
  };
  checkHdf5(H5Literate(group, H5_INDEX_NAME, H5_ITER_INC, nullptr, collect, &names), "list a group", path);
  return names;
}

}  // namespace perishell::io::hdf5
