// What a calibration writes: report.md (for people), summary.json (for programs:
// the blind study reads it), points.csv (data and model before/after per point)
// and PNG plots drawn by calibrate/plot_calibration.py (matplotlib).
#pragma once

#include "calibrate/calibration.hpp"

#include <filesystem>

namespace gapflow {

void write_calibration_outputs(const DataFile& data, const CalibrationResult& result, const std::filesystem::path& dir,
                               bool plots);

}  // namespace gapflow
