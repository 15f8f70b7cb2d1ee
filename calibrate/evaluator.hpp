// The model side of a calibration: runs the data file's design points at given
// parameter values and turns the runs into the observable, on the fit scale.
//
// Every run is a study job (studies/jobs.hpp) with a stable key, stored in a
// SQLite store like a study's runs, so an interrupted calibration resumes for free
// and identical runs (same resolved scenario) are never simulated twice, even by
// another calibration sharing the store. Common random numbers: replicate r of
// every parameter set uses run.seed = seed, run.replicate = r, hence the same
// particle sizes and packing (per-particle streams, common/random.hpp), so a
// finite difference between two parameter values is not swamped by the packing.
#pragma once

#include "calibrate/data_file.hpp"
#include "models/registry.hpp"
#include "studies/runner.hpp"
#include "studies/store.hpp"

#include <atomic>
#include <cstdint>
#include <string>
#include <utility>
#include <vector>

namespace gapflow {

// Scenario key = value assignments on top of a point's scenario.
struct ParameterSet {
  std::vector<std::pair<std::string, double>> values;
  std::string label() const;  // "particles.friction_particle=0.3, particles.drag_per_s=2" ("template" if empty)
  std::vector<std::string> overrides() const;
  ParameterSet with(const std::string& key, double value) const;  // replaced or appended
  double get(const std::string& key, double fallback) const;
};

// The model's value at each design point.
struct Prediction {
  std::vector<double> value;                   // observable in its unit (mean over replicates / pooled)
  std::vector<double> fit;                     // value on the fit scale
  std::vector<double> se_fit;                  // standard error of `fit` (from the replicates)
  std::vector<std::vector<double>> replicate_fit;  // per replicate, on the fit scale (NaN where undefined)
  std::vector<bool> valid;                     // the observable exists in every replicate
};

// Turn one point's runs into the observable.
struct PointObservable {
  double value = 0, fit = 0, se_fit = 0;
  std::vector<double> replicate_fit;
  bool valid = false;
};
PointObservable observe(ObservableKind kind, FitScale scale, const std::vector<RunRecord>& runs);

struct EvaluatorOptions {
  ModelKind model = ModelKind::box2d;
  JobRunner runner;  // empty: run_jobs on `workers` threads; an MPI job passes rank 0's (studies/mpi_runner.hpp)
  int workers = 1;
  const std::atomic<bool>* cancel = nullptr;
  std::ostream* progress = nullptr;
  bool tty = false;
};

class Evaluator {
 public:
  Evaluator(const DataFile& data, Store& store, EvaluatorOptions options);

  // Every point for every set, all runs in one worker pool. `seed` is run.seed
  // (the data file's for the fit; another for fresh-seed checks and twins). `only`,
  // when not empty, names the points to simulate (one flag per point); the others get
  // no runs and an invalid prediction. Throws RunCancelled when cancelled (what is
  // stored stays stored).
  std::vector<Prediction> evaluate(const std::vector<ParameterSet>& sets, std::uint64_t seed, int replicates,
                                   const std::vector<bool>& only = {});
  std::vector<Prediction> evaluate(const std::vector<ParameterSet>& sets) {
    return evaluate(sets, data_.seed, data_.model_replicates);
  }

  int runs_simulated() const { return simulated_; }  // by this process
  int runs_reused() const { return reused_; }        // found in the store
  double run_seconds() const { return run_seconds_; }// wall seconds of the runs, summed over runs (~CPU s)

 private:
  const DataFile& data_;
  Store& store_;
  EvaluatorOptions options_;
  int simulated_ = 0, reused_ = 0;
  double run_seconds_ = 0;
};

}  // namespace gapflow
