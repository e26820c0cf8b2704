// Output directories (issue 22): a run's lock refuses a second live holder and names it, a
// dead holder's lock is taken over with a note, an earlier run's result files and the
// temporaries of dead processes are removed, other files are kept. Host side; TEST_EXECSPACE
// only picks the binary the test runs in.
#include <perishell/io/output_directory.hpp>

#include <scratch_directory.hpp>

#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

namespace {

namespace fs = std::filesystem;
using perishell::io::OutputDirectoryError;
using perishell::io::OutputDirectoryLock;
using perishell_test::ScratchDirectory;

std::string readText(const std::string& path) {
  std::ifstream file(path);
  std::ostringstream text;
  text << file.rdbuf();
  return text.str();
}

std::vector<std::string> namesIn(const std::string& directory) {
  std::vector<std::string> names;
  for (const auto& entry : fs::directory_iterator(directory)) names.push_back(entry.path().filename().string());
  std::sort(names.begin(), names.end());
  return names;
}

std::string thisHost() {
  char name[256] = {};
  gethostname(name, sizeof name - 1);
  return name;
}

// A process id that no longer runs: a child that has exited and been reaped.
pid_t deadProcessId() {
  const pid_t child = fork();
  if (child == 0) _exit(0);
  waitpid(child, nullptr, 0);
  return child;
}

}  // namespace

TEST(TEST_CATEGORY, output_directory_lock_refuses_a_second_holder_and_names_the_first) {
  const ScratchDirectory scratch;
  const std::string directory = scratch.path() + "/run";
  std::ostringstream log;
  std::string lockPath;
  {
    const OutputDirectoryLock first(directory, log);
    lockPath = first.lockPath();
    EXPECT_EQ(lockPath, directory + "/perishell.lock");
    EXPECT_EQ(readText(lockPath), std::to_string(getpid()) + " " + thisHost() + "\n");
    try {
      const OutputDirectoryLock second(directory, log);
      ADD_FAILURE() << "a second lock was granted on a held directory";
    } catch (const OutputDirectoryError& error) {
      EXPECT_EQ(std::string(error.what()), "output directory " + directory + " is in use by run " +
                                               std::to_string(getpid()) + " on " + thisHost() + " (lock file " +
                                               lockPath + "); wait for that run to end or choose another --output");
    }
  }
  // Released: the file is gone and the next run takes the directory without a note.
  EXPECT_FALSE(fs::exists(lockPath));
  const OutputDirectoryLock again(directory, log);
  EXPECT_EQ(log.str(), "");
}

TEST(TEST_CATEGORY, output_directory_lock_of_a_killed_run_is_taken_over_and_its_files_cleared) {
  const ScratchDirectory scratch;
  const std::string& directory = scratch.path();
  const pid_t dead = deadProcessId();
  const std::string deadPid = std::to_string(dead);
  // What a killed longer run leaves: its lock text (the kernel dropped its flock), six step
  // files, the .xmf, history, timings, and temporaries of its atomic writes.
  std::ofstream(directory + "/perishell.lock") << deadPid << " " << thisHost() << "\n";
  for (const char* name : {"results.xmf", "results_mesh.h5", "results_000000.h5", "results_000001.h5",
                           "results_000002.h5", "results_000003.h5", "results_000004.h5", "results_000005.h5",
                           "history.csv", "timings.csv"})
    std::ofstream(directory + "/" + name) << "old";
  std::ofstream(directory + "/results_000006.h5.tmp." + deadPid) << "torn";
  std::ofstream(directory + "/history.csv.tmp." + deadPid) << "torn";
  // Kept: check --output's model files, the user's own files, a live process's temporary.
  const std::string liveTemporary = "model.xmf.tmp." + std::to_string(getppid());
  for (const std::string name : {"model.xmf", "model_mesh.h5", "notes.txt", "results_backup.h5", liveTemporary.c_str()})
    std::ofstream(directory + "/" + name) << "keep";

  std::ostringstream log;
  const OutputDirectoryLock lock(directory, log);
  EXPECT_NE(log.str().find("output: took over the lock of run " + deadPid + " on " + thisHost() +
                           ", which no longer runs\n"),
            std::string::npos)
      << log.str();
  EXPECT_NE(log.str().find("output: removed 12 file(s) of an earlier run from " + directory + " ("),
            std::string::npos)
      << log.str();
  std::vector<std::string> expected = {"model.xmf", "model_mesh.h5", "notes.txt", "perishell.lock",
                                       "results_backup.h5", liveTemporary};
  std::sort(expected.begin(), expected.end());
  EXPECT_EQ(namesIn(directory), expected);
  EXPECT_EQ(readText(lock.lockPath()), std::to_string(getpid()) + " " + thisHost() + "\n");
}

TEST(TEST_CATEGORY, output_directory_that_cannot_be_created_is_reported) {
  const ScratchDirectory scratch;
  std::ofstream(scratch.path() + "/file") << "not a directory";
  std::ostringstream log;
  try {
    const OutputDirectoryLock lock(scratch.path() + "/file/run", log);
    ADD_FAILURE() << "a directory under a file was locked";
  } catch (const OutputDirectoryError& error) {
    EXPECT_EQ(std::string(error.what()).rfind("output directory: cannot create '" + scratch.path() + "/file/run': ", 0), 0u)
        << error.what();
  }
}
