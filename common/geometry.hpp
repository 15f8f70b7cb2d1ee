// Compiled scenario: engine-independent geometry in lab METRES, plane frame.
//
// Plane frame: x across the channel (0 on the axis of the gap), y uphill along
// the board (0 on the gap line), z normal to the board (up out of it). The
// gap line is the segment y = 0, |x| <= W/2, between the two wall tips.
// Both engines build their worlds from this one description; neither reads the
// ScenarioDef's mm and degrees directly.
#pragma once

#include "common/scenario.hpp"

#include <cstdint>
#include <vector>

namespace gapflow {

// A convex polygon, vertices counter-clockwise, metres.
struct ConvexPolygon {
  std::vector<Vec2> vertices;
};

struct Circle {
  Vec2 centre;    // m
  double radius;  // m
};

// Obstruction placed in the plane frame.
struct ObstructionGeometry {
  ObstructionShape shape = ObstructionShape::none;
  Circle circle{};         // when shape == cylinder
  ConvexPolygon polygon;   // when shape == triangle or polygon: the core, i.e. the drawn polygon moved
                           // inward by corner_radius (the drawn polygon itself when it is 0)
  double corner_radius = 0;  // m, r: the obstruction is the core Minkowski-summed with a disc of radius r
  Vec2 reference_point{};  // m, the point whose y is D (nearest point or centroid)
  double nearest_y = 0;    // m, smallest y of the shape (distance of its nearest point to the gap line)
  Vec2 centroid{};         // m, of the drawn shape
};

// One particle as released (before settling).
struct ParticleSeed {
  Vec2 position;    // m, plane frame
  double diameter;  // m
};

struct CompiledScenario {
  ScenarioDef def;                 // the validated source (lab units as written)
  std::uint64_t scenario_hash = 0; // hash of canonical_toml(def)
  std::uint64_t run_seed = 0;      // mix(scenario_hash, run.seed, run.replicate)

  // Lab-unit quantities in SI.
  double incline = 0;            // rad
  double lateral_tilt = 0;       // rad, phi: roll of the board about its fall line
  double nominal_diameter = 0;   // m, d
  double gap = 0;                // m, the tips' real distance W + delta (what the walls are built for)
  double declared_gap = 0;       // m, W as declared (bottleneck.gap_mm): what records and W/d report
  double channel_width = 0;      // m, between retaining walls
  double plane_length = 0;       // m, gap line to top wall
  double wall_angle = 0;         // rad, bottleneck wall to the retaining wall
  double wall_thickness = 0;     // m
  double funnel_height = 0;      // m, y where the bottleneck walls meet the retaining walls
  double barrier_y = 0;          // m, release barrier line
  double density = 0;            // kg/m^3

  // Walls (static unless shaken). Bottleneck walls are convex quads; the inner
  // face of the right wall runs from the right gap tip (W/2, 0) to (width/2, funnel_height).
  ConvexPolygon left_bottleneck_wall;
  ConvexPolygon right_bottleneck_wall;
  ConvexPolygon left_retaining_wall;   // a thick box outside x = -width/2
  ConvexPolygon right_retaining_wall;  // a thick box outside x = +width/2
  ConvexPolygon top_wall;              // closes the board above y = plane_length
  ConvexPolygon barrier;               // the release barrier (removed at t = 0)
  Vec2 left_tip, right_tip;            // m, the gap tips (inner corners)
  Vec2 left_wall_normal, right_wall_normal;  // unit inward normals of the bottleneck walls' inner faces

  ObstructionGeometry obstruction;

  std::vector<ParticleSeed> particles;  // count entries, index = particle id

  // Derived, for reports.
  double w_over_d() const { return declared_gap / nominal_diameter; }
  // Gravity component down the fall line (-y), m/s^2 (g sin theta).
  double inplane_gravity() const;
  // Gravity component across the channel (+x), m/s^2 (g cos theta sin phi).
  double across_gravity() const;
  // Gravity component normal to the board, m/s^2 (g cos theta cos phi).
  double normal_gravity() const;
  // Half-width of the open channel at height y (funnel or retaining walls), m.
  double half_width_at(double y) const;
};

// Validate cross-field constraints and build the geometry and the particle packing.
// Throws ScenarioInvalid (scenario_loader.hpp) naming the offending key.
CompiledScenario compile_scenario(const ScenarioDef& def);

// Distance (m) from a point to the inner face of the nearest bottleneck wall (positive inside the funnel).
double clearance_to_bottleneck_walls(const CompiledScenario& c, Vec2 p);
// Whether a disc of `radius` (m) centred at p lies on the open board: inside the
// retaining and bottleneck walls, clear of the obstruction, below the top wall, above the gap line.
bool fits_on_board(const CompiledScenario& c, Vec2 p, double radius);
// Distance (m) from a point to the outline of `g` (the compiled rest position, or one
// displaced by shaking; negative inside; huge without an obstruction).
double obstruction_distance(const ObstructionGeometry& g, Vec2 p);
// Whether the segment [a, b] passes through the obstruction (touching its outline does not count
// for a cylinder; for a polygon it does).
bool obstruction_blocks_segment(const ObstructionGeometry& g, Vec2 a, Vec2 b);
// The convex polygon moved inward by `distance` (m): every edge shifted along its inward
// normal, edges that vanish dropped (an erosion by a disc). Empty when nothing is left.
ConvexPolygon inward_offset(const ConvexPolygon& polygon, double distance);
// Radius (m) of the largest disc inside a convex polygon.
double inradius(const ConvexPolygon& polygon);
// Smallest clearance (m) between the obstruction and the bottleneck/retaining walls (negative = overlap).
double obstruction_wall_clearance(const CompiledScenario& c);

}  // namespace gapflow
