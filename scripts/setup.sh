#!/usr/bin/env bash
# Install what is missing (Debian 12 packages only) and build gapflow (Release) into build/.
# Safe to run again: it installs nothing that is already there and rebuilds incrementally.
#   bash scripts/setup.sh [--packages-only]   (--packages-only: install, build nothing; e.g. to build
#                                              another commit's binary first, as a carried pass does)
set -euo pipefail
cd "$(dirname "$0")/.."
packages_only=false
case ${1:-} in
  "") ;;
  --packages-only) packages_only=true ;;
  *) echo "error: unknown option '$1'; allowed: --packages-only" >&2; exit 2 ;;
esac

packages=(
  build-essential cmake pkg-config
  libbox2d-dev libbullet-dev libeigen3-dev libboost-math-dev libnlopt-cxx-dev
  libgtest-dev libbenchmark-dev libbenchmark-tools
  libtomlplusplus-dev libcli11-dev libsqlite3-dev libfmt-dev libtbb-dev
  python3 python3-matplotlib
  python3-scipy                # scripts/steady_vs_paper.py: Student-t quantile
  libopenmpi-dev openmpi-bin   # gapflow study --mpi (optional at build time)
  slurm-wlm munge              # scripts/slurm_local.sh: a one-node Slurm for the slow cluster test
  libcairo2-dev ffmpeg libcpp-httplib-dev   # view/ (snapshots, movies) and gapflow serve
  python3-vtk9 python3-pil chromium         # tests: ParaView files read back by VTK; the live view in headless Chromium
  valgrind                                  # scripts/profile_3d_settings.sh (instructions per particle-step)
)
missing=()
for p in "${packages[@]}"; do
  grep -q "install ok installed" <<< "$(dpkg-query -W -f='${Status}' "$p" 2>/dev/null || true)" || missing+=("$p")
done
if [ ${#missing[@]} -gt 0 ]; then
  echo "setup: installing ${missing[*]}"
  export DEBIAN_FRONTEND=noninteractive
  apt-get update -qq
  apt-get install -y -qq --no-install-recommends "${missing[@]}"
fi

$packages_only && exit 0
cmake -S . -B build -DCMAKE_BUILD_TYPE=Release >/dev/null
cmake --build build -j"$(nproc)"
