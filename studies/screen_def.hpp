// [screen]: a racing screen over obstruction shape x size x distance D x gap W, each
// cell against the no-obstruction baseline at its gap (statistics: studies/racing.hpp;
// running it: studies/screen.hpp). The loader turns the grid into series, so jobs,
// keys, the store and the report work as for any study:
//   series "cylinder" / "A" / "V": axes obstruction.diameter_mm or obstruction.side_mm,
//                                  obstruction.distance_mm, bottleneck.gap_mm (first slowest)
//   series "none":                 axis bottleneck.gap_mm (the baseline J_0 per gap)
//
//   [screen]
//   scenario = "../../scenarios/paper/cylinder.toml"  # base scenario (relative to the study file)
//   shapes = ["cylinder", "A", "V"]
//   cylinder_diameter_d = [1.5, 3, 6, 12]   # or cylinder_diameter_mm; d = the scenario's nominal diameter
//   triangle_side_d = [1.5, 3, 5, 8]        # or triangle_side_mm (A and V)
//   distance_d = [0, 1, 2, 5, 10, 20]       # or distance_mm: gap line to the obstruction (see reference)
//   gap_d = [3, 4, 5, 6]                    # or gap_mm: W
//   reference = "nearest"                   # D to the nearest point (default) or "centre"
//   initial = 3, step = 3, max = 12, confirm = 10      # replicates (studies/racing.hpp)
//   baseline_confirm = 30                   # a baseline's confirmation replicates (default: confirm; >= confirm)
//   alpha = 0.05, scope = "cell", drop_below = 1.0, best_margin = 0.1, confidence = 0.95
//   check_model = "3d", check_replicates = 10, check_controls = 2   # the other model's check (screen_check.hpp)
#pragma once

#include "models/registry.hpp"
#include "studies/racing.hpp"

#include <optional>

#include <filesystem>
#include <string>
#include <vector>

namespace gapflow {

struct ScreenDef {
  std::filesystem::path scenario;   // the base scenario (resolved against the study file's folder)
  std::vector<std::string> shapes;  // "cylinder", "A", "V", in the file's order
  std::vector<double> cylinder_diameter_mm, triangle_side_mm, distance_mm, gap_mm;  // mm (converted from d)
  std::string reference = "nearest";  // obstruction.reference of every cell
  double d_mm = 0;                    // mm, nominal d of the base scenario with the study's set
  RacingParams racing;
  std::optional<ModelKind> check_model;  // the model that checks the screen's result (absent: no check)
  int check_replicates = 10;             // runs: fresh replicates per checked cell and per baseline of its gap
  int check_controls = 2;                // cells: not above J_0 in the screen, checked alongside as controls
};

// The series label of the baseline and the size key of a shape.
inline constexpr const char* kScreenBaseline = "none";
const char* screen_size_key(const std::string& shape);  // obstruction.diameter_mm | obstruction.side_mm

}  // namespace gapflow
