#!/usr/bin/env bash
# Every number of docs/results.md: `vtloc eval` (this engine) on the exported weights,
# known and unknown objects of the synthetic benchmark, each beside the PyTorch
# reference's metrics on the same touches (tests/eval/compare_eval.py prints the
# largest difference), the ILU N ablation (N varied at run time on one model) and the
# several-touch tables (SPEC 6).
#   bash models/results.sh OUT_DIR MODEL.safetensors [MODEL ...]
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
out="$1"; shift
data="$root/build/synth-extra"   # models/train.sh's data: the benchmark's test touches + extra renders
mkdir -p "$out"
cd "$root"
for model in "$@"; do
  name="$(basename "$model" .safetensors)"
  for objects in known unknown; do
    build/vtloc eval --model "$model" --data "$data" --objects "$objects" \
      --json "$out/$name.$objects.json" --markdown "$out/$name.$objects.md" --per-touch "$out/$name.$objects.csv"
    OMP_NUM_THREADS=2 PYTHONDONTWRITEBYTECODE=1 /usr/bin/python3 -m weights_tools.eval --model "$model" \
      --data "$data" --objects "$objects" --json "$out/$name.$objects.py.json" > /dev/null
    /usr/bin/python3 tests/eval/compare_eval.py "$out/$name.$objects.json" "$out/$name.$objects.py.json" "$data" \
      | tee "$out/$name.$objects.compare.txt"
  done
done
# Several touches (SPEC 6, docs/multitouch.md): both protocols, geometry alone, with the first
# model's heat-maps and with render-and-compare (SPEC 9; its oracle rows where the benchmark has
# indentation maps), without and with odometry noise, on the default benchmark (its meshes:
# data/synth/make_dataset.sh), known and unknown objects; the per-window CSVs feed
# models/symmetry_floor.py --per-touch.
seqdata="${VTLOC_SEQUENCE_DATA:-$root/build/synth-default}"
[ -d "$seqdata" ] || bash "$root/data/synth/make_dataset.sh" "$seqdata" 0
for objects in known unknown; do
  build/vtloc eval --model "$1" --data "$seqdata" --objects "$objects" --sequence 1,2,3,4,6,8 \
    --odometry-noise 0.5,0.5 --render-compare --json "$out/sequence.$objects.json" --markdown "$out/sequence.$objects.md" \
    --plot "$out/sequence.$objects.png" --per-touch "$out/sequence.$objects.csv"
done
# ILU N ablation on the first model: accuracy per N and this engine's time per touch.
model="$1"; name="$(basename "$model" .safetensors)"
for n in 0 4 8 16 32; do
  build/vtloc eval --model "$model" --data "$data" --objects known --iters "$n" --no-baselines \
    --json "$out/$name.iters$n.json" > /dev/null
done
echo "wrote $out"
