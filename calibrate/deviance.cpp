#include "calibrate/deviance.hpp"

#include "common/statistics.hpp"

#include <algorithm>
#include <cmath>

namespace gapflow {

double total_sigma(const DataFile& data, const Prediction& p, std::size_t i) {
  return std::hypot(data.fit_se(i), p.se_fit[i]);
}

double model_noise_share(const DataFile& data, const Prediction& p) {
  std::vector<double> share;
  for (std::size_t i = 0; i < data.points.size(); ++i) {
    if (data.points[i].held_out || !p.valid[i]) continue;
    const double model = p.se_fit[i] * p.se_fit[i], total = std::pow(total_sigma(data, p, i), 2);
    if (total > 0 && std::isfinite(total)) share.push_back(model / total);
  }
  return median(std::move(share));  // NaN when empty
}

namespace {

// One point's whitened residual and its total sigma; an invalid model point counts as 10
// sigma (with the data's own sigma).
struct PointResidual {
  double whitened, sigma;
};
PointResidual point_residual(const DataFile& data, const Prediction& p, std::size_t i) {
  if (!p.valid[i]) return {10.0, data.fit_se(i)};
  const double sigma = total_sigma(data, p, i);
  return {(data.fit_value(i) - p.fit[i]) / sigma, sigma};
}

}  // namespace

std::vector<double> whitened_residual(const DataFile& data, const Prediction& p) {
  std::vector<double> w;
  for (std::size_t i = 0; i < data.points.size(); ++i) w.push_back(point_residual(data, p, i).whitened);
  return w;
}

double chi2_of(const DataFile& data, const Prediction& p, bool held_out) {
  double chi2 = 0;
  for (std::size_t i = 0; i < data.points.size(); ++i) {
    if (data.points[i].held_out != held_out) continue;
    const double w = point_residual(data, p, i).whitened;
    chi2 += w * w;
  }
  return chi2;
}

double deviance_of(const DataFile& data, const Prediction& p, const ParameterSet& params) {
  double d = measurement_chi2(data, params);  // the measurements' sigma is fixed: no log term
  for (std::size_t i = 0; i < data.points.size(); ++i) {
    if (data.points[i].held_out) continue;
    const PointResidual r = point_residual(data, p, i);
    d += r.whitened * r.whitened + 2 * std::log(r.sigma);
  }
  return d;
}

double measurement_chi2(const DataFile& data, const ParameterSet& params) {
  return measurement_rows(data, params, {}).residual.squaredNorm();
}

double fitted_chi2(const DataFile& data, const Prediction& p, const ParameterSet& params) {
  return chi2_of(data, p) + measurement_chi2(data, params);
}

int measured_count(const DataFile& data) {
  return static_cast<int>(std::count_if(data.free.begin(), data.free.end(), [](const FreeParameter& f) { return f.has_measurement(); }));
}

MeasurementRows measurement_rows(const DataFile& data, const ParameterSet& params, const std::vector<std::string>& columns) {
  MeasurementRows m;
  const auto n = static_cast<Eigen::Index>(measured_count(data));
  m.residual = Eigen::VectorXd::Zero(n);
  m.sensitivity = Eigen::MatrixXd::Zero(n, static_cast<Eigen::Index>(columns.size()));
  Eigen::Index row = 0;
  for (const FreeParameter& f : data.free) {
    if (!f.has_measurement()) continue;
    m.residual(row) = (f.measured - params.get(f.key, f.measured)) / f.measured_se;
    for (std::size_t c = 0; c < columns.size(); ++c)
      if (columns[c] == f.key) m.sensitivity(row, static_cast<Eigen::Index>(c)) = 1 / f.measured_se;
    ++row;
  }
  return m;
}

}  // namespace gapflow
