#pragma once
// A run's hold on its output directory (docs/reliability.md, docs/results.md):
//  - a lock file DIR/perishell.lock, flock(2)ed while the run lives and holding "pid host": a
//    second run refuses the directory and names the holder; the kernel releases the lock of a
//    run that died (killed), whose file the next run takes over with a note;
//  - the result files an earlier run left are removed before this run writes (a shorter rerun
//    would otherwise leave the longer run's step files beside its own): results.xmf,
//    results_mesh.h5, results_NNNNNN.h5, history.csv, timings.csv, and the temporaries
//    checkpoint.h5 and the temporaries "<file>.tmp.<pid>" of processes that no longer run
//    (io/atomic_file.hpp). A restart (`run --restart DIR`) keeps the earlier run's results,
//    which it continues, and removes only the temporaries.
// Other files in the directory (check --output's model files, the user's own) are left alone.
#include <iosfwd>
#include <stdexcept>
#include <string>

namespace perishell::io {

// A directory another live run holds, or one that cannot be locked (the reason in the message).
class OutputDirectoryError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

class OutputDirectoryLock {
 public:
  enum class EarlierResults { Clear, Keep };

  // Creates the directory, takes the lock, clears an earlier run's result files (unless
  // Keep: a restart continues them); notes on log what it took over or removed. Throws
  // OutputDirectoryError.
  OutputDirectoryLock(const std::string& directory, std::ostream& log,
                      EarlierResults earlier = EarlierResults::Clear);
  ~OutputDirectoryLock();  // removes the lock file
  OutputDirectoryLock(const OutputDirectoryLock&) = delete;
  OutputDirectoryLock& operator=(const OutputDirectoryLock&) = delete;

  const std::string& lockPath() const { return lockPath_; }

 private:
  std::string lockPath_;
  int descriptor_ = -1;  // open while the run holds the lock
};

// The lock file's name inside an output directory.
constexpr const char* outputLockFileName = "perishell.lock";

}  // namespace perishell::io
