#include "sim2d/world2d.hpp"

#include "common/vec2_math.hpp"

#include <cmath>
#include <stdexcept>

namespace gapflow {

namespace {

// Pair materials. Box2D mixes friction as sqrt(f1 f2) and restitution as
// max(e1, e2); the scenario gives PAIR values, so set them per contact.
class PairMaterials final : public b2ContactListener {
 public:
  PairMaterials(float particle_particle, float particle_wall)
      : mu_pp_(particle_particle), mu_pw_(particle_wall) {}
  void PreSolve(b2Contact* contact, const b2Manifold*) override {
    const bool a_wall = kind(contact->GetFixtureA()) == FixtureKind::wall;
    const bool b_wall = kind(contact->GetFixtureB()) == FixtureKind::wall;
    contact->SetFriction(a_wall || b_wall ? mu_pw_ : mu_pp_);
  }

 private:
  static FixtureKind kind(b2Fixture* f) { return static_cast<FixtureKind>(f->GetUserData().pointer); }
  float mu_pp_, mu_pw_;
};

b2FixtureDef wall_fixture(const b2Shape* shape, const ParticlesDef& p, float restitution_threshold) {
  b2FixtureDef f;
  f.shape = shape;
  f.friction = static_cast<float>(p.friction_wall);
  f.restitution = static_cast<float>(p.restitution);
  f.restitutionThreshold = restitution_threshold;
  f.userData.pointer = static_cast<uintptr_t>(FixtureKind::wall);
  return f;
}

// Add a convex polygon (lab metres, relative to `origin_m`) to a body; polygons
// with more than b2_maxPolygonVertices vertices are split into a fan. A `rounding_m` > 0
// becomes the shape's skin (m_radius): Box2D's polygon-circle collision measures
// separation from the polygon minus m_radius, so the shape is the polygon
// Minkowski-summed with a disc (every fan piece rounded: the union is the same shape).
void add_polygon(World2D& w, b2Body* body, const std::vector<Vec2>& vertices, Vec2 origin_m,
                 const ParticlesDef& p, float threshold, double rounding_m = 0) {
  std::vector<b2Vec2> v;
  for (Vec2 q : vertices) v.push_back(w.to_engine(q - origin_m));
  const size_t max_n = b2_maxPolygonVertices;
  for (size_t start = 1; start + 1 < v.size(); start += max_n - 2) {
    std::vector<b2Vec2> piece{v[0]};
    for (size_t i = start; i < v.size() && piece.size() < max_n; ++i) piece.push_back(v[i]);
    // Box2D 2.4 welds vertices closer than linearSlop and silently replaces a
    // degenerate hull by a unit box: check that every vertex survived.
    b2PolygonShape shape;
    shape.Set(piece.data(), static_cast<int32>(piece.size()));
    if (shape.m_count != static_cast<int32>(piece.size()))
      throw std::runtime_error("Box2D rejected a wall or obstruction polygon (vertices closer than its slop at "
                               "this engine scale: raise model.box2d.engine_diameter)");
    if (rounding_m > 0) shape.m_radius = static_cast<float>(w.scale.to_engine_length(rounding_m));
    b2FixtureDef f = wall_fixture(&shape, p, threshold);
    body->CreateFixture(&f);
  }
}

b2Body* make_body(World2D& w, b2BodyType type, Vec2 origin_m) {
  b2BodyDef def;
  def.type = type;
  def.position = w.to_engine(origin_m);
  return w.world->CreateBody(&def);
}

Vec2 lowest_vertex(const ConvexPolygon& p) {
  Vec2 best = p.vertices.front();
  for (Vec2 q : p.vertices)
    if (q.y < best.y) best = q;
  return best;
}

}  // namespace

std::unique_ptr<World2D> build_world2d(const CompiledScenario& sc, const BodyModel2D& model) {
  auto w = std::make_unique<World2D>();
  const ScenarioDef& def = sc.def;
  const Box2DDef& engine = def.model.box2d;
  w->scale = EngineScaling::froude(sc.nominal_diameter, engine.engine_diameter);
  w->dt_engine = w->scale.to_engine_time(engine.time_step_s);
  w->velocity_iterations = engine.velocity_iterations;
  w->position_iterations = engine.position_iterations;
  w->normal_gravity = w->scale.to_engine_acceleration(sc.normal_gravity());

  // In-plane gravity: down the fall line (-y) and, on a laterally tilted board, across (+x).
  const double g_down = w->scale.to_engine_acceleration(sc.inplane_gravity()) * model.gravity_factor;
  const double g_across = w->scale.to_engine_acceleration(sc.across_gravity()) * model.gravity_factor;
  w->world = std::make_unique<b2World>(b2Vec2(static_cast<float>(g_across), static_cast<float>(-g_down)));
  w->world->SetAllowSleeping(engine.sleeping);
  w->world->SetContinuousPhysics(engine.continuous_collision);
  w->listener = std::make_unique<PairMaterials>(static_cast<float>(def.particles.friction_particle),
                                                static_cast<float>(def.particles.friction_wall));
  w->world->SetContactListener(w->listener.get());

  // Box2D treats slower impacts as perfectly inelastic below a threshold fixed
  // in engine m/s; express it in the particle's own velocity scale sqrt(g d) so
  // that the result does not depend on the engine scale.
  const auto threshold = static_cast<float>(
      w->scale.to_engine_velocity(0.1 * std::sqrt(kStandardGravity * sc.nominal_diameter)));
  const ParticlesDef& p = def.particles;

  // Static frame: retaining walls and top wall.
  w->ground = make_body(*w, b2_staticBody, {0, 0});
  for (const ConvexPolygon* poly : {&sc.left_retaining_wall, &sc.right_retaining_wall, &sc.top_wall})
    add_polygon(*w, w->ground, poly->vertices, {0, 0}, p, threshold);

  // Bottleneck walls: kinematic when shaken so that they follow the schedule exactly.
  const b2BodyType wall_type = def.shaking.walls.enabled ? b2_kinematicBody : b2_staticBody;
  const Vec2 left_origin = lowest_vertex(sc.left_bottleneck_wall);
  const Vec2 right_origin = lowest_vertex(sc.right_bottleneck_wall);
  w->left_wall = make_body(*w, wall_type, left_origin);
  w->right_wall = make_body(*w, wall_type, right_origin);
  add_polygon(*w, w->left_wall, sc.left_bottleneck_wall.vertices, left_origin, p, threshold);
  add_polygon(*w, w->right_wall, sc.right_bottleneck_wall.vertices, right_origin, p, threshold);
  w->left_wall_rest = w->left_wall->GetPosition();
  w->right_wall_rest = w->right_wall->GetPosition();

  if (sc.obstruction.shape != ObstructionShape::none) {
    const b2BodyType type = def.shaking.obstruction.enabled ? b2_kinematicBody : b2_staticBody;
    const Vec2 origin = sc.obstruction.centroid;
    w->obstruction = make_body(*w, type, origin);
    if (sc.obstruction.shape == ObstructionShape::cylinder) {
      b2CircleShape circle;
      circle.m_radius = static_cast<float>(w->scale.to_engine_length(sc.obstruction.circle.radius));
      b2FixtureDef f = wall_fixture(&circle, p, threshold);
      w->obstruction->CreateFixture(&f);
    } else {
      add_polygon(*w, w->obstruction, sc.obstruction.polygon.vertices, origin, p, threshold,
                  sc.obstruction.corner_radius);
    }
    w->obstruction_rest = w->obstruction->GetPosition();
  }

  // Particles: discs whose mass and spin inertia are those of the sphere (scaled
  // by the body model). Engine density 1 per cubic engine unit: only ratios matter.
  const double k_mass = model.translational_mass_factor;
  w->particles.reserve(sc.particles.size());
  for (size_t i = 0; i < sc.particles.size(); ++i) {
    const ParticleSeed& seed = sc.particles[i];
    const double r = w->scale.to_engine_length(seed.diameter) / 2;
    const double true_mass = (4.0 / 3.0) * kPi * r * r * r;
    b2BodyDef bd;
    bd.type = b2_dynamicBody;
    bd.position = w->to_engine(seed.position);
    bd.userData.pointer = static_cast<uintptr_t>(i + 1);  // particle id + 1 (0: not a particle)
    b2Body* body = w->world->CreateBody(&bd);
    b2CircleShape circle;
    circle.m_radius = static_cast<float>(r);
    b2FixtureDef f;
    f.shape = &circle;
    f.density = 1.0f;  // replaced by SetMassData below
    f.friction = static_cast<float>(p.friction_particle);
    f.restitution = static_cast<float>(p.restitution);
    f.restitutionThreshold = threshold;
    f.userData.pointer = static_cast<uintptr_t>(FixtureKind::particle);
    body->CreateFixture(&f);
    b2MassData md;
    md.mass = static_cast<float>(k_mass * true_mass);
    md.center.SetZero();
    md.I = static_cast<float>(model.spin_inertia_factor * true_mass * r * r);
    body->SetMassData(&md);
    w->particles.push_back(body);
    w->props.push_back({true_mass, r});
    w->active.push_back(static_cast<int>(i));
  }
  return w;
}

void set_barrier2d(World2D& w, const CompiledScenario& sc, bool closed) {
  if (closed && !w.barrier) {
    w.barrier = make_body(w, b2_staticBody, {0, 0});
    add_polygon(w, w.barrier, sc.barrier.vertices, {0, 0}, sc.def.particles, 0.0f);
  } else if (!closed && w.barrier) {
    w.world->DestroyBody(w.barrier);
    w.barrier = nullptr;
  }
}

}  // namespace gapflow
