#!/usr/bin/env bash
# Builds the container image of docker/Dockerfile for real, without a Docker engine: buildah
# (--isolation chroot) on a Debian 12 base made from this machine's own Debian sources
# (mmdebstrap; no image registry needed). Then runs `lodforge --version` and the demo job inside
# the image and checks that its outputs are byte-identical to the host build's.
#
#   scripts/container-test.sh [HOST_LODFORGE]      (default: build/lodforge)
#
# Exits 77 (skipped) when buildah or mmdebstrap is missing (scripts/install-deps.sh --tests
# installs them) or when buildah cannot run here (not root, no user namespaces). The base image
# tarball is kept in LODFORGE_CONTAINER_CACHE (default ~/.cache/lodforge-container); the host's
# apt archives and ccache directory are lent to the build to save downloads and compiling.
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
host_lodforge="$(realpath "${1:-$root/build/lodforge}")"
skip() { echo "container-test: skipped: $*"; exit 77; }
command -v buildah >/dev/null || skip "buildah is not installed (apt-get install buildah)"
command -v mmdebstrap >/dev/null || skip "mmdebstrap is not installed (apt-get install mmdebstrap)"
[ -x "$host_lodforge" ] || { echo "container-test: no lodforge binary at $host_lodforge; run scripts/build.sh" >&2; exit 1; }
buildah info >/dev/null 2>&1 || skip "buildah cannot run here (buildah info fails)"
cache="${LODFORGE_CONTAINER_CACHE:-$HOME/.cache/lodforge-container}"
mkdir -p "$cache"
export BUILDAH_ISOLATION=chroot
image=localhost/lodforge:container-test

# 1. The base images debian:bookworm and debian:bookworm-slim, from the Debian mirror apt uses.
if ! buildah inspect --type image localhost/debian:bookworm >/dev/null 2>&1; then
  if [ ! -f "$cache/bookworm.tar" ]; then
    echo "container-test: making the Debian 12 base with mmdebstrap" >&2
    mmdebstrap --variant=minbase --quiet bookworm "$cache/bookworm.tar.partial"
    mv "$cache/bookworm.tar.partial" "$cache/bookworm.tar"
  fi
  ctr=$(buildah from scratch)
  buildah add --quiet "$ctr" "$cache/bookworm.tar" / >/dev/null
  buildah config --env PATH=/usr/local/sbin:/usr/local/bin:/usr/sbin:/usr/bin:/sbin:/bin "$ctr"
  buildah commit --quiet "$ctr" localhost/debian:bookworm >/dev/null
  buildah rm "$ctr" >/dev/null
fi
buildah tag localhost/debian:bookworm localhost/debian:bookworm-slim

# 2. The image, as docker build would make it.
volumes=()
[ -d /var/cache/apt/archives ] && volumes+=(--volume /var/cache/apt/archives:/var/cache/apt/archives)
ccache_dir="$(ccache -k cache_dir 2>/dev/null || true)"
[ -n "$ccache_dir" ] && [ -d "$ccache_dir" ] && volumes+=(--volume "$ccache_dir:/root/.cache/ccache")
start=$(date +%s)
buildah bud --quiet --pull-never --layers=false "${volumes[@]}" -f "$root/docker/Dockerfile" -t "$image" "$root" >/dev/null
echo "container-test: image built in $(( $(date +%s) - start )) s" >&2

# 3. Inside: the version, and the demo job, compared with the host build's outputs.
work="$(mktemp -d)"
ctr=""
cleanup() {
  [ -n "$ctr" ] && buildah rm "$ctr" >/dev/null 2>&1
  buildah rmi --prune >/dev/null 2>&1 || true  # the images this test's earlier runs left untagged
  rm -rf "$work"
}
trap cleanup EXIT
ctr=$(buildah from --pull-never "$image")
buildah run "$ctr" -- lodforge --version
buildah run "$ctr" -- sh -c '! command -v c++ && ! command -v cmake' >/dev/null ||
  { echo "container-test: the runtime image holds build tools" >&2; exit 1; }
"$host_lodforge" synth --out "$work/city" --size-m 300 --seed 4 -q
cat > "$work/job.yaml" <<'EOF'
inputs:
  segmentation: {path: city/seg_class.tif}
  dsm: {path: city/dsm.tif}
  dtm: {path: city/dtm.tif}
tiling: {tile_size_m: 100}
output: {dir: OUT, quicklook: true, crs: "EPSG:7415", formats: [citygml, cityjson, cityjsonseq, obj, gpkg, geojson, gltf]}
work_dir: WORK
EOF
sed 's/OUT/host_out/; s/WORK/host_work/' "$work/job.yaml" > "$work/host.yaml"
sed 's/OUT/image_out/; s/WORK/image_work/' "$work/job.yaml" > "$work/image.yaml"
"$host_lodforge" run "$work/host.yaml" -q
buildah run --volume "$work:/data" "$ctr" -- lodforge run /data/image.yaml -q
# (the tile files: the index and report name the input paths, which differ inside the image)
(cd "$work/host_out" && find tiles -type f | sort | xargs sha256sum) > "$work/host.sha256"
(cd "$work/image_out" && find tiles -type f | sort | xargs sha256sum) > "$work/image.sha256"
if ! diff -u "$work/host.sha256" "$work/image.sha256"; then
  echo "container-test: the image's outputs differ from the host build's" >&2
  exit 1
fi
echo "container-test: the image's lodforge ran the job; its $(wc -l < "$work/host.sha256") output files equal the host build's"
