#include "calibrate/node_correlation.hpp"

#include <fmt/format.h>
#include <fmt/ranges.h>

#include <algorithm>
#include <cmath>
#include <limits>

namespace gapflow {

namespace {

// Point i's replicates at every node, centred and scaled at each node: [replicate][node]. Empty when
// a node lacks a finite value in some replicate, has another count of them, fewer than 3, or no spread.
Eigen::MatrixXd standardized(const std::vector<Prediction>& preds, std::size_t i) {
  const std::size_t n = preds.front().replicate_fit.size() > i ? preds.front().replicate_fit[i].size() : 0;
  if (n < 3) return {};
  Eigen::MatrixXd z(static_cast<Eigen::Index>(n), static_cast<Eigen::Index>(preds.size()));
  for (std::size_t k = 0; k < preds.size(); ++k) {
    if (preds[k].replicate_fit.size() <= i || preds[k].replicate_fit[i].size() != n) return {};
    for (std::size_t r = 0; r < n; ++r) {
      const double v = preds[k].replicate_fit[i][r];
      if (!std::isfinite(v)) return {};
      z(static_cast<Eigen::Index>(r), static_cast<Eigen::Index>(k)) = v;
    }
  }
  return standardize_columns(z) ? z : Eigen::MatrixXd{};
}

// The node pairs nearest each other, each parameter scaled by its range over the nodes.
std::vector<std::pair<std::size_t, std::size_t>> neighbour_pairs(const std::vector<ParameterSet>& nodes) {
  std::vector<std::string> keys;
  for (const ParameterSet& p : nodes)
    for (const auto& [key, value] : p.values)
      if (std::find(keys.begin(), keys.end(), key) == keys.end()) keys.push_back(key);
  std::vector<double> range;
  for (const std::string& key : keys) {
    double lo = INFINITY, hi = -INFINITY;
    for (const ParameterSet& p : nodes) lo = std::min(lo, p.get(key, 0)), hi = std::max(hi, p.get(key, 0));
    range.push_back(hi > lo ? hi - lo : 1);
  }
  auto distance = [&](std::size_t a, std::size_t b) {
    double d = 0;
    for (std::size_t k = 0; k < keys.size(); ++k) d += std::pow((nodes[a].get(keys[k], 0) - nodes[b].get(keys[k], 0)) / range[k], 2);
    return std::sqrt(d);
  };
  double nearest = INFINITY;
  for (std::size_t a = 0; a < nodes.size(); ++a)
    for (std::size_t b = a + 1; b < nodes.size(); ++b)
      if (distance(a, b) > 0) nearest = std::min(nearest, distance(a, b));
  std::vector<std::pair<std::size_t, std::size_t>> out;
  for (std::size_t a = 0; a < nodes.size(); ++a)
    for (std::size_t b = a + 1; b < nodes.size(); ++b)
      if (distance(a, b) <= nearest * (1 + 1e-9)) out.emplace_back(a, b);
  return out;
}

ObservableCorrelation pooled(const DataFile& data, ObservableKind kind, const std::vector<Prediction>& preds,
                             const std::vector<std::pair<std::size_t, std::size_t>>& neighbours) {
  ObservableCorrelation c;
  c.observable = kind;
  const auto nodes = static_cast<Eigen::Index>(preds.size());
  Eigen::MatrixXd gram = Eigen::MatrixXd::Zero(nodes, nodes);
  for (std::size_t i = 0; i < data.points.size(); ++i) {
    if (data.points[i].observable != kind) continue;
    const Eigen::MatrixXd z = standardized(preds, i);
    if (z.size() == 0) continue;
    gram += z.transpose() * z;  // unit diagonal per point
    ++c.points;
  }
  c.matrix = c.points > 0 ? Eigen::MatrixXd(gram / c.points) : Eigen::MatrixXd::Identity(nodes, nodes);
  double sum = 0;
  for (const auto& [a, b] : neighbours) sum += c.matrix(static_cast<Eigen::Index>(a), static_cast<Eigen::Index>(b));
  c.neighbours = neighbours.empty() ? std::numeric_limits<double>::quiet_NaN() : sum / static_cast<double>(neighbours.size());
  return c;
}

}  // namespace

bool standardize_columns(Eigen::MatrixXd& z) {
  for (Eigen::Index k = 0; k < z.cols(); ++k) {
    z.col(k).array() -= z.col(k).mean();
    const double norm = z.col(k).norm();
    if (!(norm > 0)) return false;
    z.col(k) /= norm;  // each point weighs alike, whatever its scale and replicate count
  }
  return true;
}

NodeCorrelations node_correlations(const DataFile& data, const std::vector<ParameterSet>& nodes,
                                   const std::vector<Prediction>& preds) {
  NodeCorrelations out;
  const auto neighbours = neighbour_pairs(nodes);
  for (const DataPoint& p : data.points) {
    std::size_t k = 0;
    while (k < out.observables.size() && out.observables[k].observable != p.observable) ++k;
    if (k == out.observables.size()) out.observables.push_back(pooled(data, p.observable, preds, neighbours));
    out.of_point.push_back(k);
  }
  return out;
}

std::string node_correlation_text(const NodeCorrelations& c) {
  std::vector<std::string> parts;
  for (const ObservableCorrelation& o : c.observables)
    if (o.points == 0)
      parts.push_back(fmt::format("{} none (no point with every replicate at every node)", to_string(o.observable)));
    else if (std::isnan(o.neighbours))
      parts.push_back(fmt::format("{} n/a (one node)", to_string(o.observable)));
    else
      parts.push_back(fmt::format("{} {:+.2f} ({} points)", to_string(o.observable), o.neighbours, o.points));
  return fmt::format("  the replicates' correlation between neighbouring nodes, counted in the surface's variance: {}",
                     fmt::join(parts, ", "));
}

}  // namespace gapflow
