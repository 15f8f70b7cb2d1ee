// Scenario description shared by the 2D and 3D models.
//
// Everything here is in LAB units (mm, degrees, s, kg/m^3) exactly as written in
// the scenario TOML file; each field name is its TOML key inside its section.
// The loader (scenario_loader.cpp) fills these structs and validates them;
// compile_scenario (geometry.hpp) turns them into engine-independent geometry in
// metres. Engines never read TOML.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

namespace gapflow {

struct Vec2 {
  double x = 0;  // mm in ScenarioDef, m in compiled geometry
  double y = 0;
};

// [plane] The inclined board. Plane frame: x across the channel (0 on the axis),
// y uphill (0 on the gap line), z normal to the board.
struct PlaneDef {
  double incline_deg = 8.0;   // deg, angle of the board to the horizontal (paper: 8)
  double length_mm = 1000.0;  // mm, from the gap line to the top wall
  double width_mm = 300.0;    // mm, between the retaining walls
  double lateral_tilt_deg = 0.0;  // deg, roll of the board about its fall line: gravity gains
                                  // g cos(theta) sin(phi) along +x, the normal part becomes g cos(theta) cos(phi)
  double cover_gap_mm = 0.0;      // mm, a cover plate parallel to the board this far above it (0 = none): the
                                  // monolayer cell of a vertical silo (3D; the 2D model is a monolayer already)
};

// [bottleneck] Two walls from the retaining walls down to the gap.
struct BottleneckDef {
  double wall_angle_deg = 30.0;    // deg, to the retaining walls (paper: 30; 90 = flat-bottomed silo)
  double gap_mm = 33.0;            // mm, W: distance between the two wall tips
  double wall_thickness_mm = 10.0; // mm, measured normal to the wall's inner face
  double gap_offset_mm = 0.0;      // mm, delta: the tips stand W + delta apart (walls not where drawn);
                                   // records and W/d keep the declared W
};

enum class SizeDistribution { none, uniform, normal };

// [particles] Spheres (3D) / discs (2D).
struct ParticlesDef {
  int count = 1551;                 // particles (paper's model: 1551)
  double diameter_mm = 7.75;        // mm, nominal d; presets: small 6.15, medium 7.75, large 11.9
  double size_scatter = 0.05;       // relative half-width of the size scatter (<= 0.05 in the paper)
  SizeDistribution size_distribution = SizeDistribution::uniform;  // uniform: d(1+U(-s,s)); normal: sigma=s/2 cut at +-s
  double density_kg_m3 = 2500.0;    // kg/m^3 (glass)
  double friction_particle = 0.24;  // pair Coulomb coefficient particle-particle (paper fit: 0.24)
  double friction_wall = 0.24;      // pair Coulomb coefficient particle-wall and particle-obstruction
  double friction_base = 0.24;      // pair Coulomb coefficient particle-board (3D; 2D assumes rolling)
  double restitution = 0.1;         // pair coefficient of restitution (paper: little effect)
  double rolling_resistance = 0.0;  // dimensionless: resisting force / normal force on the board
  double spinning_friction_mm = 0.0;// mm, torsional friction length about the contact normal (3D)
  double drag_per_s = 0.0;          // 1/s, gamma: linear drag force -gamma m v on each particle's translation
  double quadratic_drag_per_m = 0.0;// 1/m, c: quadratic drag force -c m |v| v on each particle's translation
};

// [release] Particles are packed from rest above a barrier that opens at t = 0.
struct ReleaseDef {
  double barrier_mm = 0.0;     // mm, barrier line distance uphill from the gap line (0: at the gap)
  double settle_s = 0.5;       // s, settling time against the closed barrier before t = 0
  double lattice_gap = 0.03;   // fraction of the largest diameter left free between lattice sites
};

enum class ObstructionShape { none, cylinder, triangle, polygon };
enum class DistanceReference { nearest, centre };
enum class Apex { away_from_gap, toward_gap };

// [obstruction] In front of the gap. shape = "A" and "V" are triangle presets.
struct ObstructionDef {
  ObstructionShape shape = ObstructionShape::none;
  std::string preset;                 // "A", "V" or "" (informational, for reports)
  double diameter_mm = 50.0;          // mm, cylinder diameter
  double side_mm = 20.0;              // mm, side of the equilateral triangle
  Apex apex = Apex::away_from_gap;    // triangle orientation ("A": away, "V": toward)
  std::vector<Vec2> vertices_mm;      // mm, polygon vertices (convex, counter-clockwise), local frame
  double distance_mm = 0.0;           // mm, D: gap line to the reference point, measured uphill
  DistanceReference reference = DistanceReference::nearest;  // nearest point of the shape, or its centre (centroid)
  double lateral_offset_mm = 0.0;     // mm, shift across the channel (+x)
  double corner_radius_mm = 0.0;      // mm, triangle/polygon corners rounded in place (faces stay; < inradius)
};

// [shaking.walls] and [shaking.obstruction]: decaying oscillation every period.
// displacement(t) = A (1 - tau/decay) sin(2 pi f tau) along direction, tau = (t - start) mod period < decay.
struct ShakeDef {
  bool enabled = false;
  double amplitude_mm = 0.5;    // mm, peak displacement at the start of a shake
  double direction_deg = 0.0;   // deg from +x (across the channel), counter-clockwise in the plane
  bool mirror = true;           // walls only: the left wall moves with the x component mirrored
  double decay_s = 1.0;         // s, amplitude falls linearly to zero over this time
  double period_s = 5.0;        // s, time between the starts of two shakes
  double start_s = 0.0;         // s, first shake starts at this time after release
  double frequency_hz = 20.0;   // Hz, oscillation frequency inside a shake
};

struct ShakingDef {
  ShakeDef walls;        // bottleneck walls
  ShakeDef obstruction;  // the obstruction
};

// [protocol] What is done about clogs and passed particles (besides the shaking schedules).
enum class ClogBreaking {
  shaking,             // nothing more: only the [shaking.*] schedules (the paper's protocol)
  local_perturbation,  // after clog_timeout_s without a crossing: lift the particles that see the gap onto the pile
  refill               // after clog_timeout_s without a crossing: put every particle back into the initial packing
};
struct ProtocolDef {
  ClogBreaking clog_breaking = ClogBreaking::shaking;
  bool reinject_passed = false;    // passed particles are put back on top of the pile (steady state; ends by time or n_passed)
  double perturb_radius_d = 3.0;   // local_perturbation: candidates within W/2 + this many d of the gap centre
};

enum class EndCondition { all_passed, time_limit, n_passed };

// [run]
struct RunDef {
  EndCondition end = EndCondition::all_passed;
  double time_limit_s = 600.0;      // s, hard limit on simulated time after release (all end conditions)
  int n_passed = 0;                 // particles, for end = "n_passed"
  double clog_timeout_s = 1.0;      // s, no crossing for this long = a clog
  double stop_after_no_flow_s = 30.0; // s, stop (permanent clog) after this long without a crossing; 0 = never
  int stranded_max = 0;             // particles that may be left when the run ends (any reason) and the
                                    // discharge still counts as complete for J_paper (a sphere balanced on
                                    // an obstruction's flat upstream face never leaves; the paper's J = N/T
                                    // is then taken over the particles that did pass)
  std::uint64_t seed = 1;           // base seed
  int replicate = 0;                // replicate index (mixed into the run seed)
};

// [model.box2d] (effects: [model.box2d.rolling], [model.box2d.base_friction])
enum class BaseFrictionMethod { force, joint };
struct Box2DRollingDef {
  bool enabled = true;
  double inertia_factor = 0.4;  // I/(m r^2) of the rolling body: 0.4 solid sphere, 2/3 hollow sphere
};
struct Box2DBaseFrictionDef {
  bool enabled = true;  // resistance from the board, coefficient particles.rolling_resistance
  BaseFrictionMethod method = BaseFrictionMethod::force;
};
struct Box2DDef {
  double time_step_s = 0.001;       // s (lab), chosen by the convergence study (README, results/convergence-2d)
  int velocity_iterations = 8;      // 4 save 17 % but move <s> up (+19 +- 27 %, results/convergence-2d)
  int position_iterations = 3;
  bool sleeping = false;            // engine sleeping freezes slow particles and fakes clogs
  bool continuous_collision = false;// Box2D's time-of-impact pass: 19 % of the instructions, unneeded while a
                                    // particle moves < 0.1 d per step against walls thicker than d
  double engine_diameter = 1.0;     // engine length units per nominal particle diameter (Froude scaling)
  double rolling_contact = 0.0;     // fraction (0-1) of the derived vertical sliding friction at contacts of
                                    // rolling spheres (RollingContactEffect); 0 = off. 2D only: 3D has it natively
  double spin_inertia_factor = 0.4; // I/(m r^2) about the board normal with rolling off: 0.4 a solid sphere
                                    // (Janda's beads), 0.5 a flat disc (To's disks); rolling on uses its own
  Box2DRollingDef rolling;
  Box2DBaseFrictionDef base_friction;
};

// [model.bullet]
struct BulletDef {
  double time_step_s = 0.001;       // s (lab); the largest step within 1 % in J and J/J_0 (README, convergence-3d, -ratio-3d)
  int substeps = 1;                 // engine steps per time_step_s
  int solver_iterations = 10;
  bool sleeping = false;
  double engine_diameter = 1.0;     // engine length units per nominal particle diameter
  double wall_height_d = 2.0;       // wall height in particle diameters (>= 1.5)
  double collision_margin_d = 0.02; // collision margin of boxes/hulls in particle diameters
};

struct ModelDef {
  Box2DDef box2d;
  BulletDef bullet;
};

struct ScenarioDef {
  std::string name;          // [scenario] name
  std::string description;   // [scenario] description
  PlaneDef plane;
  BottleneckDef bottleneck;
  ParticlesDef particles;
  ReleaseDef release;
  ObstructionDef obstruction;
  ShakingDef shaking;
  ProtocolDef protocol;
  RunDef run;
  ModelDef model;
};

const char* to_string(SizeDistribution v);
const char* to_string(ObstructionShape v);
const char* to_string(DistanceReference v);
const char* to_string(Apex v);
const char* to_string(EndCondition v);
const char* to_string(ClogBreaking v);
const char* to_string(BaseFrictionMethod v);

}  // namespace gapflow
