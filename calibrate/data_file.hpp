// Measured-data files: a table of measurements and what to compare it with.
//
// Strict TOML like scenarios and studies (unknown keys, bad values and missing
// columns are ScenarioErrors at file:line:column). A data file keeps apart, as
// MercuryDPM's calibration drivers do, what is fixed (the scenario template and
// its overrides), what is free (parameters with ranges) and what was measured
// (the points). It never names effects: what a model misses is for
// `gapflow calibrate` to find.
//
//   [data]        name, description
//   [source]      citation, method (measured | digitized | simulated), uncertainty (notes)
//   [model]       scenario (relative to this file), set ["key=value", ...], replicates, seed
//   [observable]  kind, scale, uncertainty (se | ci95), floor_relative  (the points' default observable)
//   [floors]      optional, per observable: <kind> = { relative = share, absolute = in its unit }, in place
//                 of floor_relative for that observable's points (an offset near 0 needs an absolute one)
//   [[design]]    column, key, unit (d | lab)
//   [[free]]      key, lo, hi, step, and optionally measured, measured_se (an independent measurement)
//   [points]      csv = "file.csv" (relative to this file)   -- or --   [[point]] rows
// Each point: one value per design column, value, uncertainty, replicates, held_out,
// and optionally observable (another kind than [observable]'s, measured on the same
// runs: a point with the design values of another and a different observable costs
// no simulation, and several observables of one experiment tell effects apart that
// one alone cannot).
#pragma once

#include "common/scenario_loader.hpp"
#include "models/registry.hpp"

#include <cstdint>
#include <filesystem>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

namespace gapflow {

// What was measured at each point. Rates are particles/s; <s> is particles.
enum class ObservableKind {
  j_paper,         // N / time for all to pass
  j_mid,           // rate between the 10 % and 90 % crossings
  j_flowing,       // rate while flowing (clogs removed)
  j_star,          // J_paper sqrt(d/g), g = 9.81 m/s^2
  mean_avalanche,  // <s>, censoring-aware mean avalanche size (first avalanches dropped)
  ln_s_plus_1,     // ln(<s> + 1)
  clog_share,      // share of runs with at least one clog
  front_arrival,   // s, barrier opening (t = 0) to the first crossing: how fast the packing starts to move
  exit_offset,     // mm, mean crossing position across the gap (0 = its centre; + toward +x)
  exit_spread      // mm, standard deviation of the crossing positions across the gap
};
const char* to_string(ObservableKind k);

// The scale on which residuals are formed: log makes the noise of rates and
// sizes roughly even (a relative error); linear for quantities already on it.
enum class FitScale { log, linear };

struct DataSource {
  std::string citation;     // where the numbers come from
  std::string method;       // measured | digitized | simulated
  std::string uncertainty;  // how the uncertainties were obtained, caveats
};

// A design column: its values set one scenario key at every point.
struct DesignColumn {
  std::string column;         // name in the points table ("W_over_d")
  std::string key;            // scenario key ("bottleneck.gap_mm")
  bool in_diameters = false;  // unit "d": value x the point's nominal diameter (mm, after its lab-unit columns); "lab": the key's own unit
  SourceLocation where;
};

// A parameter the baseline fit may move, within [lo, hi] (key units).
struct FreeParameter {
  std::string key;   // scenario key ("particles.friction_particle")
  double lo = 0, hi = 0;
  double step = 0;   // physical step: grid spacing and finite-difference step (key units)
  // An independent measurement of the parameter (the paper's friction from a tilt test: 0.28),
  // with its standard error (key units; 0: none). It enters every fit as one more datum,
  // ((value - measured) / measured_se)^2, so that the parameter cannot wander far from what was
  // measured to absorb a missing effect. measured_se = 0: the parameter is free within [lo, hi].
  double measured = 0;
  double measured_se = 0;
  bool has_measurement() const { return measured_se > 0; }
  SourceLocation where;
};

// A standard-error floor: what the replicates do not show (a calibration, a digitization, a systematic
// the scatter cannot reveal), added in quadrature to a point's standard error.
struct SeFloor {
  double relative = 0;  // share of |value| (0.005: 0.5 %)
  double absolute = 0;  // in the observable's own unit (particles/s, s, mm, particles)
};

struct DataPoint {
  std::vector<std::string> design;  // one TOML literal per design column ("4.5", "\"V\"")
  double value = 0;                 // observable, in its unit
  double se = 0;                    // standard error of value (from the file's uncertainty, floor applied)
  int replicates = 1;               // runs or experiments behind the value
  bool held_out = false;            // not used in any fit; scored separately
  ObservableKind observable = ObservableKind::j_paper;  // what `value` measures (default: [observable] kind)
  FitScale scale = FitScale::log;   // its fit scale ([observable] scale for that kind, else the kind's default)
  SourceLocation where;
};

struct DataFile {
  std::filesystem::path file;
  std::string name;
  std::string description;
  DataSource source;
  std::filesystem::path scenario;        // template, resolved against the data file's folder
  std::vector<std::string> set;          // fixed overrides
  int model_replicates = 4;              // model runs per point and parameter value (common random numbers)
  std::uint64_t seed = 1;                // run.seed of the model runs
  ObservableKind observable = ObservableKind::j_paper;  // the points' default observable
  FitScale scale = FitScale::log;                       // its fit scale
  double floor_relative = 0;             // relative SE floor added in quadrature (every observable without [floors])
  std::vector<std::pair<ObservableKind, SeFloor>> floors;  // [floors]: per observable, in place of floor_relative
  std::vector<DesignColumn> design;
  std::vector<FreeParameter> free;
  std::vector<DataPoint> points;

  // The overrides that make point i (fixed set, then design values), in scenario units.
  std::vector<std::string> point_overrides(std::size_t i) const;
  // The template with point i's overrides and `extra` after them, loaded and validated.
  LoadedScenario point_scenario(std::size_t i, const std::vector<std::string>& extra = {}) const;
  // A short label of point i ("W_over_d=4.5, shape=V").
  std::string point_label(std::size_t i) const;
  std::size_t fitted_count() const;
  std::vector<bool> held_out_flags() const;  // one per point: the points mask of the held-out ones
  // Design points that need runs of their own (points measuring other observables on the same runs count once).
  std::size_t distinct_runs_per_replicate() const;
  // Whether points measure more than one observable (reports then name each point's).
  bool mixed_observables() const;
  // "j_mid on a log scale", or per observable with its point count when mixed.
  std::string observables_text() const;
  // The floor of an observable's points: its [floors] entry, else floor_relative.
  SeFloor floor_of(ObservableKind k) const;
  // Point i's fit-scale value and standard error.
  double fit_value(std::size_t i) const;
  double fit_se(std::size_t i) const;
};

DataFile load_data_file(const std::filesystem::path& file);
// Whether `model` can run every point (check_model_supports), as a ScenarioError at the point.
void check_points_run_in(const DataFile& data, ModelKind model);
// From text (tests). Paths inside resolve against base_dir.
DataFile parse_data_file(std::string_view text, std::string_view source_name, const std::filesystem::path& base_dir);

// The observable's default fit scale (log for rates, times, sizes and spreads).
FitScale default_scale(ObservableKind k);
double to_fit_scale(FitScale scale, double v);
double from_fit_scale(FitScale scale, double v);

}  // namespace gapflow
