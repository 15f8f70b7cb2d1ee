#include "calibrate/noise_notes.hpp"

#include "common/statistics.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <map>

namespace gapflow {

// Points that measure different observables on the same runs have correlated
// noise, which the chi^2 (a sum over points) ignores. Measured here, per pair of
// observables, on the baseline nodes' replicates (each point's values centred per
// node, pooled over the point pairs), and logged so that a reader can judge it.
std::vector<std::string> shared_run_correlations(const DataFile& data, const BaselineFit& base) {
  std::map<std::pair<ObservableKind, ObservableKind>, std::pair<std::vector<double>, std::vector<double>>> pooled;
  for (std::size_t i = 0; i < data.points.size(); ++i)
    for (std::size_t j = i + 1; j < data.points.size(); ++j) {
      if (data.points[i].design != data.points[j].design) continue;
      auto& [a, b] = pooled[{data.points[i].observable, data.points[j].observable}];
      for (const Prediction& p : base.node_predictions) {
        const std::vector<double>& x = p.replicate_fit[i];
        const std::vector<double>& y = p.replicate_fit[j];
        std::vector<double> xs, ys;
        for (std::size_t r = 0; r < std::min(x.size(), y.size()); ++r)
          if (x[r] == x[r] && y[r] == y[r]) xs.push_back(x[r]), ys.push_back(y[r]);
        if (xs.size() < 2) continue;
        const double mx = summarize(xs).mean, my = summarize(ys).mean;
        for (std::size_t r = 0; r < xs.size(); ++r) a.push_back(xs[r] - mx), b.push_back(ys[r] - my);
      }
    }
  std::vector<std::string> out;
  for (const auto& [kinds, v] : pooled) {
    const auto& [a, b] = v;
    double sab = 0, saa = 0, sbb = 0;
    for (std::size_t r = 0; r < a.size(); ++r) sab += a[r] * b[r], saa += a[r] * a[r], sbb += b[r] * b[r];
    if (saa <= 0 || sbb <= 0) continue;
    out.push_back(fmt::format("{} / {}: rho = {:+.2f} over {} replicate pairs", to_string(kinds.first),
                              to_string(kinds.second), sab / std::sqrt(saa * sbb), a.size()));
  }
  return out;
}

namespace {

// The model's share of the variance above which its replicates, not the data, hold the loop's tests
// back. A planted effect's visibility scales as 1 - share of what a noiseless model would give:
// at 20 % the model costs a fifth. Blind pass 15 at 6 model replicates identified 15 of 18 single
// effects, at 12 all 18 when replayed (in-sample); the fresh pass 17 at 12 identified 15 of 18
// (calibrate/README.md, "The model's own noise is part of every test", with the shares).
constexpr double kModelNoiseShareNote = 0.2;

// The count that would bring `share` down to `target` if the model's variance fell as 1/replicates.
// It falls less in practice (blind pass 15 from 6 to 12: median share 0.31 -> 0.23, not 0.18), so this
// is a lower bound. Within the data file's range [2, 1000].
int replicates_for_share(double share, int model_replicates, double target) {
  const double n = model_replicates * share / (1 - share) * (1 - target) / target;
  if (!(n < 1000)) return 1000;  // share near 1 (and NaN) included
  return std::max(model_replicates + 1, static_cast<int>(std::ceil(n)));
}

}  // namespace

std::string model_noise_text(double share, int model_replicates) {
  if (!std::isfinite(share)) return "the model's noise share: no fitted point has a valid model value at the baseline";
  std::string s = fmt::format("the model's noise is {:.0f} % of the residual's variance at the baseline (median over the "
                              "fitted points; {} model replicates per point)", 100 * share, model_replicates);
  if (share > kModelNoiseShareNote)
    s += fmt::format(": above {:.0f} %, more model replicates give every test more power (at least {} for {:.0f} %: "
                     "--model-replicates or [model] replicates; README, Calibration)",
                     100 * kModelNoiseShareNote, replicates_for_share(share, model_replicates, kModelNoiseShareNote),
                     100 * kModelNoiseShareNote);
  return s;
}

}  // namespace gapflow
