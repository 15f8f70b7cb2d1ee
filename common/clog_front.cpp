#include "common/clog_front.hpp"

#include "common/vec2_math.hpp"

#include <algorithm>
#include <cmath>
#include <numeric>

namespace gapflow {

std::vector<int> visible_from(const ObstructionGeometry& obstruction, const std::vector<BoardDisc>& discs, Vec2 eye) {
  // A disc q can cut the segment from p to the eye only if its near edge is closer to
  // the eye than p: scan candidate occluders in order of distance and stop past |p| + r_max.
  std::vector<double> reach(discs.size());
  double r_max = 0;
  for (size_t i = 0; i < discs.size(); ++i) {
    reach[i] = length(discs[i].centre - eye);
    r_max = std::max(r_max, discs[i].radius);
  }
  std::vector<size_t> by_reach(discs.size());
  std::iota(by_reach.begin(), by_reach.end(), size_t{0});
  std::sort(by_reach.begin(), by_reach.end(), [&](size_t a, size_t b) { return reach[a] < reach[b]; });

  std::vector<int> visible;
  for (size_t i = 0; i < discs.size(); ++i) {
    const BoardDisc& p = discs[i];
    if (obstruction_blocks_segment(obstruction, p.centre, eye)) continue;
    bool seen = true;
    for (size_t j : by_reach) {
      if (reach[j] > reach[i] + r_max) break;
      const BoardDisc& q = discs[j];
      if (q.id != p.id && distance_to_segment(q.centre, p.centre, eye) < q.radius) {
        seen = false;
        break;
      }
    }
    if (seen) visible.push_back(p.id);
  }
  return visible;
}

std::vector<int> visible_from_gap(const CompiledScenario& sc, const std::vector<BoardDisc>& discs) {
  const int points = static_cast<int>(std::ceil(2 * sc.gap / sc.nominal_diameter)) + 1;
  std::vector<bool> seen(discs.size(), false);
  std::vector<size_t> index_of_id;  // ids are small non-negative integers (particle indices)
  for (size_t i = 0; i < discs.size(); ++i) {
    const auto id = static_cast<size_t>(discs[i].id);
    if (index_of_id.size() <= id) index_of_id.resize(id + 1);
    index_of_id[id] = i;
  }
  for (int k = 0; k < points; ++k) {
    const Vec2 eye{-sc.gap / 2 + (k + 0.5) * sc.gap / points, 0};
    for (int id : visible_from(sc.obstruction, discs, eye)) seen[index_of_id[static_cast<size_t>(id)]] = true;
  }
  std::vector<int> out;
  for (size_t i = 0; i < discs.size(); ++i)
    if (seen[i]) out.push_back(discs[i].id);
  return out;
}

bool touches_obstruction(const ObstructionGeometry& obstruction, const BoardDisc& disc, double tolerance_m) {
  if (obstruction.shape == ObstructionShape::none) return false;
  return obstruction_distance(obstruction, disc.centre) - disc.radius <= tolerance_m;
}

double obstruction_contact_tolerance(const CompiledScenario& sc) {
  const ShakeDef& shake = sc.def.shaking.obstruction;
  return 0.1 * sc.nominal_diameter + (shake.enabled ? shake.amplitude_mm * 1e-3 : 0.0);
}

}  // namespace gapflow
