// Report snapshots: one top view per point class of a study report, next to its plots
// (the no-obstruction reference, each obstruction at its best position, the narrowest and
// the widest gap, ...). Each picture is a re-run of one stored run -- the job rebuilt
// from the study file, found by its stored job key, so the same scenario and seed --
// stopped at the moment it is drawn. The re-run's crossings up to that moment are
// compared with the stored run's: equal counts say the picture is of the run in the store.
//
// studies/ -> view/ points down the folder order (view/ depends on common/ only).
#pragma once

#include "studies/report.hpp"
#include "studies/study.hpp"

#include <filesystem>
#include <iosfwd>
#include <optional>
#include <string>
#include <vector>

namespace gapflow {

// Simulated time a snapshot may ask for (s after release): keeps a report's re-runs short
// (a long clogging run would otherwise be re-simulated for minutes to reach its middle).
inline constexpr double kSnapshotMaxTimeS = 30.0;

// A point class of a report and the stored run that stands for it.
struct SnapshotPick {
  std::string cls;                  // the class, e.g. "J_0 reference", "cylinder at its best position"
  std::string why;                  // why this point stands for the class (Markdown)
  const ReportPoint* point = nullptr;
  const StoredRun* run = nullptr;   // the replicate re-simulated
  std::string run_why;              // why this replicate
  double t_s = 0;                   // s after release; at a clog: the clog's start (its last crossing)
  bool at_clog = false;             // drawn when the clog is detected (t_s + run.clog_timeout_s), coloured by state
  std::string when;                 // why that moment
};

// The classes that make sense for the report's analyses (report.kind), one pick each:
//   flow_vs_distance: the baseline (J_0) and each other series at its best position
//   screen_confirm:   the baseline, the screen's best point, the confirmation's best point
//   flow_vs_gap, clogging: the narrowest and the widest gap (clogging: narrowest at its first clog)
//   otherwise:        each series at its best point (else its first point, at its first clog)
// The best point is best_point() (report.hpp) in the first model that has the series.
std::vector<SnapshotPick> choose_snapshots(const ReportData& data, const std::vector<StoredRun>& runs);

struct Snapshot {
  SnapshotPick pick;
  std::string file;                 // PNG name in the report folder; "" when not drawn
  std::string problem;              // why it was not drawn
  int width = 0, height = 0;        // px
  double t_drawn_s = 0;             // s after release: the step it was drawn at
  int passed_rerun = -1;            // crossings by t_drawn_s in the re-run
  int passed_stored = -1;           // and in the stored run; -1: the store kept no crossing times
  bool matches() const { return passed_rerun >= 0 && passed_rerun == passed_stored; }
  bool comparable() const { return passed_stored >= 0; }
};

// The study file the runs were made from: `file` when given, else the copy recorded in the
// store (its scenario paths are relative to where it was read from); with `quick`, its --quick
// variant (apply_quick, its [quick] table then spent). Throws when neither works.
StudyDef study_for_snapshots(const std::filesystem::path& db, const std::optional<std::filesystem::path>& file,
                             const std::string& study_name, bool quick = false);

// Re-run each pick's job (found by its stored key among the study's jobs, [quick] and
// [confirm] ones included) up to its moment and write the picture into `dir`. A pick
// that cannot be drawn gets a `problem`, never an exception. Timings go to `log`.
std::vector<Snapshot> draw_snapshots(const std::vector<SnapshotPick>& picks, const StudyDef& study,
                                     const std::vector<StoredRun>& runs, const std::filesystem::path& dir,
                                     std::ostream& log);

// The report's "Snapshots" section; `warning` (e.g. "not requested (--no-snapshots)") replaces the pictures.
std::string snapshots_markdown(const std::vector<Snapshot>& shots, const std::string& warning);

}  // namespace gapflow
