// A screen's heat map, drawn with Cairo: two panels over the same categorical grid
// (x = D/d, y = size/d): J/J_0 on a diverging scale around 1 (blue below, red above),
// and the clog rate beside it. Dropped cells are grey with their bound; infeasible cells
// are crossed out.
#pragma once

#include <filesystem>
#include <string>
#include <vector>

namespace gapflow {

struct HeatCell {
  enum class State { final, dropped, infeasible, missing };
  std::size_t ix = 0, iy = 0;  // column (x value) and row (y value)
  State state = State::missing;
  double value = 0;            // J/J_0 (final: confirmation runs; dropped: at its drop)
  std::string text;            // printed in the cell, e.g. "1.08*" or "<0.83 r1"
  double side_value = -1;      // clogs per 100 passed (< 0: none)
  std::string side_text;
};

struct HeatMap {
  std::string title;
  std::string xlabel = "D/d", ylabel = "size/d";
  std::string left_title = "J/J_0", right_title = "clogs per 100 passed";
  std::vector<std::string> xs, ys;  // column and row labels
  std::vector<HeatCell> cells;
  std::string legend;               // one line under the panels
};

// Write the map as a PNG. Throws std::runtime_error when Cairo cannot write the file.
void draw_heatmap_png(const HeatMap& map, const std::filesystem::path& file);

}  // namespace gapflow
