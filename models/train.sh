#!/usr/bin/env bash
# Reproduces a shipped model from scratch on this project's own data:
#   1. the synthetic benchmark (data/synth/make_dataset.sh, seed 1) with 400 extra
#      training touches per object (never within 2 mm of a test contact);
#   2. weights_tools.train with the budget below (wall-clock minutes of training,
#      so the step count depends on the machine; --steps N instead for bit-exact runs);
#   3. the weight file copied to models/<run>.safetensors.
# Interrupted? Run it again: the dataset resumes object by object and training
# resumes from its checkpoint. A run longer than a session is carried between
# sessions as models/checkpoints/<run>.pt (+ .log.csv): it is picked up here
# when the run folder has no checkpoint of its own.
#   bash models/train.sh [CONFIG] [MINUTES] [RUN_NAME [extra train.py options...]]
#   (default: vtloc-lite 90; RUN_NAME defaults to CONFIG)
#   e.g. the lambda = 0 comparison: bash models/train.sh vtloc-lite 20 vtloc-lite-lambda0 --lambda 0
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
config="${1:-vtloc-lite}"
minutes="${2:-90}"
name="${3:-$config}"
extra=("${@:4}")
data="$root/build/synth-extra"
run="$root/build/runs/$name"
bash "$root/data/synth/make_dataset.sh" "$data" 400
carried="$root/models/checkpoints/$name"
if [ ! -f "$run/checkpoint.pt" ] && [ -f "$carried.pt" ]; then
  mkdir -p "$run"
  cp "$carried.pt" "$run/checkpoint.pt"
  [ -f "$carried.log.csv" ] && cp "$carried.log.csv" "$run/log.csv"
fi
resume=()
[ -f "$run/checkpoint.pt" ] && resume=(--resume)
cd "$root"
# Passive OpenMP waits: spinning torch threads collapse (~20x slower) as soon as
# anything else wants a core; passive ones are also faster alone here (115 vs 82 touches/s).
OMP_WAIT_POLICY=PASSIVE PYTHONDONTWRITEBYTECODE=1 /usr/bin/python3 -m weights_tools.train --config "$config" --data "$data" \
  --out "$run" --minutes "$minutes" --seed 0 --threads 2 --keep-every 20 "${resume[@]}" "${extra[@]}"
cp "$run/model.safetensors" "$root/models/$name.safetensors"
echo "wrote models/$name.safetensors"
