#include <perishell/io/atomic_file.hpp>

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <stdexcept>

#include <fcntl.h>
#include <unistd.h>

namespace perishell::io {

namespace {

[[noreturn]] void throwSystemError(const std::string& what, const std::string& path, int error) {
  throw std::runtime_error(what + " '" + path + "': " + std::strerror(error));
}

void closeChecked(int descriptor, const std::string& path) {
  // close() reports deferred write errors (NFS, quota), so it is checked like write().
  if (::close(descriptor) != 0) throwSystemError("cannot close", path, errno);
}

void fsyncFile(const std::string& path) {
  const int descriptor = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
  if (descriptor < 0) throwSystemError("cannot open for fsync", path, errno);
  if (::fsync(descriptor) != 0) {
    const int error = errno;
    ::close(descriptor);
    throwSystemError("fsync failed for", path, error);
  }
  closeChecked(descriptor, path);
}

void writeAll(int descriptor, const std::string& contents, const std::string& path, off_t offset = -1) {
  const char* next = contents.data();
  std::size_t left = contents.size();
  while (left > 0) {
    const ssize_t written = offset < 0 ? ::write(descriptor, next, left) : ::pwrite(descriptor, next, left, offset);
    if (written < 0) {
      if (errno == EINTR) continue;
      const int error = errno;
      ::close(descriptor);
      throwSystemError("cannot write", path, error);
    }
    next += written;
    left -= static_cast<std::size_t>(written);
    if (offset >= 0) offset += written;
  }
}

}  // namespace

std::string temporaryPathFor(const std::string& path) { return path + ".tmp." + std::to_string(::getpid()); }

void replaceFileAtomically(const std::string& path,
                           const std::function<void(const std::string& temporaryPath)>& writeTemporary) {
  if (path.empty()) throw std::invalid_argument("atomic file write: empty path");
  const std::string temporary = temporaryPathFor(path);
  try {
    writeTemporary(temporary);
    fsyncFile(temporary);
    if (std::rename(temporary.c_str(), path.c_str()) != 0)
      throwSystemError("cannot rename '" + temporary + "' to", path, errno);
  } catch (...) {
    // The writer may have failed before creating it: a missing temporary is fine here.
    std::remove(temporary.c_str());
    throw;
  }
}

void writeFileAtomically(const std::string& path, const std::string& contents) {
  replaceFileAtomically(path, [&contents](const std::string& temporary) {
    const int descriptor = ::open(temporary.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0666);
    if (descriptor < 0) throwSystemError("cannot create", temporary, errno);
    writeAll(descriptor, contents, temporary);
    closeChecked(descriptor, temporary);
  });
}

void replaceFileTail(const std::string& path, std::size_t offset, const std::string& previousTail,
                     const std::string& newTail) {
  const int descriptor = ::open(path.c_str(), O_WRONLY | O_CLOEXEC);
  if (descriptor < 0) throwSystemError("cannot open", path, errno);
  const int restoreDescriptor = ::dup(descriptor);  // writeAll closes the one it fails on
  try {
    writeAll(descriptor, newTail, path, static_cast<off_t>(offset));
    if (::fdatasync(descriptor) != 0) {
      const int error = errno;
      ::close(descriptor);
      throwSystemError("fsync failed for", path, error);
    }
    closeChecked(descriptor, path);
  } catch (...) {
    if (restoreDescriptor >= 0) {
      if (::ftruncate(restoreDescriptor, static_cast<off_t>(offset)) == 0)
        (void)::pwrite(restoreDescriptor, previousTail.data(), previousTail.size(), static_cast<off_t>(offset));
      ::close(restoreDescriptor);
    }
    throw;
  }
  if (restoreDescriptor >= 0) ::close(restoreDescriptor);
}

}  // namespace perishell::io
