#include "studies/store.hpp"

#include "studies/sqlite_statement.hpp"

#include <fmt/format.h>
#include <fmt/ranges.h>
#include <sqlite3.h>

#include <fcntl.h>
#include <sys/file.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <ostream>
#include <stdexcept>
#include <unistd.h>

#include "gapflow_code_version.h"  // generated at every build (studies/CMakeLists.txt)

namespace gapflow {

const char* code_version() { return GAPFLOW_CODE_VERSION; }

namespace {

using sqlite::exec;
using sqlite::fail;
using sqlite::has_column;
using sqlite::has_table;
using sqlite::Statement;
using sqlite::Transaction;

constexpr int kSchemaVersion = 1;

// Column order of `runs` after the identity columns is the order put() binds.
constexpr const char* kSchema = R"sql(
CREATE TABLE IF NOT EXISTS runs (
  job_key TEXT PRIMARY KEY,
  study TEXT NOT NULL, series TEXT NOT NULL, point INTEGER NOT NULL, point_label TEXT NOT NULL,
  axes_json TEXT NOT NULL, model TEXT NOT NULL, replicate INTEGER NOT NULL,
  base_seed INTEGER NOT NULL, run_seed TEXT NOT NULL, scenario_hash TEXT NOT NULL,
  scenario_name TEXT NOT NULL, code_version TEXT NOT NULL,
  particles INTEGER NOT NULL, passed INTEGER NOT NULL, reinjected INTEGER NOT NULL,
  perturbations INTEGER NOT NULL, escaped INTEGER NOT NULL,
  max_conservation_error INTEGER NOT NULL,
  sim_time_s REAL NOT NULL, wall_time_s REAL NOT NULL, end_reason TEXT NOT NULL, regime TEXT NOT NULL,
  j_paper REAL, j_flowing REAL, j_mid REAL, j_paper_star REAL, j_flowing_star REAL,
  diameter_m REAL NOT NULL, gap_m REAL NOT NULL, distance_m REAL NOT NULL, w_over_d REAL NOT NULL,
  d_over_d REAL NOT NULL,  -- D/d: obstruction distance over the nominal diameter
  incline_rad REAL NOT NULL, time_step_s REAL NOT NULL,
  n_clogs INTEGER NOT NULL, n_avalanches INTEGER NOT NULL,
  finished_at TEXT NOT NULL
);
CREATE TABLE IF NOT EXISTS crossings (
  job_key TEXT NOT NULL REFERENCES runs(job_key), id INTEGER NOT NULL, t_s REAL NOT NULL, x_m REAL NOT NULL
);
-- A particle may cross more than once (protocol.reinject_passed): rows keep the record's order by rowid.
CREATE INDEX IF NOT EXISTS crossings_job ON crossings (job_key);
CREATE TABLE IF NOT EXISTS avalanches (
  job_key TEXT NOT NULL REFERENCES runs(job_key), idx INTEGER NOT NULL, size INTEGER NOT NULL,
  t_start_s REAL NOT NULL, t_end_s REAL NOT NULL, "first" INTEGER NOT NULL, censored INTEGER NOT NULL,
  PRIMARY KEY (job_key, idx)
);
CREATE TABLE IF NOT EXISTS clogs (
  job_key TEXT NOT NULL REFERENCES runs(job_key), idx INTEGER NOT NULL, t_start_s REAL NOT NULL,
  duration_s REAL NOT NULL, censored INTEGER NOT NULL, front_m REAL, on_obstruction INTEGER,
  PRIMARY KEY (job_key, idx)
);
)sql";

// Added to schema version 1 later (Clog::front_m, then Clog::on_obstruction): a store
// written before gets the columns when it is next written to; its older clogs read back
// without them (NULL).
struct AddedColumn {
  const char* name;
  const char* definition;
};
constexpr AddedColumn kAddedClogColumns[] = {{"front_m", "REAL"}, {"on_obstruction", "INTEGER"}};

// Added to schema version 1 later: created when first written, so older stores stay readable.
constexpr const char* kStudyFilesSchema = R"sql(
CREATE TABLE IF NOT EXISTS study_files (
  study TEXT PRIMARY KEY, source TEXT NOT NULL, text TEXT NOT NULL, recorded_at TEXT NOT NULL
);
)sql";

std::string hex(std::uint64_t v) { return fmt::format("{:016x}", v); }
std::uint64_t from_hex(const std::string& s) { return std::stoull(s, nullptr, 16); }

template <class E>
E parse_enum(const std::string& text, std::initializer_list<E> all) {
  for (E e : all)
    if (text == to_string(e)) return e;
  throw std::runtime_error("results store: unknown value '" + text + "'");
}

void insert_children(sqlite3* db, const std::string& key, const RunRecord& r) {
  Statement c(db, "INSERT INTO crossings (job_key, id, t_s, x_m) VALUES (?, ?, ?, ?)");
  for (const Crossing& x : r.crossings) c.bind_all(key, x.id, x.t, x.x).run();
  Statement a(db, "INSERT INTO avalanches (job_key, idx, size, t_start_s, t_end_s, \"first\", censored) "
                  "VALUES (?, ?, ?, ?, ?, ?, ?)");
  for (std::size_t i = 0; i < r.avalanches.size(); ++i) {
    const Avalanche& v = r.avalanches[i];
    a.bind_all(key, static_cast<int>(i), v.size, v.t_start, v.t_end, v.first, v.censored).run();
  }
  for (const AddedColumn& c : kAddedClogColumns)
    if (!has_column(db, "clogs", c.name)) exec(db, fmt::format("ALTER TABLE clogs ADD COLUMN {} {}", c.name, c.definition).c_str());
  Statement k(db, "INSERT INTO clogs (job_key, idx, t_start_s, duration_s, censored, front_m, on_obstruction) "
                  "VALUES (?, ?, ?, ?, ?, ?, ?)");
  for (std::size_t i = 0; i < r.clogs.size(); ++i) {
    const Clog& v = r.clogs[i];
    k.bind_all(key, static_cast<int>(i), v.t_start, v.duration, v.censored, v.front_m, v.on_obstruction).run();
  }
}

// One run and its child rows (inside the caller's transaction). finished_at: now when empty.
void insert_run(sqlite3* db, const JobIdentity& id, const RunRecord& r, const std::string& version,
                const std::optional<std::string>& finished_at) {
  Statement s(db, R"sql(INSERT INTO runs (
      job_key, study, series, point, point_label, axes_json, model, replicate, base_seed, run_seed,
      scenario_hash, scenario_name, code_version, particles, passed, reinjected, perturbations, escaped,
      max_conservation_error, sim_time_s, wall_time_s, end_reason, regime, j_paper, j_flowing, j_mid, j_paper_star,
      j_flowing_star,
      diameter_m, gap_m, distance_m, w_over_d, d_over_d, incline_rad, time_step_s, n_clogs, n_avalanches,
      finished_at)
    VALUES (?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?,
            coalesce(?38, strftime('%Y-%m-%dT%H:%M:%fZ', 'now'))))sql");
  // SQLite integers are signed 64-bit: the seed's bits are kept (a seed >= 2^63 reads back unchanged via the cast).
  s.bind_all(id.key, id.study, id.series, id.point, id.point_label, id.axes_json, id.model, id.replicate,
             static_cast<std::int64_t>(id.base_seed), hex(id.run_seed), hex(id.scenario_hash), r.scenario_name,
             version, r.particles, r.passed, r.reinjected, r.perturbations, r.escaped, r.max_conservation_error, r.sim_time_s,
             r.wall_time_s, std::string(to_string(r.end_reason)), std::string(to_string(r.regime)), r.j_paper,
             r.j_flowing, r.j_mid, r.j_paper_star(), r.j_flowing_star(), r.diameter_m, r.gap_m, r.distance_m,
             r.gap_m / r.diameter_m, r.distance_m / r.diameter_m, r.incline_rad, r.time_step_s,
             static_cast<int>(r.clogs.size()), static_cast<int>(r.avalanches.size()), finished_at);
  s.run();
  insert_children(db, id.key, r);
}

// Added to schema version 1 for clusters (studies/merge.hpp): where each run was made, and the job
// list of a sharded study. Created when first written, so older stores stay readable.
constexpr const char* kClusterSchema = R"sql(
CREATE TABLE IF NOT EXISTS provenance (
  job_key TEXT PRIMARY KEY, shard TEXT NOT NULL, host TEXT NOT NULL, code_version TEXT NOT NULL,
  merged_from TEXT NOT NULL, recorded_at TEXT NOT NULL
);
CREATE TABLE IF NOT EXISTS plan (
  job_key TEXT PRIMARY KEY, shard TEXT NOT NULL, study TEXT NOT NULL, series TEXT NOT NULL, point INTEGER NOT NULL,
  point_label TEXT NOT NULL, model TEXT NOT NULL, replicate INTEGER NOT NULL, expected_cost REAL NOT NULL
);
)sql";

void write_provenance(sqlite3* db, const std::string& key, const Provenance& p) {
  exec(db, kClusterSchema);
  Statement s(db, "INSERT OR REPLACE INTO provenance (job_key, shard, host, code_version, merged_from, recorded_at) "
                  "VALUES (?, ?, ?, ?, ?, strftime('%Y-%m-%dT%H:%M:%SZ', 'now'))");
  s.bind_all(key, p.shard, p.host, p.code_version, p.merged_from).run();
}

std::string host_name() {
  char name[256] = {};
  if (gethostname(name, sizeof name - 1) != 0) return "?";
  return name;
}

// The clog columns to select: an added column a store does not have yet reads as NULL.
std::string clog_columns(sqlite3* db) {
  std::string columns = "t_start_s, duration_s, censored";
  for (const AddedColumn& c : kAddedClogColumns) columns += has_column(db, "clogs", c.name) ? fmt::format(", {}", c.name) : ", NULL";
  return columns;
}

void load_children(sqlite3* db, const std::string& key, const std::string& clog_columns, RunRecord& r) {
  Statement c(db, "SELECT id, t_s, x_m FROM crossings WHERE job_key = ? ORDER BY rowid");
  c.bind(1, key);
  while (c.step()) r.crossings.push_back({c.integer(0), c.real(1), c.real(2)});
  Statement a(db, "SELECT size, t_start_s, t_end_s, \"first\", censored FROM avalanches WHERE job_key = ? ORDER BY idx");
  a.bind(1, key);
  while (a.step()) r.avalanches.push_back({a.integer(0), a.real(1), a.real(2), a.integer(3) != 0, a.integer(4) != 0});
  Statement k(db, fmt::format("SELECT {} FROM clogs WHERE job_key = ? ORDER BY idx", clog_columns).c_str());
  k.bind(1, key);
  while (k.step()) r.clogs.push_back({k.real(0), k.real(1), k.integer(2) != 0, k.optional_real(3), k.optional_bool(4)});
}

// One CSV field (RFC 4180 quoting).
std::string csv_field(const Statement& s, int c) {
  switch (s.type(c)) {
    case SQLITE_NULL: return "";
    case SQLITE_INTEGER: return std::to_string(s.int64(c));
    case SQLITE_FLOAT: return fmt::format("{}", s.real(c));  // shortest text that reads back exactly
    default: break;
  }
  std::string v = s.text(c);
  if (v.find_first_of(",\"\r\n") == std::string::npos) return v;
  std::string q = "\"";
  for (char ch : v) q += ch == '"' ? std::string("\"\"") : std::string(1, ch);
  return q + "\"";
}

}  // namespace

// "<store>.lock", flock'ed while a study writes: advisory, released by the kernel when
// the process dies (kill -9 included), so it never needs cleaning up by hand.
class Store::WriterLock {
 public:
  explicit WriterLock(const std::filesystem::path& store) : path_(store.string() + ".lock") {
    for (;;) {  // retry if another process removed the file between our open and our flock
      fd_ = ::open(path_.c_str(), O_RDWR | O_CREAT | O_CLOEXEC, 0644);
      if (fd_ < 0)
        throw std::runtime_error(fmt::format("results store: cannot create the lock file {}: {}", path_.string(),
                                             std::strerror(errno)));
      if (::flock(fd_, LOCK_EX | LOCK_NB) != 0) {
        const int e = errno;
        std::string holder = holder_pid();
        ::close(fd_);
        if (e == EWOULDBLOCK)
          throw StoreError(fmt::format("results store {} is being written by another gapflow study{} (lock {}): "
                                       "wait for it to finish, or give this one another --db",
                                       store.string(), holder, path_.string()));
        throw std::runtime_error(fmt::format("results store: cannot lock {}: {}", path_.string(), std::strerror(e)));
      }
      struct stat held {}, named {};
      if (::fstat(fd_, &held) == 0 && ::stat(path_.c_str(), &named) == 0 && held.st_ino == named.st_ino &&
          held.st_dev == named.st_dev)
        break;
      ::close(fd_);
    }
    const std::string pid = std::to_string(::getpid()) + "\n";
    if (::ftruncate(fd_, 0) == 0 && ::write(fd_, pid.data(), pid.size()) < 0) {
      // The pid is only for the other process's message; the lock holds without it.
    }
  }
  ~WriterLock() {
    ::unlink(path_.c_str());  // while still locked: a waiting opener sees a new inode and retries
    ::close(fd_);
  }

 private:
  std::string holder_pid() const {
    char buf[32] = {};
    const ssize_t n = ::pread(fd_, buf, sizeof buf - 1, 0);
    if (n <= 0) return "";
    std::string pid(buf, static_cast<std::size_t>(n));
    pid.erase(pid.find_last_not_of(" \n") + 1);
    return pid.empty() ? "" : " (process " + pid + ")";
  }
  std::filesystem::path path_;
  int fd_ = -1;
};

namespace {

// What is at `file`, checked before SQLite sees it: SQLite would silently turn an empty
// file into an empty store, and call a text file "file is not a database" without naming it.
// True if the file exists (and looks like a SQLite database).
bool check_store_file(const std::filesystem::path& file) {
  struct stat st {};
  if (::stat(file.c_str(), &st) != 0) {
    if (errno == ENOENT) return false;
    throw StoreError(fmt::format("results store {}: {}", file.string(), std::strerror(errno)));
  }
  if (S_ISDIR(st.st_mode)) throw StoreError(fmt::format("results store {} is a directory, not a SQLite file", file.string()));
  if (!S_ISREG(st.st_mode)) throw StoreError(fmt::format("results store {} is not a regular file", file.string()));
  if (st.st_size == 0)
    throw StoreError(fmt::format("results store {} is empty (0 bytes), not a results store: remove it or give "
                                 "another path",
                                 file.string()));
  static constexpr char kMagic[16] = {'S', 'Q', 'L', 'i', 't', 'e', ' ', 'f', 'o', 'r', 'm', 'a', 't', ' ', '3', '\0'};
  char head[16] = {};
  std::FILE* f = std::fopen(file.c_str(), "rb");
  if (!f) throw StoreError(fmt::format("results store {}: {}", file.string(), std::strerror(errno)));
  const std::size_t n = std::fread(head, 1, sizeof head, f);
  std::fclose(f);
  if (n != sizeof head || std::memcmp(head, kMagic, sizeof head) != 0)
    throw StoreError(fmt::format("results store {} is not a SQLite database (its first bytes are not "
                                 "'SQLite format 3'): not a results store, or damaged",
                                 file.string()));
  return true;
}

sqlite3* open_sqlite(const std::string& name, int flags) {
  sqlite3* db = nullptr;
  if (sqlite3_open_v2(name.c_str(), &db, flags, nullptr) != SQLITE_OK) {
    std::string msg = db ? sqlite3_errmsg(db) : "out of memory";
    sqlite3_close(db);
    throw StoreError(fmt::format("results store: cannot open {}: {}", name, msg));
  }
  return db;
}

int schema_version(sqlite3* db) {
  Statement v(db, "PRAGMA user_version");
  v.step();
  return v.integer(0);
}

// Read-only: a WAL store on a read-only folder without its -shm file cannot be opened
// normally; a store that was closed cleanly has no -wal to replay, so it is immutable.
sqlite3* open_read_only(const std::filesystem::path& file) {
  sqlite3* db = open_sqlite(file.string(), SQLITE_OPEN_READONLY);
  if (sqlite3_exec(db, "SELECT count(*) FROM sqlite_master", nullptr, nullptr, nullptr) == SQLITE_OK) return db;
  const int code = sqlite3_errcode(db) & 0xff;
  if (code != SQLITE_CANTOPEN && code != SQLITE_READONLY) {
    const std::string why = fmt::format("results store {} is damaged or not a results store: {}", file.string(),
                                        sqlite3_errmsg(db));
    sqlite3_close(db);
    throw StoreError(why);
  }
  sqlite3_close(db);
  std::error_code ec;
  if (std::filesystem::exists(file.string() + "-wal", ec))
    throw StoreError(fmt::format("results store {} is read-only and has unfinished writes ({}-wal): open it once "
                                 "where it is writable",
                                 file.string(), file.string()));
  const std::string uri = "file:" + std::filesystem::absolute(file).string() + "?immutable=1";
  db = open_sqlite(uri, SQLITE_OPEN_READONLY | SQLITE_OPEN_URI);
  if (sqlite3_exec(db, "SELECT count(*) FROM sqlite_master", nullptr, nullptr, nullptr) != SQLITE_OK) {
    const std::string why = fmt::format("results store {} is damaged or not a results store: {}", file.string(),
                                        sqlite3_errmsg(db));
    sqlite3_close(db);
    throw StoreError(why);
  }
  return db;
}

}  // namespace

Store::Store(const std::filesystem::path& file, StoreAccess access) {
  try {
    open(file, access);
  } catch (...) {
    sqlite3_close(db_);  // the destructor does not run when a constructor throws
    db_ = nullptr;
    throw;
  }
}

void Store::open(const std::filesystem::path& file, StoreAccess access) {
  const bool exists = check_store_file(file);
  if (access == StoreAccess::read) {
    if (!exists) throw StoreError(fmt::format("no results store at {}: no such file", file.string()));
    db_ = open_read_only(file);
    exec(db_, "PRAGMA query_only = ON");
    const int version = schema_version(db_);
    if (version != kSchemaVersion || !has_table(db_, "runs"))
      throw StoreError(fmt::format("{} is a SQLite database but not a results store (schema version {}, "
                                   "this build reads {})",
                                   file.string(), version, kSchemaVersion));
    return;
  }
  if (file.has_parent_path()) {
    std::error_code ec;
    std::filesystem::create_directories(file.parent_path(), ec);
    if (ec) throw StoreError(fmt::format("results store {}: cannot create its folder: {}", file.string(), ec.message()));
  }
  if (access == StoreAccess::exclusive) lock_ = std::make_unique<WriterLock>(file);
  db_ = open_sqlite(file.string(), SQLITE_OPEN_READWRITE | SQLITE_OPEN_CREATE);
  // Another process (an export, a report, a test polling) may hold the lock briefly.
  sqlite3_busy_timeout(db_, 10000);
  exec(db_, "PRAGMA journal_mode = WAL");
  exec(db_, "PRAGMA synchronous = NORMAL");  // WAL + NORMAL: a committed run survives a killed process
  exec(db_, "PRAGMA foreign_keys = ON");
  const int version = schema_version(db_);
  if (version != 0 && version != kSchemaVersion)
    throw StoreError(fmt::format("results store {}: schema version {}, this build reads {}", file.string(), version,
                                 kSchemaVersion));
  if (version == 0 && exists) {  // an existing SQLite file that is not ours
    Statement any(db_, "SELECT count(*) FROM sqlite_master");
    any.step();
    if (any.int64(0) > 0)
      throw StoreError(fmt::format("{} is a SQLite database but not a results store: gapflow will not add its "
                                   "tables to it",
                                   file.string()));
  }
  if (version == 0) {  // new file: created once, so that readers of an existing store never need the write lock
    Transaction tx(db_);
    exec(db_, kSchema);
    exec(db_, fmt::format("PRAGMA user_version = {}", kSchemaVersion).c_str());
    tx.commit();
  }
}

Store::~Store() {
  sqlite3_close(db_);
  lock_.reset();  // after the connection: the next writer must find the store closed
}

const std::vector<std::string>& Store::tables() {
  static const std::vector<std::string> names{"runs",        "crossings",  "avalanches", "clogs",
                                              "study_files", "provenance", "plan"};
  return names;
}

std::set<std::string> Store::keys() const {
  std::lock_guard lock(mutex_);
  std::set<std::string> out;
  Statement s(db_, "SELECT job_key FROM runs");
  while (s.step()) out.insert(s.text(0));
  return out;
}

bool Store::has(const std::string& key) const {
  std::lock_guard lock(mutex_);
  Statement s(db_, "SELECT 1 FROM runs WHERE job_key = ?");
  s.bind(1, key);
  return s.step();
}

std::size_t Store::count() const {
  std::lock_guard lock(mutex_);
  Statement s(db_, "SELECT count(*) FROM runs");
  s.step();
  return static_cast<std::size_t>(s.int64(0));
}

void Store::put(const JobIdentity& id, const RunRecord& r) {
  std::lock_guard lock(mutex_);
  Transaction tx(db_);
  insert_run(db_, id, r, code_version(), std::nullopt);
  write_provenance(db_, id.key, {shard_, host_name(), code_version(), ""});
  tx.commit();
}

std::vector<StoredRun> Store::load(const std::optional<std::string>& study) const {
  return select_runs("?1 IS NULL OR study = ?1", study);
}

std::optional<StoredRun> Store::load_run(const std::string& key) const {
  std::vector<StoredRun> runs = select_runs("job_key = ?1", key);
  if (runs.empty()) return std::nullopt;
  return std::move(runs.front());
}

std::vector<StoredRun> Store::select_runs(const char* where, const std::optional<std::string>& arg) const {
  std::lock_guard lock(mutex_);
  const std::string sql = fmt::format(R"sql(SELECT
      job_key, study, series, point, point_label, axes_json, model, replicate, base_seed, run_seed,
      scenario_hash, scenario_name, code_version, particles, passed, reinjected, perturbations, escaped,
      max_conservation_error, sim_time_s, wall_time_s, end_reason, regime, j_paper, j_flowing, j_mid,
      diameter_m, gap_m, distance_m, incline_rad, time_step_s, finished_at
    FROM runs WHERE {} ORDER BY job_key)sql", where);
  Statement s(db_, sql.c_str());
  if (arg) s.bind(1, *arg);
  std::vector<StoredRun> out;
  while (s.step()) {
    StoredRun run;
    JobIdentity& id = run.id;
    RunRecord& r = run.record;
    int c = 0;
    id.key = s.text(c++), id.study = s.text(c++), id.series = s.text(c++), id.point = s.integer(c++);
    id.point_label = s.text(c++), id.axes_json = s.text(c++), id.model = s.text(c++);
    id.replicate = s.integer(c++), id.base_seed = static_cast<std::uint64_t>(s.int64(c++));
    id.run_seed = from_hex(s.text(c++)), id.scenario_hash = from_hex(s.text(c++));
    r.model = id.model, r.replicate = id.replicate, r.base_seed = id.base_seed;
    r.run_seed = id.run_seed, r.scenario_hash = id.scenario_hash;
    r.scenario_name = s.text(c++), run.code_version = s.text(c++);
    r.particles = s.integer(c++), r.passed = s.integer(c++), r.reinjected = s.integer(c++);
    r.perturbations = s.integer(c++), r.escaped = s.integer(c++);
    r.max_conservation_error = s.integer(c++), r.sim_time_s = s.real(c++), r.wall_time_s = s.real(c++);
    r.end_reason = parse_enum(s.text(c++), {EndReason::all_passed, EndReason::n_passed, EndReason::time_limit,
                                            EndReason::permanent_clog});
    r.regime = parse_enum(s.text(c++), {Regime::continuous, Regime::intermittent, Regime::clogged});
    r.j_paper = s.optional_real(c++), r.j_flowing = s.optional_real(c++), r.j_mid = s.optional_real(c++);
    r.diameter_m = s.real(c++), r.gap_m = s.real(c++), r.distance_m = s.real(c++);
    r.incline_rad = s.real(c++), r.time_step_s = s.real(c++), run.finished_at = s.text(c++);
    out.push_back(std::move(run));
  }
  const std::string columns = clog_columns(db_);
  for (StoredRun& run : out) load_children(db_, run.id.key, columns, run.record);
  return out;
}

void Store::import_runs(const std::vector<StoredRun>& runs, const std::vector<Provenance>& provenance) {
  if (runs.size() != provenance.size()) throw std::logic_error("import_runs: one provenance per run");
  std::lock_guard lock(mutex_);
  Transaction tx(db_);
  for (std::size_t i = 0; i < runs.size(); ++i) {
    const std::string& finished = runs[i].finished_at;
    insert_run(db_, runs[i].id, runs[i].record, runs[i].code_version,
               finished.empty() ? std::nullopt : std::optional<std::string>(finished));
    write_provenance(db_, runs[i].id.key, provenance[i]);
  }
  tx.commit();
}

std::map<std::string, Provenance> Store::provenance() const {
  std::lock_guard lock(mutex_);
  std::map<std::string, Provenance> out;
  if (!has_table(db_, "provenance")) return out;
  Statement s(db_, "SELECT job_key, shard, host, code_version, merged_from FROM provenance");
  while (s.step()) out[s.text(0)] = {s.text(1), s.text(2), s.text(3), s.text(4)};
  return out;
}

void Store::record_plan(const std::vector<PlannedJob>& plan) {
  std::lock_guard lock(mutex_);
  Transaction tx(db_);
  exec(db_, kClusterSchema);
  exec(db_, "DELETE FROM plan");
  Statement s(db_, "INSERT INTO plan (job_key, shard, study, series, point, point_label, model, replicate, "
                   "expected_cost) VALUES (?, ?, ?, ?, ?, ?, ?, ?, ?)");
  for (const PlannedJob& p : plan)
    s.bind_all(p.id.key, p.shard, p.id.study, p.id.series, p.id.point, p.id.point_label, p.id.model, p.id.replicate,
               p.expected_cost)
        .run();
  tx.commit();
}

std::vector<PlannedJob> Store::plan() const {
  std::lock_guard lock(mutex_);
  std::vector<PlannedJob> out;
  if (!has_table(db_, "plan")) return out;
  Statement s(db_, "SELECT job_key, shard, study, series, point, point_label, model, replicate, expected_cost "
                   "FROM plan ORDER BY job_key");
  while (s.step()) {
    PlannedJob p;
    p.id.key = s.text(0), p.shard = s.text(1), p.id.study = s.text(2), p.id.series = s.text(3);
    p.id.point = s.integer(4), p.id.point_label = s.text(5), p.id.model = s.text(6), p.id.replicate = s.integer(7);
    p.expected_cost = s.real(8);
    out.push_back(std::move(p));
  }
  return out;
}

void Store::record_study_file(const std::string& study, const std::string& source, const std::string& text) {
  std::lock_guard lock(mutex_);
  exec(db_, kStudyFilesSchema);
  Statement s(db_,
              "INSERT OR REPLACE INTO study_files (study, source, text, recorded_at) "
              "VALUES (?, ?, ?, strftime('%Y-%m-%dT%H:%M:%SZ', 'now'))");
  s.bind_all(study, source, text).run();
}

std::vector<StudyFileRecord> Store::study_files() const {
  std::lock_guard lock(mutex_);
  std::vector<StudyFileRecord> out;
  if (!has_table(db_, "study_files")) return out;  // a store written before the table existed
  Statement s(db_, "SELECT study, source, text, recorded_at FROM study_files ORDER BY study");
  while (s.step()) out.push_back({s.text(0), s.text(1), s.text(2), s.text(3)});
  return out;
}

void Store::export_csv(const std::string& table, std::ostream& out) const {
  const auto& names = tables();
  if (std::find(names.begin(), names.end(), table) == names.end())
    throw std::invalid_argument(
        fmt::format("table '{}' is not one of: {}", table, fmt::join(names, ", ")));
  std::lock_guard lock(mutex_);
  if (!has_table(db_, table))
    throw std::invalid_argument(fmt::format("this store has no table '{}' (written before it existed)", table));
  Statement s(db_, fmt::format("SELECT * FROM {} ORDER BY rowid", table).c_str());
  for (int c = 0; c < s.columns(); ++c) out << (c ? "," : "") << s.name(c);
  out << "\n";
  while (s.step()) {
    for (int c = 0; c < s.columns(); ++c) out << (c ? "," : "") << csv_field(s, c);
    out << "\n";
  }
}

}  // namespace gapflow
