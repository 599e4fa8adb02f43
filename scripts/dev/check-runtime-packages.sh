#!/usr/bin/env bash
# Checks that docker/Dockerfile's runtime stage installs what a real build of lodforge needs,
# since no Docker engine runs here to try it:
#  1. every library the binary links to directly (ELF NEEDED) is owned by a package that the
#     runtime stage's `apt-get install` lists, or libc6, libstdc++6, libgcc-s1 (debian:bookworm-slim has them);
#  2. every library ldd resolves (the whole closure) is owned by one of those packages or by a
#     package they depend on (Depends/Pre-Depends, recursively), so apt-get installs it too.
# Listed packages that own no needed library are reported as warnings.
#
# usage: scripts/dev/check-runtime-packages.sh [LODFORGE_BINARY [DOCKERFILE]]
#        (defaults: build/lodforge, docker/Dockerfile; Debian with dpkg and apt-cache)
set -euo pipefail
cd "$(dirname "$0")/../.."
binary="${1:-build/lodforge}"
dockerfile="${2:-docker/Dockerfile}"
# In debian:bookworm-slim already (and needed by apt itself).
base=(libc6 libstdc++6 libgcc-s1)

fail() { echo "check-runtime-packages: error: $*" >&2; exit 1; }
[ -x "$binary" ] || fail "'$binary' is not an executable (build first: scripts/build.sh)"
[ -f "$dockerfile" ] || fail "'$dockerfile' not found"
for tool in dpkg-query apt-cache ldd readelf; do
  command -v "$tool" >/dev/null 2>&1 || fail "$tool not found (this check runs on Debian)"
done

# The packages of the runtime stage: the words after `apt-get install` in the RUN command of
# the stage that starts at `FROM debian:bookworm-slim`, options left out, up to `&&`.
mapfile -t listed < <(awk '
  /^FROM[ \t]/ { runtime = ($2 ~ /^debian:bookworm-slim/) }
  runtime { line = line " " $0 }
  END { print line }' "$dockerfile" |
  sed 's/\\$//; s/ \\ / /g' | tr -s ' \t' '\n\n' |
  awk '$0 == "install" { on = 1; next } on && $0 == "&&" { exit } on && $0 !~ /^-/ && $0 != "\\" { print }')
[ ${#listed[@]} -gt 0 ] || fail "no 'apt-get install' packages in the debian:bookworm-slim stage of $dockerfile"

# The package that owns each library ldd resolves, from one dpkg-query call: a library is
# looked up as ldd prints it, under /usr (merged /usr), and through its symbolic links.
mapfile -t libs < <(ldd "$binary" | awk '/=>/ && $3 ~ /^\// { print $3 }' | sort -u)
candidates() { local f="$1"; echo "$f"; echo "/usr$f"; readlink -f "$f"; }
declare -A owner_of
while IFS= read -r line; do
  pkg="${line%%: /*}" path="/${line#*: /}"
  pkg="${pkg%%,*}"
  owner_of[$path]="${pkg%%:*}"
done < <(for f in "${libs[@]}"; do candidates "$f"; done | sort -u | xargs dpkg-query -S 2>/dev/null | grep -v '^diversion' || true)
owner() {  # LIBRARY PATH -> its package
  local c
  for c in $(candidates "$1"); do
    [ -n "${owner_of[$c]:-}" ] && { echo "${owner_of[$c]}"; return 0; }
  done
  return 1
}

declare -A in_list closure
for p in "${listed[@]}" "${base[@]}"; do in_list[$p]=1; done
# The dependency closure apt-get install gives, with virtual packages and alternatives
# counted generously (apt-cache prints every alternative).
while read -r p; do closure[$p]=1; done < <(
  apt-cache depends --recurse --no-recommends --no-suggests --no-conflicts --no-breaks --no-replaces \
    --no-enhances "${listed[@]}" "${base[@]}" 2>/dev/null | sed -n 's/^[ |]*\(Pre\)\{0,1\}Depends: <\{0,1\}\([^>]*\)>\{0,1\}$/\2/p; /^[a-z0-9]/p' |
  sed 's/:any$//; s/:amd64$//' | sort -u)

errors=0
declare -A used
# 1. direct dependencies
mapfile -t needed < <(readelf -d "$binary" | sed -n 's/.*(NEEDED).*\[\(.*\)\]/\1/p')
declare -A resolved
while read -r name _ path _; do
  [ -n "${path:-}" ] && [ "${path:0:1}" = / ] && resolved[$name]="$path"
done < <(ldd "$binary" | awk '/=>/ { print $1, $2, $3 }')
for lib in "${needed[@]}"; do
  path="${resolved[$lib]:-}"
  [ -n "$path" ] || { echo "  $lib: not found by ldd" >&2; errors=$((errors + 1)); continue; }
  pkg="$(owner "$path")" || { echo "  $lib ($path): no Debian package owns it" >&2; errors=$((errors + 1)); continue; }
  used[$pkg]=1
  if [ -z "${in_list[$pkg]:-}" ]; then
    echo "  $lib ($path): package $pkg is not installed by the runtime stage of $dockerfile" >&2
    errors=$((errors + 1))
  fi
done
# 2. every library ldd resolves
for path in "${libs[@]}"; do
  pkg="$(owner "$path")" || { echo "  $path: no Debian package owns it" >&2; errors=$((errors + 1)); continue; }
  if [ -z "${in_list[$pkg]:-}" ] && [ -z "${closure[$pkg]:-}" ]; then
    echo "  $path: package $pkg is neither listed in $dockerfile nor a dependency of a listed package" >&2
    errors=$((errors + 1))
  fi
done
for p in "${listed[@]}"; do
  [ -n "${used[$p]:-}" ] || echo "check-runtime-packages: warning: $p is listed but owns none of the libraries $binary links to" >&2
done
if [ "$errors" -gt 0 ]; then
  echo "check-runtime-packages: $errors problem(s); fix the apt-get install list of the runtime stage in $dockerfile" >&2
  exit 1
fi
echo "check-runtime-packages: ok: ${#needed[@]} direct libraries owned by the ${#listed[@]} listed packages (${listed[*]}) or the slim base; all ${#libs[@]} libraries ldd resolves come with them"
