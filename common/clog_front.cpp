#include "common/clog_front.hpp"

#include "common/vec2_math.hpp"

#include <algorithm>
#include <cmath>
#include <numeric>

namespace gapflow {

namespace {

// For each of `discs`, whether it has a free line of sight to `eye` (visible_from).
std::vector<char> seen_from(const ObstructionGeometry& obstruction, const std::vector<BoardDisc>& discs, Vec2 eye) {
  // A disc q can cut the segment from p to the eye only if |q - eye| < |p - eye| + r_q
  // <= |p - eye| + r_max: scan candidate occluders in order of distance and stop past that.
  std::vector<double> reach(discs.size());
  double r_max = 0;
  for (size_t i = 0; i < discs.size(); ++i) {
    reach[i] = length(discs[i].centre - eye);
    r_max = std::max(r_max, discs[i].radius);
  }
  std::vector<size_t> by_reach(discs.size());
  std::iota(by_reach.begin(), by_reach.end(), size_t{0});
  std::sort(by_reach.begin(), by_reach.end(), [&](size_t a, size_t b) { return reach[a] < reach[b]; });

  std::vector<char> seen(discs.size(), 0);
  for (size_t i = 0; i < discs.size(); ++i) {
    const BoardDisc& p = discs[i];
    if (obstruction_blocks_segment(obstruction, p.centre, eye)) continue;
    seen[i] = 1;
    for (size_t j : by_reach) {
      if (reach[j] > reach[i] + r_max) break;
      if (j != i && distance_to_segment(discs[j].centre, p.centre, eye) < discs[j].radius) {
        seen[i] = 0;
        break;
      }
    }
  }
  return seen;
}

// For each of `discs`, whether the gap sees it (visible_from_gap).
std::vector<char> seen_from_gap(const CompiledScenario& sc, const ObstructionGeometry& obstruction,
                                const std::vector<BoardDisc>& discs) {
  const int points = static_cast<int>(std::ceil(2 * sc.gap / sc.nominal_diameter)) + 1;
  std::vector<char> seen(discs.size(), 0);
  for (int k = 0; k < points; ++k) {
    const Vec2 eye{-sc.gap / 2 + (k + 0.5) * sc.gap / points, 0};
    const std::vector<char> from_here = seen_from(obstruction, discs, eye);
    for (size_t i = 0; i < discs.size(); ++i) seen[i] = seen[i] || from_here[i];
  }
  return seen;
}

std::vector<int> ids_of(const std::vector<BoardDisc>& discs, const std::vector<char>& chosen) {
  std::vector<int> out;
  for (size_t i = 0; i < discs.size(); ++i)
    if (chosen[i]) out.push_back(discs[i].id);
  return out;
}

}  // namespace

std::vector<int> visible_from(const ObstructionGeometry& obstruction, const std::vector<BoardDisc>& discs, Vec2 eye) {
  return ids_of(discs, seen_from(obstruction, discs, eye));
}

std::vector<int> visible_from_gap(const CompiledScenario& sc, const ObstructionGeometry& obstruction,
                                  const std::vector<BoardDisc>& discs) {
  return ids_of(discs, seen_from_gap(sc, obstruction, discs));
}

ObstructionGeometry displaced(const ObstructionGeometry& g, Vec2 offset) {
  ObstructionGeometry moved = g;
  moved.circle.centre = g.circle.centre + offset;
  for (Vec2& v : moved.polygon.vertices) v = v + offset;
  moved.reference_point = g.reference_point + offset;
  moved.centroid = g.centroid + offset;
  moved.nearest_y = g.nearest_y + offset.y;
  return moved;
}

bool touches_obstruction(const ObstructionGeometry& obstruction, const BoardDisc& disc, double tolerance_m) {
  if (obstruction.shape == ObstructionShape::none) return false;
  return obstruction_distance(obstruction, disc.centre) - disc.radius <= tolerance_m;
}

namespace {

// Distance (m) from a point to one side's walls: the bottleneck wall's inner face
// (moved by its shaking offset) and, above the funnel, the retaining wall.
double distance_to_side(const CompiledScenario& sc, Vec2 p, double side, Vec2 tip, Vec2 offset) {
  const Vec2 top{side * sc.channel_width / 2, sc.funnel_height};
  double d = distance_to_segment(p, tip + offset, top + offset);
  if (p.y >= sc.funnel_height) d = std::min(d, sc.channel_width / 2 - side * p.x);
  return d;
}

// Which discs are reachable from those marked in `start` through touching discs (depth first).
std::vector<char> reachable(const std::vector<BoardDisc>& discs, const std::vector<char>& start, double tolerance) {
  std::vector<char> reached = start;
  std::vector<size_t> todo;
  for (size_t i = 0; i < discs.size(); ++i)
    if (start[i]) todo.push_back(i);
  while (!todo.empty()) {
    const size_t i = todo.back();
    todo.pop_back();
    for (size_t j = 0; j < discs.size(); ++j)
      if (!reached[j] &&
          length(discs[i].centre - discs[j].centre) <= discs[i].radius + discs[j].radius + tolerance) {
        reached[j] = 1;
        todo.push_back(j);
      }
  }
  return reached;
}

}  // namespace

bool front_leans_on_obstruction(const CompiledScenario& sc, const std::vector<BoardDisc>& board,
                                const ShakeOffsets& offsets) {
  if (sc.obstruction.shape == ObstructionShape::none) return false;
  const ObstructionGeometry obstruction = displaced(sc.obstruction, offsets.obstruction);
  const std::vector<char> seen = seen_from_gap(sc, obstruction, board);
  std::vector<BoardDisc> front;
  for (size_t i = 0; i < board.size(); ++i)
    if (seen[i]) front.push_back(board[i]);
  const double d = sc.nominal_diameter;
  const double to_disc = kDiscContactTolerance_d * d, to_boundary = kBoundaryContactTolerance_d * d;
  const double to_left = to_boundary + length(offsets.left_wall), to_right = to_boundary + length(offsets.right_wall);
  const double to_obstruction = to_boundary + length(offsets.obstruction);
  std::vector<char> on_left(front.size()), on_right(front.size()), on_obstruction(front.size());
  for (size_t i = 0; i < front.size(); ++i) {
    const BoardDisc& b = front[i];
    on_left[i] = distance_to_side(sc, b.centre, -1, sc.left_tip, offsets.left_wall) - b.radius <= to_left;
    on_right[i] = distance_to_side(sc, b.centre, +1, sc.right_tip, offsets.right_wall) - b.radius <= to_right;
    on_obstruction[i] = touches_obstruction(obstruction, b, to_obstruction);
  }
  const std::vector<char> from_left = reachable(front, on_left, to_disc);
  for (size_t i = 0; i < front.size(); ++i)
    if (from_left[i] && on_right[i]) return false;  // an arch from wall to wall
  const std::vector<char> from_obstruction = reachable(front, on_obstruction, to_disc);
  for (size_t i = 0; i < front.size(); ++i)
    if (from_obstruction[i] && (on_left[i] || on_right[i])) return true;
  return false;
}

}  // namespace gapflow
