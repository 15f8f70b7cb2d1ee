// One mapping from failures to exit codes for every subcommand:
// 2 bad input (scenario, study or command line), 1 failure while running.
#pragma once

#include "common/scenario_loader.hpp"

#include <iostream>
#include <stdexcept>

namespace gapflow {

inline constexpr int kExitBadInput = 2;
inline constexpr int kExitFailure = 1;

template <class Body>
int exit_code_of(Body&& body) {
  try {
    return body();
  } catch (const ScenarioError& e) {
    std::cerr << "error: " << e.what() << "\n";
    return kExitBadInput;
  } catch (const std::invalid_argument& e) {
    std::cerr << "error: " << e.what() << "\n";
    return kExitBadInput;
  } catch (const std::exception& e) {
    std::cerr << "gapflow failed: " << e.what() << "\n";
    return kExitFailure;
  }
}

}  // namespace gapflow
