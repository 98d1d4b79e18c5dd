#!/usr/bin/env bash
# Installs the Debian 12 packages squeeze builds against, if any is missing, then configures and
# builds squeeze in Release mode into build/ (or $SQUEEZE_BUILD_DIR). Safe to run again.
# Usage: scripts/setup-debian.sh            (as root, or with sudo available)
#        SQUEEZE_SETUP_PACKAGES_ONLY=1 scripts/setup-debian.sh   only the packages (scripts/test.sh --sanitize)
set -euo pipefail
here="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
build="${SQUEEZE_BUILD_DIR:-$here/build}"

packages=(build-essential cmake ninja-build pkg-config
  libcgal-dev libgmp-dev libmpfr-dev libboost-dev libompl-dev
  libassimp-dev libeigen3-dev libtbb-dev nlohmann-json3-dev libcli11-dev libspdlog-dev libfmt-dev
  libgtest-dev libgmock-dev libbenchmark-dev libnanoflann-dev
  libosmesa6-dev libegl-dev libgl-dev libpng-dev libplplot-dev libcairo2-dev
  plplot-driver-cairo libegl-mesa0 libgl1-mesa-dri
  libtinygltf-dev libavcodec-dev libavformat-dev libavutil-dev libswscale-dev
  tetgen)

missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if ((${#missing[@]})); then
  echo "squeeze: installing missing Debian packages: ${missing[*]}" >&2
  sudo_cmd=()
  [ "$(id -u)" -eq 0 ] || sudo_cmd=(sudo)
  "${sudo_cmd[@]}" apt-get update -q
  DEBIAN_FRONTEND=noninteractive "${sudo_cmd[@]}" apt-get install -y -q --no-install-recommends "${missing[@]}"
fi

[ "${SQUEEZE_SETUP_PACKAGES_ONLY:-0}" = 1 ] && exit 0

launcher=()
command -v ccache >/dev/null 2>&1 && launcher=(-DCMAKE_CXX_COMPILER_LAUNCHER=ccache)
cmake -S "$here" -B "$build" -G Ninja -DCMAKE_BUILD_TYPE=Release "${launcher[@]}" >/dev/null
cmake --build "$build" --parallel "$(nproc)"
