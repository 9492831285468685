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
if [ ${#missing[@]} -eq 0 ]; then
  echo "setup: all ${#pkgs[@]} Debian packages present"
  exit 0
fi
sudo_cmd=""
[ "$(id -u)" -eq 0 ] || sudo_cmd="sudo"
echo "setup: installing ${missing[*]}"
$sudo_cmd apt-get update -qq
DEBIAN_FRONTEND=noninteractive $sudo_cmd apt-get install -y -qq --no-install-recommends "${missing[@]}"
