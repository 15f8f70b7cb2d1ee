// A study as one MPI job: `mpirun -np N gapflow study STUDY.toml --mpi`.
//
// Rank 0 hands out jobs one at a time (by key, to whichever rank is free) and is the
// only rank that opens the store; ranks 1..N-1 simulate and send each finished run
// back as bytes (record_pack.hpp). Jobs already stored are skipped, so an MPI job
// that dies resumes like any study. Records are identical to a local run: each job is
// the same single-threaded, seeded simulation wherever it runs.
//
// Built only when CMake finds MPI (find_package(MPI)); otherwise mpi_available() is
// false and MpiSession throws std::invalid_argument saying so (exit 2).
#pragma once

#include "studies/jobs.hpp"
#include "studies/runner.hpp"
#include "studies/store.hpp"

#include <atomic>
#include <string>
#include <vector>

namespace gapflow {

bool mpi_available();

// MPI_Init .. MPI_Finalize. Rank 0's destructor releases the workers (they leave worker_loop).
class MpiSession {
 public:
  MpiSession();
  ~MpiSession();
  MpiSession(const MpiSession&) = delete;
  MpiSession& operator=(const MpiSession&) = delete;

  int rank() const { return rank_; }
  int size() const { return size_; }

  // Ranks >= 1: simulate the jobs rank 0 sends until it releases them. Returns the number run.
  int worker_loop(const std::atomic<bool>* cancel);

  // Rank 0: run `jobs` on the other ranks into `store` (jobs already stored are skipped).
  // Needs at least 2 ranks. Progress lines go to options.progress.
  RunnerSummary run_jobs(const std::vector<Job>& jobs, Store& store, const RunnerOptions& options);

 private:
  int rank_ = 0;
  int size_ = 1;
  std::string host_;  // MPI_Get_processor_name: where this rank simulates
};

}  // namespace gapflow
