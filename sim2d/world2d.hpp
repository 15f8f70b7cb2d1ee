// The Box2D world built from a CompiledScenario, in engine units.
//
// The board is seen from above: x across the channel, y uphill, gravity pulls
// toward -y with the in-plane component g sin(theta) (reduced by the rolling
// effect). Engine units follow EngineScaling::froude (gravity stays 9.81).
#pragma once

#include "common/geometry.hpp"
#include "common/units.hpp"

#include <box2d/box2d.h>
#include <memory>
#include <vector>

namespace gapflow {

// Fixture user data: what a fixture belongs to (for pair materials). A particle's body
// carries its id + 1 as body user data (0 on every other body).
enum class FixtureKind : uintptr_t { particle = 1, wall = 2 };

// Per-particle constants the effects need (engine units).
struct ParticleProps2D {
  double true_mass = 0;  // mass of the sphere (engine)
  double radius = 0;     // engine length
};

// How a particle body is built: the rolling effect changes these.
struct BodyModel2D {
  double translational_mass_factor = 1.0;  // engine mass = factor * true mass (7/5 for rolling solid spheres)
  double gravity_factor = 1.0;             // world gravity = factor * g sin(theta) (5/7 for rolling)
  double spin_inertia_factor = 0.4;        // I about the board normal / (m r^2): 2/5 for a solid sphere
};

struct World2D {
  EngineScaling scale;
  double dt_engine = 0;  // engine s per step
  int velocity_iterations = 8;
  int position_iterations = 3;
  double normal_gravity = 0;  // engine, g cos(theta): the board's normal force per unit true mass

  std::unique_ptr<b2ContactListener> listener;  // pair materials; declared first so it outlives the world
  std::unique_ptr<b2World> world;
  b2Body* ground = nullptr;      // retaining walls, top wall (static)
  b2Body* left_wall = nullptr;   // bottleneck walls: kinematic when shaken, else static
  b2Body* right_wall = nullptr;
  b2Body* obstruction = nullptr; // kinematic when shaken, else static; null without obstruction
  b2Body* barrier = nullptr;     // present while closed
  b2Vec2 left_wall_rest, right_wall_rest, obstruction_rest;  // engine positions at rest

  std::vector<b2Body*> particles;       // index = particle id; null once retired
  std::vector<ParticleProps2D> props;   // index = particle id
  std::vector<int> active;              // ids still simulated, ascending

  b2Vec2 to_engine(Vec2 p_m) const {
    return {static_cast<float>(scale.to_engine_length(p_m.x)), static_cast<float>(scale.to_engine_length(p_m.y))};
  }
  Vec2 to_lab(b2Vec2 p) const { return {scale.to_lab_length(p.x), scale.to_lab_length(p.y)}; }
};

// Build the world with walls, obstruction, barrier and particles.
std::unique_ptr<World2D> build_world2d(const CompiledScenario& scenario, const BodyModel2D& body_model);

// Create the barrier body (closed) or destroy it (open).
void set_barrier2d(World2D& w, const CompiledScenario& scenario, bool closed);

}  // namespace gapflow
