# The blind study's cases, shared by studies/calibration_blind.sh (which makes and calibrates them)
# and studies/blind_resignal.sh (which makes them again), and when a case's calibration has ended
# (calibration_ended_well, for calibration_replay.sh and blind_pass_carry.sh). Sourced, not run.

# id  model  seed  planted (effect:NAME:SIZE | set:KEY=VALUE), space-separated
# outside-quadratic-16 was added for pass 20: on design v2 the quadratic drags of 2 and 4 /m were
# invisible to the oracle in nearly every pass (lambda 0-16, power 0.01-0.87), so the out-of-catalogue
# criterion went untested. 16 /m (terminal speed on the 8 deg board sqrt(g sin 8 / 16) = 0.29 m/s,
# as a linear drag of 4.7 /s gives) had lambda 140 in a scratch twin at seed 99141 (not a pass's).
blind_cases="
null-1              2d 101
null-2              2d 102
null-3              2d 103
null-4              2d 104
rolling-low         2d 111 effect:rolling_resistance:low
rolling-high        2d 112 effect:rolling_resistance:high
spinning-low        2d 113 effect:spinning_friction:low
spinning-high       2d 114 effect:spinning_friction:high
wallfriction-low    2d 115 effect:wall_friction:low
wallfriction-high   2d 116 effect:wall_friction:high
scatter-low         2d 117 effect:size_scatter:low
scatter-high        2d 118 effect:size_scatter:high
restitution-low     2d 119 effect:restitution:low
restitution-high    2d 120 effect:restitution:high
tilt-low            2d 121 effect:lateral_tilt:low
tilt-high           2d 122 effect:lateral_tilt:high
gapoffset-low       2d 123 effect:gap_offset:low
gapoffset-high      2d 124 effect:gap_offset:high
drag-low            2d 125 effect:linear_drag:low
drag-high           2d 126 effect:linear_drag:high
corners-low         2d 127 effect:corner_rounding:low
corners-high        2d 128 effect:corner_rounding:high
two-drag-gap        2d 131 effect:linear_drag:high effect:gap_offset:high
two-tilt-rolling    2d 132 effect:lateral_tilt:high effect:rolling_resistance:high
outside-quadratic-2 2d 141 set:particles.quadratic_drag_per_m=2
outside-quadratic-4 2d 142 set:particles.quadratic_drag_per_m=4
outside-quadratic-16 2d 143 set:particles.quadratic_drag_per_m=16
twin-3d             3d 151
"

# A case's planted list (effect:NAME:SIZE | set:KEY=VALUE ...) as `gapflow twin` options, in the
# array twin_options.
planted_options() {
  twin_options=()
  local p
  for p in "$@"; do
    case "$p" in
      effect:*) twin_options+=(--effect "${p#effect:}") ;;
      set:*) twin_options+=(--set "${p#set:}") ;;
    esac
  done
}

# The `gapflow twin` options that give a twin of seed SEED its model seed under MODEL_SEEDS MODE
# (per-twin | design; studies/calibration_blind.sh), in the array seed_options. Per twin: 1000 x
# its seed. A calibration runs on its model seed and on it + 7907, 7919 and 7933 (the keep test,
# the fresh re-score, the signatures' own seeds: calibrate/calibration.hpp); the twins' seeds are
# consecutive, so their own seeds would meet (one twin's + 7919 is another's + 7907), and twins
# ending at the same parameters would share runs. Spaced by 1000, no two meet (no difference of
# those offsets is a multiple of 1000), nor, at the offsets used, a twin's data seeds (design seed +
# 1000003 + seed; those are in another store, but equal seeds at equal parameters are equal runs).
model_seed_options() {
  seed_options=()
  if [[ $1 == per-twin ]]; then seed_options=(--model-seed $(($2 * 1000))); fi
}
# calibration_ended_well FOLDER ID: the calibration ID in FOLDER (a pass, or a replay's folder) has
# ended well: its summary.json written and its .time (studies/calibration_blind.sh's and
# calibration_replay.sh's /usr/bin/time record) not empty and not saying the command failed. time
# creates the file empty at the start and writes it at the end, and gapflow writes summary.json
# before its other outputs, so summary.json alone does not say a calibration has ended. A folder
# without the .time (a pass copied without its time records) is judged by summary.json.
calibration_ended_well() {
  [[ -f $1/$2/summary.json ]] || return 1
  [[ -f $1/$2.time ]] || return 0
  [[ -s $1/$2.time ]] && ! grep -q '^Command ' "$1/$2.time"
}
