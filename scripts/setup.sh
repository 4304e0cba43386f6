#!/usr/bin/env bash
# Installs every Debian bookworm package tachi needs to build, test and run.
# Idempotent: when everything is present it prints nothing and exits 0.
# Fails loudly (non-zero, naming the package) when a package cannot be installed.
set -euo pipefail

# Usage: setup.sh [--demo]. --demo installs only what README command (1) needs to build and run the
# pipeline on a recording; without it, also the tests', benchmarks' and fuzzers' toolchain.
demo_only=false
[ "${1:-}" = "--demo" ] && demo_only=true

packages=(
  # toolchain (Ninja and ccache: scripts/build_env.sh)
  build-essential cmake ninja-build ccache pkg-config git
  # DDS
  cyclonedds-dev cyclonedds-tools
  # Kinect v1 (live driver + fakenect playback library)
  libfreenect-dev libfreenect-bin
  # maths; vision: only the OpenCV modules sensor/ and viewer/ use (without libopencv-dev's CMake package
  # cmake/TachiOpenCV.cmake finds them itself); FFmpeg's libraries for the viewer's fragmented MP4 video
  # (viewer/include/tachi/viewer/video_writer.hpp)
  libeigen3-dev libopencv-core-dev libopencv-imgproc-dev libopencv-imgcodecs-dev libopencv-highgui-dev
  libopencv-videoio-dev libavformat-dev libavcodec-dev libswscale-dev libavutil-dev
  # objects to drape the cloth over: PLY point clouds (assimp) and nearest-point queries (nanoflann)
  libassimp-dev libnanoflann-dev
  # conventions shared by every executable
  libcli11-dev libspdlog-dev nlohmann-json3-dev
  # voice commands
  libpocketsphinx-dev libsphinxbase-dev pocketsphinx-en-us
  # the viewer's window (X11) and the run's plots (tachi run: latency.png, trajectory.png via scripts/plot_run.py)
  libx11-dev libxfixes-dev python3-matplotlib
)
test_packages=(
  # OpenCV's own CMake package (it depends on every OpenCV module: 51 packages, 61 MB the demo does without);
  # the full build takes the module targets from it
  libopencv-dev
  # voice tests: recorded speech, synthesized speech in every English voice the machine can speak (docs/voice.md)
  pocketsphinx-testdata flite sox espeak-ng festival festvox-kallpc16k festvox-us-slt-hts
  # tests and benchmarks (Bullet is the simulator baseline)
  libgtest-dev libgmock-dev libbenchmark-dev libbullet-dev
  # multi-host tests in network namespaces; the capture that proves DDS stays on loopback
  iproute2 tcpdump
  # DDS Security test PKI (scripts/make_test_pki.sh); libFuzzer targets and sanitizer builds (-DTACHI_FUZZ=ON;
  # clang needs LLVM's OpenMP runtime for the solver's threads)
  openssl clang libomp-dev
  # viewer under a virtual display
  xvfb xdotool imagemagick
  # the MCAP tests read tachi's recordings with an independent reader (@mcap/core, installed by npm at test time)
  nodejs
)
# Node's own packages (NodeSource) bring npm with nodejs; Debian's nodejs needs its npm package.
command -v npm >/dev/null 2>&1 || test_packages+=(npm)
$demo_only || packages+=("${test_packages[@]}")

missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
[ ${#missing[@]} -eq 0 ] && exit 0

if [ "$(id -u)" -ne 0 ]; then
  echo "setup.sh: missing packages: ${missing[*]}; run this script as root" >&2
  exit 1
fi
echo "setup.sh: installing ${missing[*]}" >&2
export DEBIAN_FRONTEND=noninteractive
apt-get update -qq >/dev/null || { echo "setup.sh: apt-get update failed" >&2; exit 1; }
if ! apt-get install -y -qq --no-install-recommends "${missing[@]}" >/tmp/tachi-setup.log 2>&1; then
  tail -n 20 /tmp/tachi-setup.log >&2
  echo "setup.sh: apt-get install failed for: ${missing[*]}" >&2
  exit 1
fi
for p in "${missing[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" \
    || { echo "setup.sh: package $p is still not installed" >&2; exit 1; }
done
