#!/bin/bash
# The closed form's interval coverage for a planted spinning friction whose response is partly a level
# the particle friction can take up, with the friction measured beside the data (se 0.04): five
# variants of the model's noise, of how the level depends on the friction and of how large it is, 30 twins each
# (tests/test_calibration_synthetic.cpp, DISABLED_IntervalCoverageAgainstTheFriction; about 16 min
# each on one core). Writes each variant's twins and its count here, without the loop's log lines.
#   results/calibration-interval-coverage/closed-form/run.sh [TESTS]   (default build/tests/gapflow_tests)
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
tests=$(realpath "${1:-$here/../../../build/tests/gapflow_tests}")
run() {
  local name=$1; shift
  # every knob the exploration reads is unset first, so that one set outside does not leak into a variant
  env -u GAPFLOW_EFFECT -u GAPFLOW_SPIN_LEVEL -u GAPFLOW_SPIN_COUPLING -u GAPFLOW_FRICTION_SE -u GAPFLOW_COMMON_NOISE \
    -u GAPFLOW_OWN_NOISE -u GAPFLOW_MODEL_REPS -u GAPFLOW_MORE_GAPS "$@" GAPFLOW_SEEDS=30 "$tests" --gtest_also_run_disabled_tests --gtest_filter='*IntervalCoverageAgainst*' |
    grep -E '^(seed|spinning_friction)' > "$here/$name.txt.part"
  mv "$here/$name.txt.part" "$here/$name.txt"
}
run additive GAPFLOW_OWN_NOISE=0.01                                            # noise of each parameter value's own
run shared_noise GAPFLOW_OWN_NOISE=0.01 GAPFLOW_COMMON_NOISE=0.02              # most of it shared by all parameter values
run coupling_plus4 GAPFLOW_OWN_NOISE=0.01 GAPFLOW_SPIN_COUPLING=4              # the level stronger at high friction
run coupling_minus2.5 GAPFLOW_OWN_NOISE=0.01 GAPFLOW_SPIN_COUPLING=-2.5        # the level weaker at high friction
run level_0.3 GAPFLOW_OWN_NOISE=0.01 GAPFLOW_SPIN_LEVEL=0.3                     # twice the level: 0.86 mm as +0.13 in the friction
