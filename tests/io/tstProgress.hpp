// Progress lines (step, time, elapsed, ETA) with a scripted clock, and the summary table.
#include <perishell/io/progress.hpp>

#include <sstream>

namespace perishell_test_progress {

TEST(TEST_CATEGORY, progress_prints_first_due_and_last_steps_with_eta) {
  double now = 100.0;
  std::ostringstream out;
  perishell::io::ProgressReporter progress(1000, out, 5.0, [&] { return now; });
  now = 101.0;
  EXPECT_TRUE(progress.update(1, 1.0e-7));  // the first step always prints
  now = 103.0;
  EXPECT_FALSE(progress.update(300, 3.0e-5));  // 2 s since the last line
  now = 106.0;
  EXPECT_TRUE(progress.update(600, 6.0e-5));  // 600 steps in 6 s: 400 more take 4 s
  now = 107.0;
  EXPECT_TRUE(progress.update(1000, 1.0e-4));  // the last step always prints
  EXPECT_EQ(out.str(),
            "step 1/1000 (  0.1 %)  t = 1.000000e-07 s  elapsed 1.0 s  ETA 16 min 39 s\n"
            "step 600/1000 ( 60.0 %)  t = 6.000000e-05 s  elapsed 6.0 s  ETA 4.0 s\n"
            "step 1000/1000 (100.0 %)  t = 1.000000e-04 s  elapsed 7.0 s  ETA 0.0 s\n");
  EXPECT_DOUBLE_EQ(progress.elapsedSeconds(), 7.0);
  EXPECT_THROW(progress.update(1001, 0.0), std::out_of_range);
  EXPECT_THROW(perishell::io::ProgressReporter(0, out), std::invalid_argument);
}

TEST(TEST_CATEGORY, progress_durations_and_summary_table) {
  EXPECT_EQ(perishell::io::formatDuration(12.34), "12.3 s");
  EXPECT_EQ(perishell::io::formatDuration(187.0), "3 min 07 s");
  EXPECT_EQ(perishell::io::formatDuration(3720.0), "1 h 02 min");
  EXPECT_EQ(perishell::io::formatDuration(-1.0), "?");
  std::ostringstream out;
  perishell::io::SummaryTable("run summary").add("steps", "50,000").add("wall time", "1 h 02 min").print(out);
  EXPECT_EQ(out.str(), "run summary\n  steps      50,000\n  wall time  1 h 02 min\n");
}

}  // namespace perishell_test_progress
