// The study runner: a pool of worker threads takes jobs in order, runs each
// (single-threaded, deterministic from its seed) and stores it on completion.
// Jobs already in the store are skipped, so running again resumes. Raising the
// cancel flag abandons the runs in flight (they leave no row) and stops.
#pragma once

#include "studies/jobs.hpp"
#include "studies/store.hpp"

#include <atomic>
#include <functional>
#include <iosfwd>
#include <string>
#include <vector>

namespace gapflow {

struct RunnerOptions {
  int workers = 1;
  const std::atomic<bool>* cancel = nullptr;  // e.g. raised by SIGINT
  std::ostream* progress = nullptr;           // progress and failures; nullptr = silent
  bool tty = false;                           // redraw a bar in place (else a line every ~10 % or 30 s)
  // Runs one job; the default compiles the job's scenario and calls run_model. Tests replace it.
  std::function<RunRecord(const Job&, const std::atomic<bool>* cancel)> run;
};

struct FailedJob {
  JobIdentity id;
  std::string error;
};

struct RunnerSummary {
  int total = 0;           // jobs in the study
  int already_stored = 0;  // skipped (resume)
  int done_now = 0;        // run and stored by this call
  std::vector<FailedJob> failed;
  bool cancelled = false;
};

RunnerSummary run_jobs(const std::vector<Job>& jobs, Store& store, const RunnerOptions& options);

// Something that runs the jobs a store lacks into it: run_jobs, or an MPI job's rank 0
// (studies/mpi_runner.hpp). Studies and calibrations take either.
using JobRunner = std::function<RunnerSummary(const std::vector<Job>&, Store&, const RunnerOptions&)>;

// The jobs not yet in the store (resume), in order; sets summary.total and summary.already_stored.
std::vector<const Job*> jobs_to_run(const std::vector<Job>& jobs, const Store& store, RunnerSummary& summary);

// Run one job the default way: compile its scenario (checking it still hashes to the job's key) and
// run its model. What run_jobs does without RunnerOptions::run; MPI workers call it too.
RunRecord run_job(const Job& job, const std::atomic<bool>* cancel);

// "12 runs/min" progress text helpers (also used by the dry run).
std::string format_duration(double seconds);

}  // namespace gapflow
