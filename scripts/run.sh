#!/usr/bin/env bash
# Sets up, builds and opens Facet's GUI on the bundled sample project (or on the project
# given as the first argument).
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
cd "$root"
bash scripts/setup.sh
build="${FACET_BUILD_DIR:-$root/build/release}"
cmake -S "$root" -B "$build" -G Ninja -DCMAKE_BUILD_TYPE=Release >/dev/null
cmake --build "$build" -j "${FACET_JOBS:-2}" --target facet
exec "$build/app/facet" "$@"
