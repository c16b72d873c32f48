#!/usr/bin/env bash
# Behaviour check for refactorings: runs the CLI on a fixed set of the shared real-world inputs
# (../shared/data; a few triangulate, polygonize, smooth, render, inspect and sample runs, under
# a minute on two cores) and prints the sha256 of every output, one line a run. Run it on the
# build before a change and after it and compare the two listings (`diff`): a refactoring that
# changes no behaviour leaves every line as it was. The triangulate runs also hash the
# summary's `hint` lines (the advice printed to the user), which carry no timings.
#
#   scripts/check_outputs_unchanged.sh > before.txt   # on the unchanged build
#   ... change, rebuild ...
#   scripts/check_outputs_unchanged.sh | diff before.txt -
#
# Environment: PM_BUILD_DIR (default build/), PM_SHARED_DATA_DIR (default ../shared/data).
set -euo pipefail

ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
BUILD="${PM_BUILD_DIR:-$ROOT/build}"
DATA="${PM_SHARED_DATA_DIR:-$ROOT/../shared/data}"
PM="$BUILD/cli/particlemesh"
[ -x "$PM" ] || { echo "check_outputs_unchanged: no CLI at $PM (build first)" >&2; exit 1; }
[ -d "$DATA" ] || { echo "check_outputs_unchanged: no shared data at $DATA" >&2; exit 1; }

OUT="$(mktemp -d)"
trap 'rm -rf "$OUT"' EXIT

# run NAME OUTPUT ARGS...: runs the CLI (summary to OUT/NAME.log), prints the output's hash.
run() {
  local name="$1" output="$2"; shift 2
  if ! "$PM" "$@" >"$OUT/$name.log" 2>&1; then
    echo "$name FAILED: $PM $*" ; sed 's/^/  /' "$OUT/$name.log"; return 0
  fi
  printf '%-28s %s\n' "$name" "$(sha256sum <"$output" | cut -c1-64)"
}
# hint NAME: hashes the hint lines of a triangulate run's summary.
hint() {
  printf '%-28s %s\n' "$1.hint" "$( (grep -i 'hint' "$OUT/$1.log" || true) | sha256sum | cut -c1-64)"
}

run tri_bunny_poisson   "$OUT/a.ply" triangulate "$DATA/points/bunny_poisson.ply" -o "$OUT/a.ply" -q
run tri_bunny_raw       "$OUT/b.ply" triangulate "$DATA/points/bunny_poisson.ply" -o "$OUT/b.ply" --raw -q
run tri_spot_vertices   "$OUT/c.ply" triangulate "$DATA/points/spot_vertices.ply" -o "$OUT/c.ply"
hint tri_spot_vertices
run tri_bunny_vert_glob "$OUT/d.ply" triangulate "$DATA/points/bunny_vertices.ply" -o "$OUT/d.ply" --global-spacing
hint tri_bunny_vert_glob
run tri_dam_break       "$OUT/e.ply" triangulate "$DATA/particles/double_dam_break_frame_26_4732_particles.ply" -o "$OUT/e.ply"
hint tri_dam_break
run tri_milk_pcd        "$OUT/f.ply" triangulate "$DATA/pcd/milk.pcd" -o "$OUT/f.ply"
hint tri_milk_pcd
run tri_spot_loop       "$OUT/g.obj" triangulate "$DATA/points/spot_poisson.ply" -o "$OUT/g.obj" --smooth loop --levels 1 -q
run poly_cube           "$OUT/h.ply" polygonize "$DATA/particles/cube_2366_particles.ply" -o "$OUT/h.ply" --radius 0.1 -q
run poly_dam_aniso      "$OUT/i.ply" polygonize "$DATA/particles/double_dam_break_frame_26_4732_particles.ply" -o "$OUT/i.ply" --anisotropic -q
run poly_bunny_frame     "$OUT/j.ply" polygonize "$DATA/particles/bunny_frame_14_7705_particles.ply" -o "$OUT/j.ply" -q
run smooth_loop         "$OUT/k.ply" smooth "$DATA/meshes/bunny_coarse.ply" -o "$OUT/k.ply" --scheme loop --levels 2 -q
run smooth_butterfly    "$OUT/l.ply" smooth "$DATA/meshes/spot.obj" -o "$OUT/l.ply" --scheme butterfly --levels 1 -q
run render_cube         "$OUT/m.png" render "$DATA/particles/cube_2366_particles.ply" -o "$OUT/m.png" --width 160 --height 120 -q
run render_dam_aniso    "$OUT/n.png" render "$DATA/particles/double_dam_break_frame_26_4732_particles.ply" -o "$OUT/n.png" --anisotropic --width 160 --height 120 -q
"$PM" inspect "$DATA/meshes/rocker_arm.obj" --json >"$OUT/o.json" 2>&1 || true
printf '%-28s %s\n' inspect_rocker_arm "$(sha256sum <"$OUT/o.json" | cut -c1-64)"
run sample_trefoil      "$OUT/p.ply" sample trefoil --spacing 0.05 --seed 1 -o "$OUT/p.ply"
