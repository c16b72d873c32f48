#!/usr/bin/env bash
# The README's main command: set up, build, then turn the bundled default input (an evenly
# sampled knotted tube that particlemesh generates itself) into a mesh and summarise it.
set -euo pipefail

ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
"$ROOT/scripts/setup.sh"
BUILD="${PM_BUILD_DIR:-$ROOT/build}"
PM="$BUILD/cli/particlemesh"
OUT="$ROOT/out/demo"
mkdir -p "$OUT"

"$PM" sample trefoil --spacing 0.05 --seed 1 -o "$OUT/trefoil_particles.ply"
"$PM" triangulate "$OUT/trefoil_particles.ply" -o "$OUT/trefoil.ply" --report "$OUT/trefoil_report.json"
echo
echo "Mesh:   $OUT/trefoil.ply"
echo "Report: $OUT/trefoil_report.json"
