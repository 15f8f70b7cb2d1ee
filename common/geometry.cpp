// compile_scenario: ScenarioDef (lab mm, degrees) -> CompiledScenario (metres).
// Stages: convert units -> build walls -> place obstruction -> check clearances
// -> pack particles. Every failed check names the scenario key to change.
#include "common/geometry.hpp"

#include "common/input_bounds.hpp"
#include "common/random.hpp"
#include "common/scenario_loader.hpp"
#include "common/units.hpp"
#include "common/vec2_math.hpp"

#include <algorithm>
#include <cmath>
#include <fmt/format.h>

namespace gapflow {

double CompiledScenario::inplane_gravity() const { return kStandardGravity * std::sin(incline); }
double CompiledScenario::across_gravity() const {
  return kStandardGravity * std::cos(incline) * std::sin(lateral_tilt);
}
double CompiledScenario::normal_gravity() const {
  return kStandardGravity * std::cos(incline) * std::cos(lateral_tilt);
}

double CompiledScenario::half_width_at(double y) const {
  if (y >= funnel_height) return channel_width / 2;
  return gap / 2 + std::max(y, 0.0) * std::tan(wall_angle);
}

namespace {

ConvexPolygon box(double x0, double y0, double x1, double y1) {
  return {{{x0, y0}, {x1, y0}, {x1, y1}, {x0, y1}}};
}

ConvexPolygon counter_clockwise(std::vector<Vec2> v) {
  if (signed_area2(v) < 0) std::reverse(v.begin(), v.end());
  return {std::move(v)};
}

ConvexPolygon mirrored_x(const ConvexPolygon& p) {
  std::vector<Vec2> v;
  for (Vec2 q : p.vertices) v.push_back({-q.x, q.y});
  return counter_clockwise(std::move(v));
}

std::string num(double v) { return fmt::format("{:g}", v); }

// --- Stage 1: units ----------------------------------------------------------
void convert_units(const ScenarioDef& def, CompiledScenario& c) {
  c.incline = deg_to_rad(def.plane.incline_deg);
  c.lateral_tilt = deg_to_rad(def.plane.lateral_tilt_deg);
  c.nominal_diameter = mm_to_m(def.particles.diameter_mm);
  c.declared_gap = mm_to_m(def.bottleneck.gap_mm);
  c.gap = mm_to_m(def.bottleneck.gap_mm + def.bottleneck.gap_offset_mm);
  c.channel_width = mm_to_m(def.plane.width_mm);
  c.plane_length = mm_to_m(def.plane.length_mm);
  c.wall_angle = deg_to_rad(def.bottleneck.wall_angle_deg);
  c.wall_thickness = mm_to_m(def.bottleneck.wall_thickness_mm);
  c.barrier_y = mm_to_m(def.release.barrier_mm);
  c.density = def.particles.density_kg_m3;
}

// --- Stage 2: walls ----------------------------------------------------------
void build_walls(CompiledScenario& c) {
  const ScenarioDef& d = c.def;
  if (c.gap >= c.channel_width && d.bottleneck.gap_offset_mm != 0)
    throw ScenarioInvalid("bottleneck.gap_offset_mm", num(d.bottleneck.gap_offset_mm),
                          fmt::format("must keep the effective gap W + delta below plane.width_mm = {}",
                                      num(d.plane.width_mm)));
  if (c.gap >= c.channel_width)
    throw ScenarioInvalid("bottleneck.gap_mm", num(d.bottleneck.gap_mm),
                          fmt::format("must be smaller than plane.width_mm = {}", num(d.plane.width_mm)));
  const double run = (c.channel_width - c.gap) / 2;  // horizontal extent of one bottleneck wall
  // At 90 degrees the walls are flat (a flat-bottomed silo): height 0.
  const bool flat = std::abs(c.wall_angle - kPi / 2) < 1e-12;
  c.funnel_height = flat ? 0.0 : run / std::tan(c.wall_angle);
  if (c.funnel_height + 2 * c.nominal_diameter >= c.plane_length)
    throw ScenarioInvalid("plane.length_mm", num(d.plane.length_mm),
                          fmt::format("must exceed the bottleneck height {:.6g} mm (from plane.width_mm, "
                                      "bottleneck.gap_mm and bottleneck.wall_angle_deg) by at least 2 d",
                                      c.funnel_height * 1e3));

  // Right wall: inner face from the right gap tip up-and-out to the retaining wall;
  // the thickness lies on the outer side (away from the funnel).
  const Vec2 tip{c.gap / 2, 0};
  const Vec2 top{c.channel_width / 2, c.funnel_height};
  const Vec2 outward{std::cos(c.wall_angle), -std::sin(c.wall_angle)};
  const double t = c.wall_thickness;
  c.right_bottleneck_wall = counter_clockwise({tip, tip + t * outward, top + t * outward, top});
  c.left_bottleneck_wall = mirrored_x(c.right_bottleneck_wall);
  c.right_tip = tip;
  c.left_tip = {-tip.x, 0};
  c.right_wall_normal = {-outward.x, -outward.y};
  c.left_wall_normal = {outward.x, -outward.y};

  // Retaining walls, top wall and barrier are thick boxes outside the open board.
  const double thick = std::max(t, 2 * c.nominal_diameter);
  const double w2 = c.channel_width / 2, L = c.plane_length;
  c.right_retaining_wall = box(w2, c.funnel_height - thick, w2 + thick, L + thick);
  c.left_retaining_wall = box(-w2 - thick, c.funnel_height - thick, -w2, L + thick);
  c.top_wall = box(-w2 - thick, L, w2 + thick, L + thick);
  if (c.barrier_y + 2 * c.nominal_diameter >= L)
    throw ScenarioInvalid("release.barrier_mm", num(d.release.barrier_mm),
                          "must leave at least 2 d below plane.length_mm for the packing");
  c.barrier = box(-w2, c.barrier_y - thick, w2, c.barrier_y);
}

// --- Stage 3: obstruction ----------------------------------------------------
std::vector<Vec2> obstruction_outline_local(const ObstructionDef& o) {
  const double s = mm_to_m(o.side_mm);
  const double h = s * std::sqrt(3.0) / 2;
  switch (o.shape) {
    case ObstructionShape::triangle:
      if (o.apex == Apex::away_from_gap) return {{-s / 2, 0}, {s / 2, 0}, {0, h}};
      return {{0, 0}, {s / 2, h}, {-s / 2, h}};
    case ObstructionShape::polygon: {
      std::vector<Vec2> v;
      for (Vec2 p : o.vertices_mm) v.push_back({mm_to_m(p.x), mm_to_m(p.y)});
      return counter_clockwise(std::move(v)).vertices;
    }
    default:
      return {};
  }
}

// The core of a polygon whose corners are rounded with obstruction.corner_radius_mm.
ConvexPolygon round_corners(const ConvexPolygon& drawn, const ObstructionDef& o, double& radius_out) {
  radius_out = mm_to_m(o.corner_radius_mm);
  if (radius_out <= 0) return drawn;
  const double limit = inradius(drawn);
  if (radius_out >= limit)
    throw ScenarioInvalid("obstruction.corner_radius_mm", num(o.corner_radius_mm),
                          fmt::format("must be below the shape's inradius, {:.4g} mm", limit * 1e3));
  return inward_offset(drawn, radius_out);
}

void place_obstruction(CompiledScenario& c) {
  const ObstructionDef& o = c.def.obstruction;
  ObstructionGeometry& g = c.obstruction;
  g.shape = o.shape;
  if (o.shape == ObstructionShape::none) return;
  const double D = mm_to_m(o.distance_mm), dx = mm_to_m(o.lateral_offset_mm);
  const bool by_nearest = o.reference == DistanceReference::nearest;

  if (o.shape == ObstructionShape::cylinder) {
    const double R = mm_to_m(o.diameter_mm) / 2;
    const double cy = by_nearest ? D + R : D;
    g.circle = {{dx, cy}, R};
    g.centroid = {dx, cy};
    g.nearest_y = cy - R;
  } else {
    std::vector<Vec2> v = obstruction_outline_local(o);
    const Vec2 centroid = polygon_centroid(v);
    double ymin = 1e300;
    for (Vec2 p : v) ymin = std::min(ymin, p.y);
    const Vec2 shift{dx - centroid.x, by_nearest ? D - ymin : D - centroid.y};
    for (Vec2& p : v) p = p + shift;
    g.centroid = centroid + shift;
    // Rounded in place: the drawn polygon is placed first, then its corners are rounded, so
    // the faces stay put and a corner's nearest point moves inward.
    g.polygon = round_corners(ConvexPolygon{std::move(v)}, o, g.corner_radius);
    g.nearest_y = 1e300;
    for (Vec2 p : g.polygon.vertices) g.nearest_y = std::min(g.nearest_y, p.y - g.corner_radius);
  }
  g.reference_point = by_nearest ? Vec2{g.centroid.x, g.nearest_y} : g.centroid;
  if (g.nearest_y < 0)
    throw ScenarioInvalid("obstruction.distance_mm", num(o.distance_mm),
                          fmt::format("puts the obstruction across the gap line (nearest point at {:.2f} mm); "
                                      "with reference = \"centre\" D must be at least the distance from the centre "
                                      "to the nearest point",
                                      g.nearest_y * 1e3));
}

// Distance between a convex polygon and a circle or another convex polygon; negative if they overlap.
double distance_convex_convex(const std::vector<Vec2>& a, const std::vector<Vec2>& b) {
  for (Vec2 p : a)
    if (inside_convex(b, p)) return -1;
  for (Vec2 p : b)
    if (inside_convex(a, p)) return -1;
  // Two convex polygons can also cross with no vertex inside the other (a cross shape).
  for (size_t i = 0; i < a.size(); ++i)
    for (size_t j = 0; j < b.size(); ++j)
      if (segments_intersect(a[i], a[(i + 1) % a.size()], b[j], b[(j + 1) % b.size()])) return -1;
  double d = 1e300;
  for (Vec2 p : a) d = std::min(d, signed_distance_to_convex(b, p));
  for (Vec2 p : b) d = std::min(d, signed_distance_to_convex(a, p));
  return d;
}

double distance_obstruction_to(const ObstructionGeometry& g, const ConvexPolygon& wall) {
  if (g.shape == ObstructionShape::cylinder)
    return signed_distance_to_convex(wall.vertices, g.circle.centre) - g.circle.radius;
  const double d = distance_convex_convex(g.polygon.vertices, wall.vertices);
  return d < 0 ? d : d - g.corner_radius;
}

// The obstruction's centre must lie on the open board: between the retaining walls and
// inside the funnel (with the overlap check below, the whole obstruction then does).
void check_obstruction_on_board(const CompiledScenario& c) {
  const Vec2 centre = c.obstruction.centroid;
  if (std::abs(centre.x) < c.channel_width / 2 && clearance_to_bottleneck_walls(c, centre) > 0) return;
  const ObstructionDef& o = c.def.obstruction;
  throw ScenarioInvalid("obstruction.lateral_offset_mm", num(o.lateral_offset_mm),
                        fmt::format("puts the obstruction's centre (x = {:.6g} mm, y = {:.6g} mm) outside the board "
                                    "(|x| < plane.width_mm / 2 = {:.6g} mm, above the funnel walls)",
                                    centre.x * 1e3, centre.y * 1e3, c.channel_width / 2 * 1e3));
}

void check_obstruction_clearance(const CompiledScenario& c) {
  if (c.obstruction.shape == ObstructionShape::none) return;
  check_obstruction_on_board(c);
  const double clearance = obstruction_wall_clearance(c);
  if (clearance <= 0)
    throw ScenarioInvalid("obstruction.distance_mm", num(c.def.obstruction.distance_mm),
                          fmt::format("makes the obstruction overlap a wall (clearance {:.2f} mm); move it "
                                      "further from the gap, or reduce its size or lateral offset",
                                      clearance * 1e3));
  const double top = c.obstruction.shape == ObstructionShape::cylinder
                         ? c.obstruction.circle.centre.y + c.obstruction.circle.radius
                         : [&] {
                             double y = -1e300;
                             for (Vec2 p : c.obstruction.polygon.vertices) y = std::max(y, p.y);
                             return y + c.obstruction.corner_radius;
                           }();
  if (top + 2 * c.nominal_diameter >= c.plane_length)
    throw ScenarioInvalid("obstruction.distance_mm", num(c.def.obstruction.distance_mm),
                          "puts the obstruction within 2 d of the top wall");
}

// --- Stage 4: particles ------------------------------------------------------
double particle_size_factor(const ParticlesDef& p, const RunDef& run, int index) {
  RandomStream rs = particle_stream(run.seed, run.replicate, StreamPurpose::size, static_cast<std::uint64_t>(index));
  const double s = p.size_scatter;
  switch (p.size_distribution) {
    case SizeDistribution::none:
      return 1.0;
    case SizeDistribution::uniform:
      return 1.0 + rs.uniform(-s, s);
    case SizeDistribution::normal:
      return 1.0 + std::clamp(0.5 * s * rs.normal(), -s, s);
  }
  return 1.0;
}

// Particles sit on a triangular lattice above the barrier, spaced for the
// largest possible diameter plus lattice_gap, and jittered inside the free
// space so that no two overlap. Particle i's size and jitter come from its own
// random streams: changing the geometry moves particles between sites but does
// not change which sizes exist.
void pack_particles(CompiledScenario& c) {
  const ParticlesDef& p = c.def.particles;
  const double d_max = c.nominal_diameter * (1 + p.size_scatter);
  const double a = d_max * (1 + c.def.release.lattice_gap);
  const double row_pitch = a * std::sqrt(3.0) / 2;
  const double jitter = (a - d_max) / (2 * std::sqrt(2.0));
  const double w2 = c.channel_width / 2;

  c.particles.clear();
  c.particles.reserve(p.count);
  // A board many thousands of diameters wide would be scanned site by site for ever:
  // the scan is bounded (kMaxPackingSites) and the limit reported.
  const std::int64_t sites_per_row = 2 * (static_cast<std::int64_t>(std::min(w2 / a, 1e12)) + 2) + 1;
  std::int64_t scanned = 0;
  for (int row = 0; static_cast<int>(c.particles.size()) < p.count; ++row) {
    scanned += sites_per_row;
    if (scanned > kMaxPackingSites)
      throw ScenarioInvalid("particles.diameter_mm", num(p.diameter_mm),
                            fmt::format("the packing would scan more than {} lattice sites (plane.width_mm / d = "
                                        "{:.6g}): use larger particles or a smaller board",
                                        kMaxPackingSites, c.channel_width / c.nominal_diameter));
    const double y = c.barrier_y + a / 2 + row * row_pitch;
    if (y > c.plane_length - a / 2) {
      throw ScenarioInvalid(
          "particles.count", std::to_string(p.count),
          fmt::format("only {} particles fit between the barrier and the top wall; lengthen plane.length_mm "
                      "or widen plane.width_mm",
                      c.particles.size()));
    }
    const double offset = (row % 2) ? a / 2 : 0.0;
    const int half_sites = static_cast<int>(std::ceil(w2 / a)) + 1;
    for (int j = -half_sites; j <= half_sites && static_cast<int>(c.particles.size()) < p.count; ++j) {
      const Vec2 site{j * a + offset, y};
      if (!fits_on_board(c, site, a / 2)) continue;
      const int id = static_cast<int>(c.particles.size());
      RandomStream place = particle_stream(c.def.run.seed, c.def.run.replicate, StreamPurpose::placement,
                                           static_cast<std::uint64_t>(id));
      const Vec2 shift{place.uniform(-jitter, jitter), place.uniform(-jitter, jitter)};
      c.particles.push_back({site + shift, c.nominal_diameter * particle_size_factor(p, c.def.run, id)});
    }
  }
}

}  // namespace

double obstruction_distance(const ObstructionGeometry& g, Vec2 p) {
  switch (g.shape) {
    case ObstructionShape::none:
      return 1e300;
    case ObstructionShape::cylinder:
      return length(p - g.circle.centre) - g.circle.radius;
    default:
      return signed_distance_to_convex(g.polygon.vertices, p) - g.corner_radius;
  }
}

bool obstruction_blocks_segment(const ObstructionGeometry& g, Vec2 a, Vec2 b) {
  switch (g.shape) {
    case ObstructionShape::none:
      return false;
    case ObstructionShape::cylinder:
      return distance_to_segment(g.circle.centre, a, b) < g.circle.radius;
    default: {
      const std::vector<Vec2>& v = g.polygon.vertices;
      if (inside_convex(v, a) || inside_convex(v, b)) return true;
      for (size_t i = 0; i < v.size(); ++i)
        if (segments_intersect(a, b, v[i], v[(i + 1) % v.size()])) return true;
      if (g.corner_radius <= 0) return false;
      // Rounded: the segment passes through the shape if it comes closer than r to the core.
      // Neither crosses the other here, so the closest pair involves an end point.
      for (size_t i = 0; i < v.size(); ++i) {
        const Vec2 c = v[i], e = v[(i + 1) % v.size()];
        const double d = std::min({distance_to_segment(c, a, b), distance_to_segment(a, c, e),
                                   distance_to_segment(b, c, e)});
        if (d < g.corner_radius) return true;
      }
      return false;
    }
  }
}

double clearance_to_bottleneck_walls(const CompiledScenario& c, Vec2 p) {
  const Vec2 right_top{c.channel_width / 2, c.funnel_height};
  const Vec2 left_top{-c.channel_width / 2, c.funnel_height};
  auto signed_to = [&](Vec2 tip, Vec2 top, Vec2 inward) {
    const double d = distance_to_segment(p, tip, top);
    return dot(p - tip, inward) >= 0 ? d : -d;
  };
  return std::min(signed_to(c.right_tip, right_top, c.right_wall_normal),
                  signed_to(c.left_tip, left_top, c.left_wall_normal));
}

bool fits_on_board(const CompiledScenario& c, Vec2 p, double radius) {
  return std::abs(p.x) <= c.channel_width / 2 - radius && p.y >= radius && p.y <= c.plane_length - radius &&
         clearance_to_bottleneck_walls(c, p) >= radius && obstruction_distance(c.obstruction, p) >= radius;
}

ConvexPolygon inward_offset(const ConvexPolygon& polygon, double distance) {
  // Clip the polygon by each edge's half-plane shifted inward (Sutherland-Hodgman).
  const std::vector<Vec2>& src = polygon.vertices;
  std::vector<Vec2> out = src;
  for (size_t i = 0; i < src.size() && !out.empty(); ++i) {
    const Vec2 a = src[i], b = src[(i + 1) % src.size()];
    const Vec2 edge = b - a;
    const Vec2 n = (1.0 / length(edge)) * Vec2{-edge.y, edge.x};  // inward (counter-clockwise polygon)
    auto inside = [&](Vec2 p) { return dot(p - a, n) - distance; };
    std::vector<Vec2> kept;
    for (size_t k = 0; k < out.size(); ++k) {
      const Vec2 p = out[k], q = out[(k + 1) % out.size()];
      const double sp = inside(p), sq = inside(q);
      if (sp >= 0) kept.push_back(p);
      if ((sp >= 0) != (sq >= 0)) kept.push_back(p + (sp / (sp - sq)) * (q - p));
    }
    out = std::move(kept);
  }
  // Merge points that clipping made coincide (an edge that shrank to nothing).
  std::vector<Vec2> merged;
  const double tol = 1e-12 * std::max(1.0, distance);
  for (Vec2 p : out)
    if (merged.empty() || length(p - merged.back()) > tol) merged.push_back(p);
  while (merged.size() > 1 && length(merged.front() - merged.back()) <= tol) merged.pop_back();
  if (merged.size() < 3 || signed_area2(merged) <= 0) return {};
  return {std::move(merged)};
}

double inradius(const ConvexPolygon& polygon) {
  double lo = 0, hi = 0;
  for (Vec2 p : polygon.vertices)
    for (Vec2 q : polygon.vertices) hi = std::max(hi, length(p - q));
  for (int i = 0; i < 100 && hi - lo > 1e-12 * hi; ++i) {
    const double mid = (lo + hi) / 2;
    (inward_offset(polygon, mid).vertices.empty() ? hi : lo) = mid;
  }
  return lo;
}

double obstruction_wall_clearance(const CompiledScenario& c) {
  const ObstructionGeometry& g = c.obstruction;
  if (g.shape == ObstructionShape::none) return 1e300;
  double d = 1e300;
  for (const ConvexPolygon* wall : {&c.left_bottleneck_wall, &c.right_bottleneck_wall, &c.left_retaining_wall,
                                    &c.right_retaining_wall, &c.top_wall})
    d = std::min(d, distance_obstruction_to(g, *wall));
  return d;
}

CompiledScenario compile_scenario(const ScenarioDef& def) {
  CompiledScenario c;
  c.def = def;
  c.scenario_hash = scenario_hash(def);
  c.run_seed = run_seed(c.scenario_hash, def.run.seed, def.run.replicate);
  convert_units(def, c);
  build_walls(c);
  place_obstruction(c);
  check_obstruction_clearance(c);
  pack_particles(c);
  return c;
}

}  // namespace gapflow
