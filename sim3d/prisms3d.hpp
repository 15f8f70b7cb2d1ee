// Prisms extruded normal to the board from the scenario's plane-frame polygons: the walls, the
// obstruction and the cover of the 3D model (Session3D builds them). A rectangle becomes a box (exact
// sphere-box contacts, robust against deep penetration); any other convex polygon a hull moved inward
// by Bullet's margin first, since Bullet inflates a hull by its margin (the faces stay where the
// scenario puts them; the corners round with radius margin). Engine units throughout.
#pragma once

#include "common/geometry.hpp"
#include "common/units.hpp"

#include <btBulletDynamicsCommon.h>

#include <memory>
#include <vector>

namespace gapflow::bullet3d {

struct Point2 {
  double x, y;  // engine units, in the board's plane
};

// A collision shape and where its local origin sits in the world (engine units).
struct PlacedShape {
  std::unique_ptr<btCollisionShape> shape;
  btTransform pose;
};

// A polygon's vertices in engine units.
std::vector<Point2> to_engine(const ConvexPolygon& p, const EngineScaling& s);
// A prism's pose: centred on the mean of `poly`'s vertices, halfway between z0 and z1; no shape yet.
PlacedShape prism_at(const std::vector<Point2>& poly, double z0, double z1);
// Fills `out` (posed by prism_at) with the hull over a polygon already moved inward by
// `margin`: Bullet's hull plus its margin is that polygon Minkowski-summed with a disc.
PlacedShape hull_prism(PlacedShape out, const std::vector<Point2>& shrunk, double z0, double z1, double margin);
// Right prism over a convex polygon (counter-clockwise), from z0 to z1.
PlacedShape make_prism(const std::vector<Point2>& poly, double z0, double z1, double margin);

}  // namespace gapflow::bullet3d
