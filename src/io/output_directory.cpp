#include <perishell/io/output_directory.hpp>

#include <cerrno>
#include <csignal>
#include <cstring>
#include <filesystem>
#include <ostream>
#include <regex>
#include <string>
#include <vector>

#include <fcntl.h>
#include <sys/file.h>
#include <sys/stat.h>
#include <unistd.h>

namespace perishell::io {

namespace {

namespace fs = std::filesystem;

std::string hostName() {
  char name[256] = {};
  if (::gethostname(name, sizeof name - 1) != 0) return "unknown host";
  return name;
}

bool processRuns(long pid) { return pid > 0 && (::kill(static_cast<pid_t>(pid), 0) == 0 || errno == EPERM); }

[[noreturn]] void failOn(const std::string& what, const std::string& path, int error) {
  throw OutputDirectoryError("output directory: cannot " + what + " '" + path + "': " + std::strerror(error));
}

std::string readAll(int descriptor) {
  std::string text;
  char buffer[256];
  ssize_t count;
  ::lseek(descriptor, 0, SEEK_SET);
  while ((count = ::read(descriptor, buffer, sizeof buffer)) > 0) text.append(buffer, std::size_t(count));
  while (!text.empty() && (text.back() == '\n' || text.back() == '\r')) text.pop_back();
  return text;
}

// "run 1234 on host" from the lock's "pid host" text.
std::string describeHolder(const std::string& text) {
  const auto space = text.find(' ');
  if (text.empty() || space == std::string::npos) return "another run (lock text '" + text + "')";
  return "run " + text.substr(0, space) + " on " + text.substr(space + 1);
}

// The files an earlier run of either solver leaves (docs/results.md), and the temporaries of
// atomic writes whose process no longer runs.
void removeEarlierResults(const std::string& directory, std::ostream& log, bool keepResults) {
  static const std::regex resultFile(
      R"((results(_mesh|_[0-9]{6,})?\.(xmf|h5))|history\.csv|timings\.csv|checkpoint\.h5)");
  static const std::regex temporaryFile(R"(.+\.tmp\.([0-9]+))");
  std::vector<std::string> removed;
  for (const auto& entry : fs::directory_iterator(directory)) {
    if (!entry.is_regular_file()) continue;
    const std::string name = entry.path().filename().string();
    std::smatch match;
    // A pid of more than 9 digits is no process of this system.
    const bool stale = (!keepResults && std::regex_match(name, resultFile)) ||
                       (std::regex_match(name, match, temporaryFile) &&
                        (match[1].length() > 9 || !processRuns(std::stol(match[1].str()))));
    if (!stale) continue;
    std::error_code error;
    if (!fs::remove(entry.path(), error) && error) failOn("remove the earlier result file", entry.path().string(), error.value());
    removed.push_back(name);
  }
  if (removed.empty()) return;
  log << "output: removed " << removed.size() << " file(s) of an earlier run from " << directory << " (";
  for (std::size_t k = 0; k < removed.size() && k < 4; ++k) log << (k ? ", " : "") << removed[k];
  log << (removed.size() > 4 ? ", ..." : "") << ")\n";
}

}  // namespace

OutputDirectoryLock::OutputDirectoryLock(const std::string& directory, std::ostream& log, EarlierResults earlier)
    : lockPath_((fs::path(directory) / outputLockFileName).string()) {
  std::error_code error;
  fs::create_directories(directory, error);
  if (error) failOn("create", directory, error.value());
  // flock: the kernel drops it when the holder dies, so a killed run's lock is free; the
  // text names the holder for the refusal and the takeover note.
  for (;;) {
    const int descriptor = ::open(lockPath_.c_str(), O_RDWR | O_CREAT | O_CLOEXEC, 0644);
    if (descriptor < 0) failOn("create the lock file", lockPath_, errno);
    if (::flock(descriptor, LOCK_EX | LOCK_NB) != 0) {
      const int lockError = errno;
      const std::string holder = readAll(descriptor);
      ::close(descriptor);
      if (lockError != EWOULDBLOCK) failOn("lock", lockPath_, lockError);
      throw OutputDirectoryError("output directory " + directory + " is in use by " + describeHolder(holder) +
                                 " (lock file " + lockPath_ + "); wait for that run to end or choose another --output");
    }
    // The holder before may have removed the file between our open and our lock: retry on the new one.
    struct stat opened {}, current {};
    if (::fstat(descriptor, &opened) != 0 || ::stat(lockPath_.c_str(), &current) != 0 ||
        opened.st_ino != current.st_ino) {
      ::close(descriptor);
      continue;
    }
    const std::string previous = readAll(descriptor);
    if (!previous.empty())
      log << "output: took over the lock of " << describeHolder(previous) << ", which no longer runs\n";
    const std::string text = std::to_string(::getpid()) + " " + hostName() + "\n";
    if (::ftruncate(descriptor, 0) != 0 || ::pwrite(descriptor, text.data(), text.size(), 0) != ssize_t(text.size())) {
      const int writeError = errno;
      ::close(descriptor);
      failOn("write the lock file", lockPath_, writeError);
    }
    descriptor_ = descriptor;
    break;
  }
  removeEarlierResults(directory, log, earlier == EarlierResults::Keep);
}

OutputDirectoryLock::~OutputDirectoryLock() {
  // Unlink first: a run that opens the path next creates a fresh file and locks that one.
  ::unlink(lockPath_.c_str());
  ::close(descriptor_);
}

}  // namespace perishell::io
