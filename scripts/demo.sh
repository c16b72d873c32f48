#!/usr/bin/env bash
# The README's main command: set up, build, then turn the bundled default input (an evenly
# sampled knotted tube that particlemesh generates itself) into a mesh, summarise it, and
# render it in Blender through the add-on (out/demo/trefoil.png).
set -euo pipefail

ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
"$ROOT/scripts/setup.sh"
BUILD="${PM_BUILD_DIR:-$ROOT/build}"
PM="$BUILD/cli/particlemesh"
OUT="$ROOT/out/demo"
mkdir -p "$OUT"

"$PM" sample trefoil --spacing 0.05 --seed 1 -o "$OUT/trefoil_particles.ply"
"$PM" triangulate "$OUT/trefoil_particles.ply" -o "$OUT/trefoil.ply" --report "$OUT/trefoil_report.json"

# The same mesh in Blender, through the add-on built with it, rendered to a still (Cycles on
# the CPU, denoising off, small: a few seconds).
ZIP="$(ls "$BUILD"/blender_addon/particlemesh-*-blender-addon.zip 2>/dev/null | head -n 1 || true)"
RENDER=""
if command -v blender >/dev/null && [ -n "$ZIP" ]; then
  rm -f "$OUT/trefoil.png"
  if ! blender --background --factory-startup -noaudio --python-exit-code 1 \
      --python "$ROOT/scripts/blender_demo.py" -- \
      --zip "$ZIP" --mesh "$OUT/trefoil.ply" --out "$OUT/trefoil.png" >"$OUT/blender.log" 2>&1; then
    tail -n 20 "$OUT/blender.log" >&2
    echo "demo: the Blender render failed (log: $OUT/blender.log)" >&2
    exit 1
  fi
  grep "^blender_demo:" "$OUT/blender.log" || true
  RENDER="$OUT/trefoil.png"
else
  echo "(blender or the add-on zip is missing: no render)"
fi

echo
echo "Mesh:   $OUT/trefoil.ply"
echo "Report: $OUT/trefoil_report.json"
[ -n "$RENDER" ] && echo "Render: $RENDER"
true
