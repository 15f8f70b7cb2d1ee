// The results store of a study: one SQLite file (WAL mode).
//
//   runs        one row per finished job (identity + every scalar of RunRecord)
//   crossings   (job_key, id, t_s, x_m)                       per crossing
//   avalanches  (job_key, idx, size, t_start_s, t_end_s, first, censored)
//   clogs       (job_key, idx, t_start_s, duration_s, censored)
//
//   study_files (study, source, text, recorded_at)            the study file as run
//   provenance  (job_key, shard, host, code_version, merged_from, recorded_at)   where a run was made
//   plan        (job_key, shard, study, series, point, ...)    the job list of a sharded study
//
// A run and its child rows are written in one transaction: after a crash or
// kill -9 a job is either completely stored or absent, so resuming = running
// the jobs whose key is not in `runs`. Safe to call from several threads (one
// connection behind a mutex; writes are tiny next to a simulation).
#pragma once

#include "common/run_record.hpp"
#include "studies/jobs.hpp"

#include <filesystem>
#include <iosfwd>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <set>
#include <stdexcept>
#include <string>
#include <vector>

struct sqlite3;

namespace gapflow {

struct StoredRun {
  JobIdentity id;
  RunRecord record;  // rebuilt completely, child rows included
  std::string code_version;
  std::string finished_at;  // UTC, ISO 8601
};

// The study file a study was run from, kept in its store so that `gapflow report`
// reads the [report] settings (baseline, analyses, J kind) the runs were made for.
struct StudyFileRecord {
  std::string study;        // the study's name
  std::string source;       // the path it was read from
  std::string text;         // its whole text
  std::string recorded_at;  // UTC, ISO 8601
};

// Where a run was made (the provenance table): kept through merges.
struct Provenance {
  std::string shard;         // "2/8" for share 2 of 8; "" for a whole-study run; "rank N" in an MPI job
  std::string host;          // gethostname() of the machine that simulated it
  std::string code_version;  // the build that simulated it
  std::string merged_from;   // the shard store it was merged from ("" where it was made)
};

// One job of a sharded plan (the plan table): what a merge expects to find.
struct PlannedJob {
  JobIdentity id;
  std::string shard;         // "I/K"
  double expected_cost = 0;  // Job::expected_cost
};

// What this build writes into runs.code_version (git describe at configure time).
const char* code_version();

// A store that cannot be used as asked (bad input: exit 2): not a SQLite file, empty,
// damaged, a directory, or being written by another study. what() names the file.
class StoreError : public std::invalid_argument {
 public:
  using std::invalid_argument::invalid_argument;
};

// How a Store is opened: the one open path for every command.
//   read       never creates or changes anything (report, export, --dry-run); works on
//              stores shared read-only (a cluster's project folder, a published data set)
//   write      open or create (with its folder); the schema is created when missing
//   exclusive  write, and hold "<file>.lock" (flock) while open: a second study on the
//              same store refuses at start instead of running every job twice
enum class StoreAccess { read, write, exclusive };

class Store {
 public:
  // Throws StoreError when the file is not a usable store (see StoreAccess).
  explicit Store(const std::filesystem::path& file, StoreAccess access = StoreAccess::write);
  ~Store();
  Store(const Store&) = delete;
  Store& operator=(const Store&) = delete;

  std::set<std::string> keys() const;  // job keys of every stored run
  bool has(const std::string& key) const;
  std::size_t count() const;

  // Store one finished run in one transaction. Throws if the key is already stored.
  void put(const JobIdentity& id, const RunRecord& record);

  // Which shard this store's put() records in `provenance` ("" = a whole-study run).
  void set_shard(const std::string& shard) { shard_ = shard; }
  // Store runs made elsewhere (a merge, an MPI rank): their code version and finish time (now when
  // empty) are kept. Runs and provenance go in one transaction; the keys must not be stored yet.
  void import_runs(const std::vector<StoredRun>& runs, const std::vector<Provenance>& provenance);
  // Provenance of every run that has one (runs written before the table existed have none).
  std::map<std::string, Provenance> provenance() const;
  // The job list of a sharded study (every share's jobs, not only this store's); replaces what was there.
  void record_plan(const std::vector<PlannedJob>& plan);
  std::vector<PlannedJob> plan() const;  // by job key; empty when none was recorded

  // Every stored run (of one study, when given), in job-key order.
  std::vector<StoredRun> load(const std::optional<std::string>& study = std::nullopt) const;
  // One stored run by job key (a merge compares runs of one key without loading the whole store).
  std::optional<StoredRun> load_run(const std::string& key) const;

  // Keep (or replace) the study file of `study`: the last one run is the one recorded.
  void record_study_file(const std::string& study, const std::string& source, const std::string& text);
  std::vector<StudyFileRecord> study_files() const;  // by study name

  // One table as CSV (header row; NULL = empty field; reals round-trip exactly).
  void export_csv(const std::string& table, std::ostream& out) const;
  static const std::vector<std::string>& tables();  // runs, crossings, avalanches, clogs, study_files, provenance, plan

 private:
  std::vector<StoredRun> select_runs(const char* where, const std::optional<std::string>& arg) const;
  void open(const std::filesystem::path& file, StoreAccess access);
  class WriterLock;
  std::unique_ptr<WriterLock> lock_;  // held while open with StoreAccess::exclusive
  sqlite3* db_ = nullptr;
  mutable std::mutex mutex_;
  std::string shard_;
};

}  // namespace gapflow
