#!/usr/bin/env bash
# Installs the Debian 12 packages lodforge needs to build, test and run. Idempotent: does
# nothing when everything is present.
set -euo pipefail
packages=(
  build-essential cmake ccache pkg-config
  libeigen3-dev libopencv-dev libcgal-dev libceres-dev libmaxflow-dev
  libgdal-dev gdal-bin libtbb-dev libspdlog-dev libyaml-cpp-dev
  libgtest-dev libgmock-dev libbenchmark-dev
  libxml2-utils python3 python3-gdal python3-jsonschema python3-numpy python3-pil
)
missing=()
for p in "${packages[@]}"; do
  dpkg -s "$p" >/dev/null 2>&1 || missing+=("$p")
done
if [ ${#missing[@]} -eq 0 ]; then
  echo "install-deps: all ${#packages[@]} packages present"
  exit 0
fi
echo "install-deps: installing ${missing[*]}"
sudo=""
[ "$(id -u)" -ne 0 ] && sudo="sudo"
$sudo apt-get update -qq
DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y -qq --no-install-recommends "${missing[@]}"
