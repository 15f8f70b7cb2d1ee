// Small 2D vector helpers for the plane frame (no engine types).
#pragma once

#include "common/scenario.hpp"

#include <algorithm>
#include <cmath>
#include <vector>

namespace gapflow {

inline Vec2 operator+(Vec2 a, Vec2 b) { return {a.x + b.x, a.y + b.y}; }
inline Vec2 operator-(Vec2 a, Vec2 b) { return {a.x - b.x, a.y - b.y}; }
inline Vec2 operator*(double s, Vec2 a) { return {s * a.x, s * a.y}; }
inline double dot(Vec2 a, Vec2 b) { return a.x * b.x + a.y * b.y; }
inline double cross(Vec2 a, Vec2 b) { return a.x * b.y - a.y * b.x; }
inline double length(Vec2 a) { return std::sqrt(dot(a, a)); }

// Distance from p to the segment [a, b].
inline double distance_to_segment(Vec2 p, Vec2 a, Vec2 b) {
  Vec2 ab = b - a;
  double len2 = dot(ab, ab);
  double t = len2 > 0 ? dot(p - a, ab) / len2 : 0.0;
  t = t < 0 ? 0 : (t > 1 ? 1 : t);
  return length(p - (a + t * ab));
}

// Segments [a, b] and [c, d] intersect or touch.
inline bool segments_intersect(Vec2 a, Vec2 b, Vec2 c, Vec2 d) {
  auto sign = [](double v) { return (v > 0) - (v < 0); };
  auto on_segment = [](Vec2 p, Vec2 q, Vec2 r) {  // r collinear with [p, q]: is it between them?
    return std::min(p.x, q.x) <= r.x && r.x <= std::max(p.x, q.x) && std::min(p.y, q.y) <= r.y &&
           r.y <= std::max(p.y, q.y);
  };
  const int o1 = sign(cross(b - a, c - a)), o2 = sign(cross(b - a, d - a));
  const int o3 = sign(cross(d - c, a - c)), o4 = sign(cross(d - c, b - c));
  if (o1 != o2 && o3 != o4) return true;
  return (o1 == 0 && on_segment(a, b, c)) || (o2 == 0 && on_segment(a, b, d)) ||
         (o3 == 0 && on_segment(c, d, a)) || (o4 == 0 && on_segment(c, d, b));
}

// Twice the signed area (positive for counter-clockwise).
inline double signed_area2(const std::vector<Vec2>& v) {
  double a = 0;
  for (size_t i = 0; i < v.size(); ++i) a += cross(v[i], v[(i + 1) % v.size()]);
  return a;
}

inline Vec2 polygon_centroid(const std::vector<Vec2>& v) {
  double a2 = signed_area2(v);
  Vec2 c{};
  for (size_t i = 0; i < v.size(); ++i) {
    const Vec2 p = v[i], q = v[(i + 1) % v.size()];
    double w = cross(p, q);
    c = c + (w / (3.0 * a2)) * (p + q);
  }
  return c;
}

// Point inside a counter-clockwise convex polygon (boundary counts as inside).
inline bool inside_convex(const std::vector<Vec2>& v, Vec2 p) {
  for (size_t i = 0; i < v.size(); ++i)
    if (cross(v[(i + 1) % v.size()] - v[i], p - v[i]) < 0) return false;
  return true;
}

// Distance from a point to a convex polygon's boundary, negative when inside.
inline double signed_distance_to_convex(const std::vector<Vec2>& v, Vec2 p) {
  double d = 1e300;
  for (size_t i = 0; i < v.size(); ++i) d = std::min(d, distance_to_segment(p, v[i], v[(i + 1) % v.size()]));
  return inside_convex(v, p) ? -d : d;
}

}  // namespace gapflow
