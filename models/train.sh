#!/usr/bin/env bash
# Reproduces a shipped model from scratch on this project's own data:
#   1. the synthetic benchmark (data/synth/make_dataset.sh, seed 1) with 400 extra
#      training touches per object (never within 2 mm of a test contact);
#   2. weights_tools.train with the budget below (wall-clock minutes of training,
#      so the step count depends on the machine; --steps N instead for bit-exact runs);
#   3. the weight file copied to models/<config>.safetensors.
# Interrupted? Run it again: the dataset resumes object by object and training
# resumes from its checkpoint. A run longer than a session is carried between
# sessions as models/checkpoints/<config>.pt (+ .log.csv): it is picked up here
# when the run folder has no checkpoint of its own.
#   bash models/train.sh [CONFIG] [MINUTES]      (default: vtloc-lite 90)
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
config="${1:-vtloc-lite}"
minutes="${2:-90}"
data="$root/build/synth-extra"
run="$root/build/runs/$config"
bash "$root/data/synth/make_dataset.sh" "$data" 400
carried="$root/models/checkpoints/$config"
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
  --out "$run" --minutes "$minutes" --seed 0 --threads 2 --keep-every 20 "${resume[@]}"
cp "$run/model.safetensors" "$root/models/$config.safetensors"
echo "wrote models/$config.safetensors"
