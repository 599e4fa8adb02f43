#!/usr/bin/env bash
# Installs the Debian 12 packages lodforge needs to build, test and run. Idempotent: does
# nothing when everything is present.
#   --tests   also what the integration tests need (scripts/test.sh): Slurm (slurm-wlm) for
#             tests/slurm/slurm_test.sh (and iproute2's ss to find free ports), python3-yaml for
#             scripts/slurm/submit.sh's job reading; buildah and mmdebstrap for
#             scripts/container-test.sh (the container image built and run, ctest container.image).
#             Debian's slurmctld and slurmd services do not start without /etc/slurm/slurm.conf
#             (their units and init scripts check it), and the test starts its own daemons on
#             other ports with auth/none, so a munge service started by the package is unused.
set -euo pipefail
tests=0
case "${1:-}" in
  --tests) tests=1 ;;
  "") ;;
  *) echo "usage: $0 [--tests]" >&2; exit 2 ;;
esac
packages=(
  build-essential cmake ccache pkg-config
  libeigen3-dev libopencv-dev libcgal-dev libceres-dev libmaxflow-dev
  libgdal-dev gdal-bin libtbb-dev libspdlog-dev libyaml-cpp-dev libcli11-dev nlohmann-json3-dev libtinygltf-dev libxml2-dev
  libgtest-dev libgmock-dev libbenchmark-dev
  libxml2-utils python3 python3-gdal python3-jsonschema python3-numpy python3-pil
)
if [ "$tests" -eq 1 ]; then packages+=(slurm-wlm iproute2 python3-yaml buildah mmdebstrap); fi
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
