#!/usr/bin/env bash
# Shared set-up of the README's two commands: Debian packages, configure, build. Idempotent.
# Usage: scripts/setup.sh            (sourced by demo.sh and test.sh; safe to run alone)
set -euo pipefail

FIRN_ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
FIRN_BUILD="${FIRN_BUILD:-$FIRN_ROOT/build}"

# Everything Firn needs, from Debian 12 alone.
FIRN_PACKAGES=(
  cmake make g++ pkg-config
  blender
  libopenvdb-dev python3-openvdb libboost-iostreams-dev
  pybind11-dev python3-dev python3-numpy python3-pytest
  libglm-dev libembree-dev libtbb-dev
  libgtest-dev
  xvfb xauth libgl1-mesa-dri
)

firn_install_packages() {
  local missing=()
  for pkg in "${FIRN_PACKAGES[@]}"; do
    dpkg-query -W -f='${Status}' "$pkg" 2>/dev/null | grep -q "install ok installed" || missing+=("$pkg")
  done
  [ ${#missing[@]} -eq 0 ] && return 0
  echo "firn: installing Debian packages: ${missing[*]}"
  local sudo=()
  if [ "$(id -u)" -ne 0 ]; then
    command -v sudo >/dev/null || { echo "firn: run as root (or install sudo) to install: ${missing[*]}" >&2; exit 1; }
    sudo=(sudo)
  fi
  "${sudo[@]}" env DEBIAN_FRONTEND=noninteractive apt-get update -q
  "${sudo[@]}" env DEBIAN_FRONTEND=noninteractive apt-get install -y -q --no-install-recommends "${missing[@]}"
}

firn_build() {
  if [ ! -f "$FIRN_BUILD/CMakeCache.txt" ]; then
    echo "firn: configuring $FIRN_BUILD"
    cmake -S "$FIRN_ROOT" -B "$FIRN_BUILD" -DCMAKE_BUILD_TYPE=Release -DPython_EXECUTABLE=/usr/bin/python3
  fi
  # FIRN_BUILD_TARGETS (e.g. firn_addon for the demo) builds only those; unset, everything (tests too).
  echo "firn: building ${FIRN_BUILD_TARGETS:-everything}"
  cmake --build "$FIRN_BUILD" --parallel "$(nproc)" ${FIRN_BUILD_TARGETS:+--target $FIRN_BUILD_TARGETS}
}

firn_install_packages
firn_build
