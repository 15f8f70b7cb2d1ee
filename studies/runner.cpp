#include "studies/runner.hpp"

#include "models/registry.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <condition_variable>
#include <mutex>
#include <ostream>
#include <thread>

namespace gapflow {

std::string format_duration(double seconds) {
  const long s = std::lround(std::max(0.0, seconds));
  if (s < 60) return fmt::format("{}s", s);
  if (s < 3600) return fmt::format("{}m {:02}s", s / 60, s % 60);
  return fmt::format("{}h {:02}m", s / 3600, (s % 3600) / 60);
}

RunRecord run_job(const Job& job, const std::atomic<bool>* cancel) {
  const CompiledScenario sc = compile_job(job);
  // The key promised what this run is: a scenario file edited since the expansion breaks that promise.
  if (sc.scenario_hash != job.id.scenario_hash)
    throw std::runtime_error(fmt::format("scenario {} changed since the study started (hash {:016x}, expected {:016x})",
                                         job.scenario.string(), sc.scenario_hash, job.id.scenario_hash));
  return run_model(sc, job.model, nullptr, cancel);
}

namespace {

using Clock = std::chrono::steady_clock;

// Progress on stderr: a bar redrawn in place on a terminal; in a log file one
// line per ~10 % of the jobs or per 30 s, whichever comes first.
class Progress {
 public:
  Progress(std::ostream* out, bool tty, int total, int already)
      : out_(out), tty_(tty), total_(total), already_(already), start_(Clock::now()), last_line_(start_) {}

  void update(int done_now, int failed) {
    if (!out_) return;
    const int done = already_ + done_now;
    if (tty_) {
      *out_ << "\r" << text(done_now, failed, true) << "\x1b[K" << std::flush;
      return;
    }
    const int tenth = total_ > 0 ? 10 * done / total_ : 10;
    const auto now = Clock::now();
    if (tenth > last_tenth_ || now - last_line_ >= std::chrono::seconds(30)) {
      *out_ << text(done_now, failed, false) << "\n" << std::flush;
      last_tenth_ = tenth;
      last_line_ = now;
    }
  }
  void finish() {
    if (out_ && tty_) *out_ << "\n";
  }

 private:
  std::string text(int done_now, int failed, bool bar) const {
    const int done = already_ + done_now;
    const double minutes = std::chrono::duration<double>(Clock::now() - start_).count() / 60.0;
    const double rate = minutes > 0 ? done_now / minutes : 0.0;  // runs per minute, this session only
    const int left = total_ - done - failed;
    std::string eta = rate > 0 ? format_duration(60.0 * left / rate) : std::string("?");
    std::string s;
    if (bar) {
      constexpr int width = 30;
      const auto filled = static_cast<std::size_t>(total_ > 0 ? std::clamp(width * done / total_, 0, width) : width);
      s = fmt::format("[{}{}] ", std::string(filled, '#'), std::string(width - filled, '-'));
    }
    s += fmt::format("{}/{} runs ({:.0f} %)  {:.1f} runs/min  ETA {}", done, total_,
                     total_ > 0 ? 100.0 * done / total_ : 100.0, rate, eta);
    if (failed > 0) s += fmt::format("  ({} failed)", failed);
    return s;
  }

  std::ostream* out_;
  bool tty_;
  int total_, already_;
  Clock::time_point start_, last_line_;
  int last_tenth_ = 0;
};

bool cancelled(const std::atomic<bool>* cancel) { return cancel && cancel->load(); }

}  // namespace

std::vector<const Job*> jobs_to_run(const std::vector<Job>& jobs, const Store& store, RunnerSummary& summary) {
  summary.total = static_cast<int>(jobs.size());
  const std::set<std::string> stored = store.keys();
  std::vector<const Job*> todo;
  for (const Job& j : jobs)
    if (!stored.count(j.id.key)) todo.push_back(&j);
  // Longest expected jobs first (LPT): a long 3D or large run started last would leave the
  // other workers idle at the end. Only the order changes, never a result (a job's seed and
  // scenario are in its key).
  std::stable_sort(todo.begin(), todo.end(),
                   [](const Job* a, const Job* b) { return a->expected_cost > b->expected_cost; });
  summary.already_stored = summary.total - static_cast<int>(todo.size());
  return todo;
}

RunnerSummary run_jobs(const std::vector<Job>& jobs, Store& store, const RunnerOptions& options) {
  RunnerSummary summary;
  const std::vector<const Job*> todo = jobs_to_run(jobs, store, summary);

  const auto run = options.run ? options.run : run_job;
  std::mutex mutex;  // guards summary.failed, finished_workers; signals the progress loop
  std::condition_variable changed;
  std::size_t next = 0;
  int done_now = 0, finished_workers = 0;

  auto worker = [&] {
    for (;;) {
      const Job* job = nullptr;
      {
        std::lock_guard lock(mutex);
        if (cancelled(options.cancel) || next >= todo.size()) break;
        job = todo[next++];
      }
      try {
        const RunRecord record = run(*job, options.cancel);
        store.put(job->id, record);
        std::lock_guard lock(mutex);
        ++done_now;
      } catch (const RunCancelled&) {
        break;  // abandoned: leaves no row, runs again on resume
      } catch (const std::exception& e) {
        std::lock_guard lock(mutex);
        summary.failed.push_back({job->id, e.what()});
        if (options.progress)
          *options.progress << fmt::format("{}failed: job {} (series '{}', point {} '{}', model {}, replicate {}): {}\n",
                                           options.tty ? "\r\x1b[K" : "", job->id.key, job->id.series,
                                           job->id.point, job->id.point_label, job->id.model, job->id.replicate,
                                           e.what());
      }
      changed.notify_all();
    }
    std::lock_guard lock(mutex);
    ++finished_workers;
    changed.notify_all();
  };

  const int n_workers = std::max(1, std::min<int>(options.workers, static_cast<int>(todo.size())));
  Progress progress(options.progress, options.tty, summary.total, summary.already_stored);
  std::vector<std::thread> pool;
  if (!todo.empty())
    for (int w = 0; w < n_workers; ++w) pool.emplace_back(worker);
  {
    std::unique_lock lock(mutex);
    while (finished_workers < static_cast<int>(pool.size())) {
      progress.update(done_now, static_cast<int>(summary.failed.size()));
      // Wake at least once a second: the bar's rate and ETA move, and the 30 s line is due.
      changed.wait_for(lock, std::chrono::seconds(1));
    }
    if (!pool.empty()) progress.update(done_now, static_cast<int>(summary.failed.size()));
  }
  for (auto& t : pool) t.join();
  if (!pool.empty()) progress.finish();
  summary.done_now = done_now;
  summary.cancelled = cancelled(options.cancel);
  return summary;
}

}  // namespace gapflow
