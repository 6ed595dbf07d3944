#!/usr/bin/env bash
# Builds the default synthetic benchmark (docs/dataset.md): the 21 named CGAL
# meshes (installed from Debian's libcgal-demo, never committed: GPL/LGPL)
# plus the procedural shapes of objects.txt. Resumes if interrupted.
#   bash data/synth/make_dataset.sh [OUT_DIR [EXTRA]]
# EXTRA: extra training touches per object (default 60; the shipped models use 400).
# --indentation: each touch's gel indentation too (touches/<id>.depth.png; the same frames), for
# vtloc eval's render-and-compare oracle rows (docs/render_compare.md).
set -euo pipefail
root="$(cd "$(dirname "$0")/../.." && pwd)"
out="${1:-$root/build/synth-default}"
extra="${2:-60}"
meshes="$root/build/cgal-meshes"
bash "$root/data/synth/get_cgal_meshes.sh" "$meshes"
[ -x "$root/build/vtloc" ] || bash "$root/setup.sh"
"$root/build/vtloc" synth --objects "$root/data/synth/objects.txt" --mesh-dir "$meshes" \
  --out "$out" --contacts 40 --extra "$extra" --seed 1 --indentation
