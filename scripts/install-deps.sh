#!/usr/bin/env bash
# Installs the Debian packages fact needs, skipping those already present.
set -euo pipefail
packages=(
  build-essential cmake pkg-config          # toolchain
  libeigen3-dev                             # linear algebra (lib/)
  libgtest-dev googletest                   # tests
  nlohmann-json3-dev libcli11-dev           # JSON files, command lines
  gnuplot-nox                               # benchmark plots (PNG)
  liblcm-dev liblcm-bin liblcm-java libglib2.0-dev  # LCM: library, lcm-gen/lcm-spy/logger/logplayer, Java
  default-jdk-headless default-jre libjchart2d-java  # the jar of our types; lcm-spy's window (AWT on X11), charts
  xvfb x11-apps x11-utils                   # lcm-spy test under a virtual display (xwd screenshot, xwininfo)
  libsodium-dev                             # gossip authentication (crypto_auth)
  iproute2                                  # private network namespaces for udpm tests
  libopencv-core-dev libopencv-imgproc-dev libopencv-imgcodecs-dev libopencv-dnn-dev  # detector, PNG I/O
  python3-onnx python3-numpy                # tiny synthetic YOLO model, made at test time (/usr/bin/python3)
  nodejs                                    # node-mavlink, the independent MAVLink decoder of the bridge test
  libccd-dev                                # planner: GJK/EPA penetration depth (lib/planner)
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
# npm comes with some nodejs builds (NodeSource's) and separately with Debian's; add Debian's only if
# there is none, so the two never collide.
if ! command -v npm >/dev/null 2>&1; then
  sudo=""; [ "$(id -u)" -eq 0 ] || sudo="sudo"
  DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y -qq --no-install-recommends npm
fi
