// The study runner on both engines at a less tiny size (label slow): a sweep of the
// paper's cylinder position with 2D and 3D must store the same records with one
// and with two worker threads (Bullet and Box2D are deterministic per run, and
// runs share nothing).
#include "studies/jobs.hpp"
#include "studies/runner.hpp"
#include "studies/store.hpp"
#include "studies/study.hpp"
#include "tests/test_support.hpp"

#include <gtest/gtest.h>

#include <filesystem>
#include <sstream>
#include <unistd.h>

using namespace gapflow;
namespace fs = std::filesystem;

namespace {

const char* kStudy = R"(
[study]
name = "slow-cylinder"
replicates = 2
models = ["2d", "3d"]
set = ["particles.count=300", "run.time_limit_s=8", "run.stop_after_no_flow_s=0"]
[[series]]
label = "cylinder"
scenario = "cylinder.toml"
  [[series.sweep]]
  key = "obstruction.distance_mm"
  values = [70, 100]
)";

// Every stored run as text: identity and the complete record as JSON (wall time zeroed).
std::vector<std::string> stored_text(const fs::path& db) {
  std::vector<std::string> out;
  for (StoredRun r : Store(db).load()) {
    r.record.wall_time_s = 0;
    std::ostringstream s;
    s << r.id.key << " " << r.id.series << " " << r.id.point << " " << r.id.point_label << " " << r.id.axes_json
      << " " << r.id.model << " " << r.id.replicate << "\n";
    write_json(s, r.record);
    out.push_back(s.str());
  }
  return out;
}

}  // namespace

TEST(SlowStudyRunner, slow_BothModelsStoreTheSameRecordsOnOneAndTwoWorkers) {
  const fs::path dir = fs::temp_directory_path() / ("gapflow-slow-study-" + std::to_string(getpid()));
  fs::create_directories(dir);
  const std::vector<Job> jobs =
      expand_jobs(parse_study(kStudy, "slow.toml", gapflow::testing::source_path("scenarios/paper")));
  ASSERT_EQ(jobs.size(), 8u);
  for (int workers : {1, 2}) {
    Store store(dir / (std::to_string(workers) + ".sqlite"));
    RunnerOptions o;
    o.workers = workers;
    const RunnerSummary s = run_jobs(jobs, store, o);
    EXPECT_EQ(s.done_now, 8);
    EXPECT_TRUE(s.failed.empty());
  }
  const auto one = stored_text(dir / "1.sqlite"), two = stored_text(dir / "2.sqlite");
  ASSERT_EQ(one.size(), 8u);
  EXPECT_EQ(one, two);
  fs::remove_all(dir);
}
