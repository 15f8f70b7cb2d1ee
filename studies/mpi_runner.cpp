#include "studies/mpi_runner.hpp"

#include "studies/record_pack.hpp"

#include <fmt/format.h>

#include <stdexcept>

#ifdef GAPFLOW_HAVE_MPI
#include <mpi.h>

#include <chrono>
#include <map>
#include <ostream>
#include <thread>
#endif

namespace gapflow {

#ifndef GAPFLOW_HAVE_MPI

bool mpi_available() { return false; }
MpiSession::MpiSession() {
  throw std::invalid_argument(
      "--mpi: this gapflow was built without MPI (CMake found none, or GAPFLOW_WITH_MPI=OFF): install libopenmpi-dev and openmpi-bin "
      "(scripts/setup.sh) and rebuild, or run the study with --shard I/K or `gapflow slurm`");
}
MpiSession::~MpiSession() = default;
int MpiSession::worker_loop(const std::atomic<bool>*) { return 0; }
RunnerSummary MpiSession::run_jobs(const std::vector<Job>&, Store&, const RunnerOptions&) { return {}; }

#else

bool mpi_available() { return true; }

namespace {

enum Tag : int { kJob = 1, kStop = 2, kResult = 3, kFailed = 4, kCancelled = 5 };
constexpr char kSep = '\0';

// A job on the wire: what a worker needs to run it (the key is checked against the scenario's hash).
std::string pack_job(const Job& j) {
  std::string s = fmt::format("{}{}{:016x}{}{}{}{}", j.id.key, kSep, j.id.scenario_hash, kSep,
                              model_key_id(j.model), kSep, j.scenario.string());
  for (const std::string& o : j.overrides) s += kSep + o;
  return s;
}

Job unpack_job(const std::string& bytes) {
  std::vector<std::string> parts(1);
  for (char c : bytes) {
    if (c == kSep) parts.emplace_back();
    else parts.back().push_back(c);
  }
  if (parts.size() < 4) throw std::runtime_error("mpi: damaged job message");
  Job j;
  j.id.key = parts[0];
  j.id.scenario_hash = std::stoull(parts[1], nullptr, 16);
  j.model = std::stoull(parts[2]) == model_key_id(ModelKind::bullet) ? ModelKind::bullet : ModelKind::box2d;
  j.scenario = parts[3];
  j.overrides.assign(parts.begin() + 4, parts.end());
  return j;
}

void send(const std::string& bytes, int to, Tag tag) {
  MPI_Send(bytes.data(), static_cast<int>(bytes.size()), MPI_CHAR, to, tag, MPI_COMM_WORLD);
}

struct Message {
  int source = 0;
  int tag = 0;
  std::string bytes;
};

// Wait for the next message without spinning a core (OpenMPI's blocking receive polls
// hard, and a rank that only hands out jobs must not take a simulating rank's core).
Message receive(int from) {
  int ready = 0;
  MPI_Status status;
  for (;;) {
    MPI_Iprobe(from, MPI_ANY_TAG, MPI_COMM_WORLD, &ready, &status);
    if (ready) break;
    std::this_thread::sleep_for(std::chrono::milliseconds(2));
  }
  int n = 0;
  MPI_Get_count(&status, MPI_CHAR, &n);
  Message m{status.MPI_SOURCE, status.MPI_TAG, std::string(static_cast<std::size_t>(n), '\0')};
  MPI_Recv(m.bytes.data(), n, MPI_CHAR, status.MPI_SOURCE, status.MPI_TAG, MPI_COMM_WORLD, MPI_STATUS_IGNORE);
  return m;
}

}  // namespace

MpiSession::MpiSession() {
  int initialized = 0;
  MPI_Initialized(&initialized);
  if (!initialized) MPI_Init(nullptr, nullptr);
  MPI_Comm_rank(MPI_COMM_WORLD, &rank_);
  MPI_Comm_size(MPI_COMM_WORLD, &size_);
  char name[MPI_MAX_PROCESSOR_NAME] = {};
  int length = 0;
  MPI_Get_processor_name(name, &length);
  host_.assign(name, static_cast<std::size_t>(length));
}

MpiSession::~MpiSession() {
  if (rank_ == 0)
    for (int r = 1; r < size_; ++r) send("", r, kStop);
  MPI_Finalize();
}

int MpiSession::worker_loop(const std::atomic<bool>* cancel) {
  int runs = 0;
  for (;;) {
    const Message m = receive(0);
    if (m.tag == kStop) return runs;
    const Job job = unpack_job(m.bytes);
    try {
      const RunRecord record = run_job(job, cancel);
      send(job.id.key + kSep + host_ + kSep + pack_record(record), 0, kResult);
      ++runs;
    } catch (const RunCancelled&) {
      send(job.id.key, 0, kCancelled);
    } catch (const std::exception& e) {
      send(job.id.key + kSep + e.what(), 0, kFailed);
    }
  }
}

RunnerSummary MpiSession::run_jobs(const std::vector<Job>& jobs, Store& store, const RunnerOptions& options) {
  if (size_ < 2)
    throw std::invalid_argument("--mpi needs at least 2 ranks (rank 0 hands out jobs, the others simulate): "
                                "mpirun -np 3 gapflow study ... --mpi");
  RunnerSummary summary;
  const std::vector<const Job*> todo = jobs_to_run(jobs, store, summary);
  auto cancelled = [&] { return options.cancel && options.cancel->load(); };

  std::size_t next = 0;
  std::map<int, const Job*> in_flight;  // rank -> its job
  auto hand_out = [&](int rank) {
    if (next >= todo.size() || cancelled()) return;
    in_flight[rank] = todo[next];
    send(pack_job(*todo[next++]), rank, kJob);
  };
  for (int r = 1; r < size_; ++r) hand_out(r);
  int last_tenth = -1;
  while (!in_flight.empty()) {
    const Message m = receive(MPI_ANY_SOURCE);
    auto it = in_flight.find(m.source);
    if (it == in_flight.end()) continue;  // not a reply to a job (cannot happen between stages)
    const Job& job = *it->second;
    in_flight.erase(it);
    const std::string payload = m.bytes.substr(std::min(m.bytes.size(), job.id.key.size() + 1));
    if (m.bytes.compare(0, job.id.key.size(), job.id.key) != 0) {
      summary.failed.push_back({job.id, fmt::format("rank {} answered for another job", m.source)});
    } else if (m.tag == kResult) {
      // Stored with the simulating rank's host as its provenance (put() would name rank 0's).
      const std::size_t host_end = payload.find(kSep);
      const std::string host = payload.substr(0, host_end);
      StoredRun run{job.id, unpack_record(payload.substr(std::min(host_end + 1, payload.size()))), code_version(), ""};
      store.import_runs({run}, {{fmt::format("mpi rank {}/{}", m.source, size_ - 1), host, code_version(), ""}});
      ++summary.done_now;
    } else if (m.tag == kFailed) {
      summary.failed.push_back({job.id, fmt::format("rank {}: {}", m.source, payload)});
      if (options.progress) *options.progress << fmt::format("failed: job {} on rank {}: {}\n", job.id.key, m.source, payload);
    }  // kCancelled: leaves no row, runs again on resume
    hand_out(m.source);
    const int done = summary.already_stored + summary.done_now;
    const int tenth = summary.total ? 10 * done / summary.total : 10;
    if (options.progress && tenth > last_tenth) {
      *options.progress << fmt::format("{}/{} runs ({} ranks simulating)\n", done, summary.total, size_ - 1)
                        << std::flush;
      last_tenth = tenth;
    }
  }
  summary.cancelled = cancelled();
  return summary;
}

#endif

}  // namespace gapflow
