// String forms of the scenario enums. Each string is exactly the value written
// in the scenario TOML, so the loader and canonical_toml() share one spelling.
#include "common/scenario.hpp"

namespace gapflow {

const char* to_string(SizeDistribution v) {
  switch (v) {
    case SizeDistribution::none: return "none";
    case SizeDistribution::uniform: return "uniform";
    case SizeDistribution::normal: return "normal";
  }
  return "?";
}

const char* to_string(ObstructionShape v) {
  switch (v) {
    case ObstructionShape::none: return "none";
    case ObstructionShape::cylinder: return "cylinder";
    case ObstructionShape::triangle: return "triangle";
    case ObstructionShape::polygon: return "polygon";
  }
  return "?";
}

const char* to_string(DistanceReference v) {
  switch (v) {
    case DistanceReference::nearest: return "nearest";
    case DistanceReference::centre: return "centre";
  }
  return "?";
}

const char* to_string(Apex v) {
  switch (v) {
    case Apex::away_from_gap: return "away_from_gap";
    case Apex::toward_gap: return "toward_gap";
  }
  return "?";
}

const char* to_string(EndCondition v) {
  switch (v) {
    case EndCondition::all_passed: return "all_passed";
    case EndCondition::time_limit: return "time_limit";
    case EndCondition::n_passed: return "n_passed";
  }
  return "?";
}

const char* to_string(ClogBreaking v) {
  switch (v) {
    case ClogBreaking::shaking: return "shaking";
    case ClogBreaking::local_perturbation: return "local_perturbation";
    case ClogBreaking::refill: return "refill";
  }
  return "?";
}

const char* to_string(BaseFrictionMethod v) {
  switch (v) {
    case BaseFrictionMethod::force: return "force";
    case BaseFrictionMethod::joint: return "joint";
  }
  return "?";
}

}  // namespace gapflow
