#!/usr/bin/env bash
# Installs Facet's build, run and test dependencies from Debian 12 packages (idempotent).
# The package list lives in scripts/deps-debian.txt, the only place dependencies are named.
# `setup.sh --checked` also installs the packages after its "# [checked]" line (clang and the
# sanitizer/libFuzzer runtimes), which only the checked build and the fuzzers need: the
# default build and CI do not pay for their download.
set -euo pipefail
here="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
checked=0
[ "${1:-}" = "--checked" ] && checked=1
mapfile -t pkgs < <(awk -v checked="$checked" '/^# \[checked\]/ { if (!checked) exit } !/^[[:space:]]*(#|$)/' "$here/deps-debian.txt")
missing=()
for p in "${pkgs[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
sudo_cmd=""
[ "$(id -u)" -eq 0 ] || sudo_cmd="sudo"
if [ ${#missing[@]} -eq 0 ]; then
  echo "setup: all ${#pkgs[@]} Debian packages present"
else
  echo "setup: installing ${missing[*]}"
  $sudo_cmd apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $sudo_cmd apt-get install -y -qq --no-install-recommends "${missing[@]}"
fi

# The Khronos glTF Validator, which the export tests run on every .glb they write
# (tests/gltf/validate.js): the npm package pinned in tests/gltf/package-lock.json, installed
# here so that nothing is downloaded at build or test time. Node and npm come from Debian when
# the machine has none (any Node >= 12 runs the validator).
if ! command -v npm >/dev/null 2>&1; then
  echo "setup: installing nodejs npm (for the glTF Validator)"
  $sudo_cmd apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $sudo_cmd apt-get install -y -qq --no-install-recommends nodejs npm
fi
gltf_dir="$here/../tests/gltf"
# A copy of the lock file beside the installed packages says which lock they were installed
# from: equal files mean the pinned validator is there.
stamp="$gltf_dir/node_modules/.facet-installed-lock.json"
if cmp -s "$gltf_dir/package-lock.json" "$stamp" && [ -f "$gltf_dir/node_modules/gltf-validator/package.json" ]; then
  echo "setup: glTF Validator $(node -p "require('$gltf_dir/node_modules/gltf-validator/package.json').version") present"
else
  echo "setup: installing the glTF Validator (npm ci in tests/gltf)"
  (cd "$gltf_dir" && npm ci --no-audit --no-fund --loglevel=error)
  cp "$gltf_dir/package-lock.json" "$stamp"
fi
