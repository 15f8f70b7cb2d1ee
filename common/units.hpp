// Units and scaling.
//
// Three systems, converted in one place:
//  * lab units: SI metres, seconds (the scenario's mm and degrees become m and rad
//    in compile_scenario);
//  * dimensionless units: d = 1 (nominal particle diameter), g = 1 (standard
//    gravity, 9.81 m/s^2) -- the paper's J*sqrt(d/g), W/d, D/d;
//  * engine units: lengths multiplied by `length` so that a particle is
//    `engine_diameter` long (engines are tuned for 0.1-10 units), time multiplied
//    by `time` = sqrt(length) so that the engine's gravity stays g (Froude
//    scaling: v^2/(g L) is the same in lab and engine).
#pragma once

#include <cmath>

namespace gapflow {

inline constexpr double kStandardGravity = 9.81;  // m/s^2, the g of the dimensionless form
inline constexpr double kPi = 3.14159265358979323846;

inline double deg_to_rad(double deg) { return deg * kPi / 180.0; }
inline double rad_to_deg(double rad) { return rad * 180.0 / kPi; }
inline double mm_to_m(double mm) { return mm * 1e-3; }

// Lab <-> engine Froude scaling.
struct EngineScaling {
  double length = 1.0;  // engine length units per lab metre
  double time = 1.0;    // engine seconds per lab second (= sqrt(length))

  static EngineScaling froude(double nominal_diameter_m, double engine_diameter) {
    EngineScaling s;
    s.length = engine_diameter / nominal_diameter_m;
    s.time = std::sqrt(s.length);
    return s;
  }
  double to_engine_length(double m) const { return m * length; }
  double to_lab_length(double e) const { return e / length; }
  double to_engine_time(double s) const { return s * time; }
  double to_lab_time(double e) const { return e / time; }
  double to_engine_velocity(double m_per_s) const { return m_per_s * length / time; }
  double to_lab_velocity(double e) const { return e * time / length; }
  // Acceleration scales as length/time^2 = 1 under Froude scaling; kept explicit.
  // A rate (1/s), e.g. a drag coefficient per second.
  double to_engine_rate(double per_s) const { return per_s / time; }
  double to_engine_acceleration(double m_per_s2) const { return m_per_s2 * length / (time * time); }
  double to_engine_mass(double kg) const { return kg * length * length * length; }  // same density number
};

// Dimensionless flow rate J*sqrt(d/g) with g = standard gravity (the paper's form).
inline double dimensionless_flow_rate(double j_per_s, double d_m) {
  return j_per_s * std::sqrt(d_m / kStandardGravity);
}
// Same with the in-plane gravity g sin(theta) (useful when comparing inclines).
inline double dimensionless_flow_rate_inplane(double j_per_s, double d_m, double incline_rad) {
  return j_per_s * std::sqrt(d_m / (kStandardGravity * std::sin(incline_rad)));
}

}  // namespace gapflow
