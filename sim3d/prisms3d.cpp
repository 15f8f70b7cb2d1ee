#include "sim3d/prisms3d.hpp"

#include <cmath>

namespace gapflow::bullet3d {

namespace {

// A polygon moved inward by `m` (edges offset along their normals). Bullet
// inflates hulls by their margin, so shrinking first puts the faces where the
// scenario says (corners become rounded with radius m).
std::vector<Point2> shrink_convex(const std::vector<Point2>& v, double m) {
  const size_t n = v.size();
  std::vector<Point2> out(n);
  for (size_t i = 0; i < n; ++i) {
    const Point2 a = v[(i + n - 1) % n], b = v[i], c = v[(i + 1) % n];
    // Inward normals (counter-clockwise polygon: interior on the left).
    auto normal = [](Point2 p, Point2 q) {
      const double ex = q.x - p.x, ey = q.y - p.y, len = std::hypot(ex, ey);
      return Point2{-ey / len, ex / len};
    };
    const Point2 n1 = normal(a, b), n2 = normal(b, c);
    // Solve n1.p = n1.b + m and n2.p = n2.b + m for p = b + q.
    const double det = n1.x * n2.y - n1.y * n2.x;
    const double qx = (m * n2.y - n1.y * m) / det, qy = (n1.x * m - m * n2.x) / det;
    out[i] = {b.x + qx, b.y + qy};
  }
  return out;
}

bool is_rectangle(const std::vector<Point2>& v) {
  if (v.size() != 4) return false;
  for (size_t i = 0; i < 4; ++i) {
    const Point2 a = v[i], b = v[(i + 1) % 4], c = v[(i + 2) % 4];
    const double ux = b.x - a.x, uy = b.y - a.y, wx = c.x - b.x, wy = c.y - b.y;
    if (std::abs(ux * wx + uy * wy) > 1e-9 * (ux * ux + uy * uy + wx * wx + wy * wy)) return false;
  }
  return true;
}

}  // namespace

PlacedShape prism_at(const std::vector<Point2>& poly, double z0, double z1) {
  double cx = 0, cy = 0;
  for (Point2 p : poly) cx += p.x / poly.size(), cy += p.y / poly.size();
  PlacedShape out;
  out.pose.setIdentity();
  out.pose.setOrigin(btVector3(cx, cy, (z0 + z1) / 2));
  return out;
}

PlacedShape hull_prism(PlacedShape out, const std::vector<Point2>& shrunk, double z0, double z1, double margin) {
  const double cx = out.pose.getOrigin().x(), cy = out.pose.getOrigin().y(), hz = (z1 - z0) / 2;
  auto hull = std::make_unique<btConvexHullShape>();
  for (Point2 p : shrunk) {
    hull->addPoint(btVector3(p.x - cx, p.y - cy, -hz + margin), false);
    hull->addPoint(btVector3(p.x - cx, p.y - cy, hz - margin), false);
  }
  hull->recalcLocalAabb();
  hull->setMargin(margin);
  out.shape = std::move(hull);
  return out;
}

PlacedShape make_prism(const std::vector<Point2>& poly, double z0, double z1, double margin) {
  PlacedShape out = prism_at(poly, z0, z1);
  if (is_rectangle(poly)) {
    // A box: exact sphere-box contacts, robust against deep penetration.
    const double ex = poly[1].x - poly[0].x, ey = poly[1].y - poly[0].y;
    const double len0 = std::hypot(ex, ey);
    const double len1 = std::hypot(poly[2].x - poly[1].x, poly[2].y - poly[1].y);
    auto box = std::make_unique<btBoxShape>(btVector3(len0 / 2, len1 / 2, (z1 - z0) / 2));
    box->setMargin(margin);  // btBoxShape keeps its outer extents when the margin changes
    out.pose.setRotation(btQuaternion(btVector3(0, 0, 1), std::atan2(ey, ex)));
    out.shape = std::move(box);
    return out;
  }
  return hull_prism(std::move(out), shrink_convex(poly, margin), z0, z1, margin);
}

std::vector<Point2> to_engine(const ConvexPolygon& p, const EngineScaling& s) {
  std::vector<Point2> v;
  for (Vec2 q : p.vertices) v.push_back({s.to_engine_length(q.x), s.to_engine_length(q.y)});
  return v;
}

}  // namespace gapflow::bullet3d
