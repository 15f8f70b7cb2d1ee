// ParaView time series: one VTK XML PolyData file (.vtp, ASCII) per frame for
// the particles (points with radius, velocity, id, state and, in 3D, spin; z is
// the true height in 3D, the radius in 2D) and one for the walls and the
// obstruction (polygons in the board plane z = 0, where the shaking has them),
// tied by a .pvd collection that ParaView opens directly (File > Open DIR/run.pvd).
// Lengths in m, velocities in m/s, spin in rad/s, plane frame.
#pragma once

#include "view/frame.hpp"

#include <string>
#include <vector>

namespace gapflow {

class VtkSeries {
 public:
  // Creates `dir` if needed. Files are named particles_NNNNNN.vtp, boundary_NNNNNN.vtp, run.pvd.
  VtkSeries(const CompiledScenario& sc, std::string dir);
  void write(const FrameState& frame);
  // Write run.pvd (only after the last frame: a .pvd means the series is complete).
  void finish() const;
  int frames() const { return static_cast<int>(times_.size()); }

 private:
  const CompiledScenario& sc_;
  std::string dir_;
  std::vector<double> times_;
};

}  // namespace gapflow
