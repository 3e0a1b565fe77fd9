#!/usr/bin/env bash
# Installs the Debian 12 packages sweepmap needs, only those that are missing.
# Idempotent: a second run does nothing but check. Run as root or with sudo.
#   setup.sh        the native (amd64) build: every library, the tools, the tests
#   setup.sh --pi   also the arm64 cross build of the on-board tree (`make pi`): the cross
#                   compiler, qemu-user-static, the arm64 libraries (multiarch), and the arm64
#                   -dev files that Debian 12 cannot co-install with the amd64 ones, unpacked
#                   into $SWEEPMAP_ARM64_ROOT (default /opt/sweepmap-arm64)
set -euo pipefail

pi=0
for arg in "$@"; do
  case "$arg" in
    --pi) pi=1 ;;
    -h | --help)
      sed -n '2,8p' "$0" | sed 's/^# \{0,1\}//'
      exit 0
      ;;
    *)
      echo "setup.sh: unknown argument '$arg' (expected --pi or --help)" >&2
      exit 2
      ;;
  esac
done

packages=(
  build-essential cmake pkg-config
  liblcm-dev liblcm-bin liblcm-java libjchart2d-java libglib2.0-dev default-jdk-headless
  libeigen3-dev libpcl-dev libceres-dev liboctomap-dev
  libgtest-dev libgmock-dev libyaml-cpp-dev nlohmann-json3-dev libcli11-dev
  gnuplot-nox iproute2 util-linux clang-format python3
  clang libclang-rt-14-dev
  libgpiod-dev
  libsodium-dev  # signed LCM messages (net/message_auth.hpp)
  iptables libnetfilter-queue-dev  # the two-host test: loss and reordering without netem
  systemd
  libwebsocketpp-dev libasio-dev  # sweepmap view: HTTP and WebSocket server (header-only)
  libjs-three                     # sweepmap view: three.js, served from /usr/share/javascript
  chromium                        # browser tests of the view and off-screen 3D renderings
  firefox-esr xvfb                # the view's browser tests in Firefox too (WebDriver BiDi; its
                                  # headless mode has no WebGL on Linux: a window on Xvfb)
)
# The on-board tree for arm64: only packages that are Multi-Arch: same (co-installable with
# their amd64 twins) or host tools. liblcm1, liblcm-dev and libyaml-cpp-dev are not
# co-installable (liblcm-dev:arm64 would replace lcm-gen's liblcm-bin:amd64): see below.
pi_packages=(
  crossbuild-essential-arm64 qemu-user-static ccache
  libsodium-dev:arm64
  dpkg-dev file  # dpkg-shlibdeps and file: CPack's Debian packages (make package)
  libc6:arm64 libyaml-cpp0.7:arm64 libgpiod-dev:arm64 libgtest-dev:arm64 libgmock-dev:arm64
  libglib2.0-0:arm64
)
# Unpacked (dpkg -x) into SWEEPMAP_ARM64_ROOT, not installed: cmake/toolchain-aarch64-linux-gnu.cmake
# finds the headers, lcm.pc and yaml-cpp's CMake files there, and qemu the arm64 liblcm.so.1.
pi_unpacked=(liblcm1:arm64 liblcm-dev:arm64 libyaml-cpp0.7:arm64 libyaml-cpp-dev:arm64)
ARM64_ROOT="${SWEEPMAP_ARM64_ROOT:-/opt/sweepmap-arm64}"

SUDO=""
if [ "$(id -u)" -ne 0 ]; then SUDO="sudo"; fi
export DEBIAN_FRONTEND=noninteractive

if [ "$pi" -eq 1 ]; then
  packages+=("${pi_packages[@]}")
  if ! dpkg --print-foreign-architectures | grep -qx arm64; then
    echo "setup: adding the arm64 architecture (dpkg --add-architecture arm64)"
    $SUDO dpkg --add-architecture arm64
    $SUDO apt-get update -qq
  fi
fi

missing=()
for p in "${packages[@]}"; do
  if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed"; then
    missing+=("$p")
  fi
done

if [ ${#missing[@]} -eq 0 ]; then
  echo "setup: all ${#packages[@]} packages present"
else
  echo "setup: installing ${missing[*]}"
  $SUDO apt-get update -qq
  $SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}"
fi

if [ "$pi" -eq 1 ]; then
  # One stamp per package version: a new Debian point release re-unpacks.
  want=$(apt-cache policy "${pi_unpacked[@]}" | awk '/^[^ ]/{p=$1} /Candidate:/{print p "=" $2}')
  if [ -f "$ARM64_ROOT/.unpacked" ] && [ "$(cat "$ARM64_ROOT/.unpacked")" = "$want" ]; then
    echo "setup: arm64 LCM and yaml-cpp present in $ARM64_ROOT"
  else
    echo "setup: unpacking ${pi_unpacked[*]} into $ARM64_ROOT"
    tmp=$(mktemp -d)
    chmod 777 "$tmp"  # apt-get download writes as _apt
    (cd "$tmp" && apt-get download -qq "${pi_unpacked[@]}")
    $SUDO rm -rf "$ARM64_ROOT"
    $SUDO mkdir -p "$ARM64_ROOT"
    for deb in "$tmp"/*.deb; do $SUDO dpkg -x "$deb" "$ARM64_ROOT"; done
    rm -rf "$tmp"
    # lcm.pc: the unpacked prefix; no glib (LCM's headers include none; liblcm.so.1 links
    # libglib2.0-0:arm64 itself).
    pc="$ARM64_ROOT/usr/lib/aarch64-linux-gnu/pkgconfig/lcm.pc"
    $SUDO sed -i -e "s|^prefix=.*|prefix=$ARM64_ROOT/usr|" -e '/^Requires:/d' "$pc"
    echo "$want" | $SUDO tee "$ARM64_ROOT/.unpacked" >/dev/null
  fi
fi

# Test-only Node packages (tests/js/package-lock.json, pinned): independent readers of our
# MCAP, LAS and Foxglove WebSocket output, and the browser driver. The product needs no Node.
# Installed again only when the lock file changed (a stamp beside node_modules).
root="$(cd "$(dirname "$0")/../.." && pwd)"
js="$root/tests/js"
if [ -f "$js/package-lock.json" ]; then
  if ! command -v npm >/dev/null; then
    echo "setup: installing npm"
    $SUDO apt-get install -y -qq --no-install-recommends nodejs npm
  fi
  stamp="$js/node_modules/.lock-sha256"
  want_lock=$(sha256sum "$js/package-lock.json" | cut -d' ' -f1)
  if [ -f "$stamp" ] && [ "$(cat "$stamp")" = "$want_lock" ]; then
    echo "setup: test-only npm packages present in tests/js/node_modules"
  else
    echo "setup: npm ci in tests/js (test-only packages)"
    (cd "$js" && npm ci --no-audit --no-fund --loglevel=error)
    echo "$want_lock" >"$stamp"
  fi
fi
