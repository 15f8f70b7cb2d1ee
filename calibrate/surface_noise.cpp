#include "calibrate/surface_noise.hpp"

#include "common/statistics.hpp"

#include <fmt/format.h>
#include <fmt/ranges.h>

#include <cmath>
#include <map>

namespace gapflow {

namespace {

constexpr double kUnderstatedNote = 1.5;  // independent nodes: about 1 (tests/test_surface_noise.cpp)

// Every replicate of point i finite at every node, and `n` of them.
bool complete(const std::vector<Prediction>& nodes, std::size_t i, std::size_t n) {
  for (const Prediction& p : nodes) {
    if (!p.valid[i] || p.replicate_fit[i].size() != n) return false;
    for (double v : p.replicate_fit[i])
      if (!std::isfinite(v)) return false;
  }
  return true;
}

// The window's nodes with replicate r's values (r < 0: their mean), every node of a point weighted by
// the point's replicate variance pooled over the nodes, on the fit scale of the replicates themselves.
BaselineFit replicate_nodes(const BaselineFit& window, std::size_t points, std::size_t n, int r) {
  BaselineFit b = window;
  for (std::size_t i = 0; i < points; ++i) {
    double pooled = 0;
    for (const Prediction& p : window.grid_predictions)
      if (p.replicate_fit[i].size() == n) pooled += std::pow(summarize(p.replicate_fit[i]).se(), 2);
    pooled = std::sqrt(pooled / static_cast<double>(window.grid_predictions.size()));
    for (Prediction& p : b.grid_predictions) {
      p.se_fit[i] = pooled > 0 ? pooled : 1;
      if (p.replicate_fit[i].size() != n) continue;
      p.fit[i] = r >= 0 ? p.replicate_fit[i][static_cast<std::size_t>(r)] : summarize(p.replicate_fit[i]).mean;
    }
  }
  return b;
}

// The variance the surface reports at point i without its lack-of-fit widening (fit.cpp, build_surface).
double unwidened_variance(const Surface& s, const Prediction& p, const ParameterSet& at, std::size_t i) {
  return p.se_fit[i] * p.se_fit[i] - s.misfit_part(at, i);
}

struct Sums {
  int points = 0;
  double spread = 0, independent = 0;  // summed over the points, at the window's middle node
  double counted = 0, independent_fit = 0;  // the surface's variance and independent nodes', at the baseline fit
};

SurfaceNoiseGroup estimate(std::string name, const Sums& s, double h_middle, double h_fit) {
  SurfaceNoiseGroup g;
  g.name = std::move(name);
  g.points = s.points;
  if (s.points == 0 || !(s.independent > 0) || !(h_middle < 1)) return g;
  g.correlation = (s.spread / s.independent - 1) / (1 / h_middle - 1);
  g.understated = 1 + g.correlation * (1 / h_fit - 1);
  if (s.independent_fit > 0) g.counted = s.counted / s.independent_fit;
  return g;
}

}  // namespace

SurfaceNoiseCheck surface_noise_check(const DataFile& data, const BaselineFit& base) {
  SurfaceNoiseCheck c;
  const std::size_t n = static_cast<std::size_t>(data.model_replicates);
  if (n < 3) return c.problem = "fewer than 3 model replicates", c;
  if (data.free.size() != 1) return c.problem = "not one free parameter", c;
  BaselineFit window;
  for (std::size_t k : surface_window(data, base, base.surface_at))
    window.grid.push_back(base.grid[k]), window.grid_predictions.push_back(base.grid_predictions[k]);
  c.nodes = static_cast<int>(window.grid.size());
  if (c.nodes < 4) return c.problem = "fewer than 4 nodes in the window", c;
  const ParameterSet middle = window.grid[window.grid.size() / 2];
  const std::size_t points = data.points.size();

  std::vector<Prediction> per_replicate;  // each replicate's surface, at the window's middle node
  for (std::size_t r = 0; r < n; ++r)
    per_replicate.push_back(
        surface_around(data, replicate_nodes(window, points, n, static_cast<int>(r)), middle).predict_fit(middle));
  const BaselineFit means = replicate_nodes(window, points, n, -1);
  const Surface mean_surface = surface_around(data, means, middle);
  const Prediction at_fit = mean_surface.predict_fit(base.params);

  Sums all;
  std::map<std::string, Sums> by_observable;
  double h_middle = NAN, h_fit = NAN;
  for (std::size_t i = 0; i < points; ++i) {
    if (data.points[i].held_out || !complete(window.grid_predictions, i, n)) continue;
    const double independent = mean_surface.independent_nodes_variance(middle, i);
    if (!(independent > 0)) continue;
    std::vector<double> fits;
    for (const Prediction& p : per_replicate) fits.push_back(p.fit[i]);
    const double spread = std::pow(summarize(fits).se(), 2);
    // One free parameter and every node of a point weighted alike: the leverage is the same at every point.
    const double pooled = std::pow(means.grid_predictions.front().se_fit[i], 2);  // a node's variance
    h_middle = independent / pooled;
    const double independent_fit = mean_surface.independent_nodes_variance(base.params, i);
    h_fit = independent_fit / pooled;
    for (Sums* s : {&all, &by_observable[to_string(data.points[i].observable)]}) {
      ++s->points, s->spread += spread, s->independent += independent;
      s->counted += unwidened_variance(mean_surface, at_fit, base.params, i), s->independent_fit += independent_fit;
    }
  }
  if (all.points == 0) return c.problem = "no fitted point has every model replicate at every node", c;
  c.all = estimate("all", all, h_middle, h_fit);
  for (const auto& [name, sums] : by_observable) c.by_observable.push_back(estimate(name, sums, h_middle, h_fit));
  return c;
}

std::string surface_noise_text(const SurfaceNoiseCheck& c) {
  if (!c.problem.empty()) return "surface noise check: not made (" + c.problem + ")";
  std::string s = fmt::format(
      "surface noise check: the model replicates correlate {:+.2f} between grid nodes (from the spread of a surface "
      "fitted to each replicate alone, {} fitted points; independent nodes give about 0), so at the baseline "
      "independent nodes would understate the model's variance {:.2f} x; the surface counts {:.2f} x (the "
      "correlation pooled over each observable's points)",
      c.all.correlation, c.all.points, c.all.understated, c.all.counted);
  std::vector<std::string> parts, high;
  for (const SurfaceNoiseGroup& g : c.by_observable) {
    parts.push_back(fmt::format("{} {:+.2f} ({:.2f} x, counted {:.2f} x)", g.name, g.correlation, g.understated, g.counted));
    if (g.understated / g.counted > kUnderstatedNote) high.push_back(g.name);
  }
  if (c.by_observable.size() > 1) s += fmt::format("; by observable: {}", fmt::join(parts, ", "));
  if (!high.empty())
    s += fmt::format(". Above {:.1f} x what the surface counts ({}): the replicates correlate between nodes more "
                     "than their pooled correlation says, and the loop's tests take the model's noise there as smaller "
                     "than it is (calibrate/README.md, \"The model's own noise is part of every test\")",
                     kUnderstatedNote, fmt::join(high, ", "));
  return s;
}

}  // namespace gapflow
