#!/usr/bin/env bash
# Installs the Debian 12 packages sweepmap needs, only those that are missing.
# Idempotent: a second run does nothing but check. Run as root or with sudo.
set -euo pipefail

packages=(
  build-essential cmake pkg-config
  liblcm-dev liblcm-bin liblcm-java libjchart2d-java libglib2.0-dev default-jdk-headless
  libeigen3-dev libpcl-dev libceres-dev liboctomap-dev
  libgtest-dev libgmock-dev libyaml-cpp-dev nlohmann-json3-dev libcli11-dev
  gnuplot-nox iproute2 util-linux clang-format python3
  clang libclang-rt-14-dev
  libgpiod-dev
  iptables libnetfilter-queue-dev  # the two-host test: loss and reordering without netem
  systemd
)

missing=()
for p in "${packages[@]}"; do
  if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed"; then
    missing+=("$p")
  fi
done

if [ ${#missing[@]} -eq 0 ]; then
  echo "setup: all ${#packages[@]} packages present"
  exit 0
fi

echo "setup: installing ${missing[*]}"
SUDO=""
if [ "$(id -u)" -ne 0 ]; then SUDO="sudo"; fi
export DEBIAN_FRONTEND=noninteractive
$SUDO apt-get update -qq
$SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}"
