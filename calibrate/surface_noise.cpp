#include "calibrate/surface_noise.hpp"

#include "common/statistics.hpp"

#include <fmt/format.h>
#include <fmt/ranges.h>

#include <cmath>
#include <map>

namespace gapflow {

namespace {

constexpr double kSurfaceNoiseNote = 1.5;  // well above the 0.8-1.2 of independent nodes

// A node's replicate values at point i, when it has exactly `n` finite ones.
bool complete(const Prediction& p, std::size_t i, std::size_t n) {
  if (!p.valid[i] || p.replicate_fit[i].size() != n) return false;
  for (double v : p.replicate_fit[i])
    if (!std::isfinite(v)) return false;
  return true;
}

// The baseline's nodes with every node of a point weighted alike, by the point's variance pooled
// over the nodes (so the fit is ordinary least squares and its reported variance unbiased for
// independent nodes), and with replicate r's values in place of the means (r < 0: the means).
BaselineFit equally_weighted(const BaselineFit& base, int r) {
  BaselineFit b;
  b.grid = base.grid;
  b.grid_predictions = base.grid_predictions;
  const std::size_t points = base.grid_predictions.front().fit.size();
  for (std::size_t i = 0; i < points; ++i) {
    double pooled = 0;
    for (const Prediction& p : base.grid_predictions) pooled += p.se_fit[i] * p.se_fit[i];
    pooled = std::sqrt(pooled / static_cast<double>(base.grid_predictions.size()));
    for (Prediction& p : b.grid_predictions) {
      p.se_fit[i] = pooled;
      if (r >= 0 && static_cast<std::size_t>(r) < p.replicate_fit[i].size()) p.fit[i] = p.replicate_fit[i][static_cast<std::size_t>(r)];
    }
  }
  return b;
}

}  // namespace

SurfaceNoiseCheck surface_noise_check(const DataFile& data, const BaselineFit& base) {
  SurfaceNoiseCheck c;
  if (base.grid_predictions.empty()) return c;
  const std::size_t n = static_cast<std::size_t>(data.model_replicates);
  c.replicates = data.model_replicates;
  if (n < 3) return c;
  // Replicate r's surface, evaluated at the baseline fit; and the variance the same surface
  // through the means reports.
  std::vector<Prediction> per_replicate;
  for (std::size_t r = 0; r < n; ++r)
    per_replicate.push_back(
        surface_around(data, equally_weighted(base, static_cast<int>(r)), base.surface_at).predict_fit(base.params));
  const Prediction reported = surface_around(data, equally_weighted(base, -1), base.surface_at).predict_fit(base.params);
  std::vector<double> all;
  std::map<std::string, std::vector<double>> by_observable;
  for (std::size_t i = 0; i < data.points.size(); ++i) {
    if (data.points[i].held_out || !reported.valid[i] || !(reported.se_fit[i] > 0)) continue;
    bool usable = true;
    for (const Prediction& p : base.grid_predictions) usable = usable && complete(p, i, n);
    if (!usable) continue;
    std::vector<double> fits;
    for (const Prediction& p : per_replicate) fits.push_back(p.fit[i]);
    const double spread = summarize(fits).se();  // the replicate fits' mean is the surface's own prediction
    const double ratio = spread * spread / (reported.se_fit[i] * reported.se_fit[i]);
    all.push_back(ratio);
    by_observable[to_string(data.points[i].observable)].push_back(ratio);
  }
  c.points = static_cast<int>(all.size());
  if (all.empty()) return c;
  c.median_ratio = median(std::move(all));
  for (auto& [name, v] : by_observable) c.by_observable.emplace_back(name, median(std::move(v)));
  return c;
}

std::string surface_noise_text(const SurfaceNoiseCheck& c) {
  if (c.points == 0)
    return "surface noise check: no fitted point has a value in every model replicate at every node";
  std::string s = fmt::format(
      "surface noise check: at the baseline, the spread of the surfaces fitted to each model replicate alone is "
      "{:.2f} x the variance the surface reports (median over {} fitted points; independent nodes give about 1)",
      c.median_ratio, c.points);
  std::vector<std::string> parts, high;
  for (const auto& [name, ratio] : c.by_observable) {
    parts.push_back(fmt::format("{} {:.2f}", name, ratio));
    if (ratio > kSurfaceNoiseNote) high.push_back(name);
  }
  if (c.by_observable.size() > 1) s += fmt::format("; by observable: {}", fmt::join(parts, ", "));
  if (!high.empty())
    s += fmt::format(". Above {:.1f} ({}): the same seeds at every node keep those replicates correlated between "
                     "nodes, and the loop's tests understate the model's noise there (README, Calibration, limits)",
                     kSurfaceNoiseNote, fmt::join(high, ", "));
  return s;
}

}  // namespace gapflow
