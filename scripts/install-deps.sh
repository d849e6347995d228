#!/usr/bin/env bash
# Installs the Debian packages fact needs, skipping those already present.
set -euo pipefail
packages=(
  build-essential cmake pkg-config          # toolchain
  libeigen3-dev                             # linear algebra (lib/)
  libgtest-dev googletest                   # tests
  nlohmann-json3-dev libcli11-dev           # JSON files, command lines
  gnuplot-nox                               # benchmark plots (PNG)
  libsdpa-dev libsdp-dev coinor-csdp        # SDP peers, benchmark only (never linked into lib/ or apps/)
)
missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if ((${#missing[@]})); then
  echo "== installing: ${missing[*]}"
  sudo=""; [ "$(id -u)" -eq 0 ] || sudo="sudo"
  $sudo apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y -qq --no-install-recommends "${missing[@]}"
else
  echo "== dependencies present"
fi
