#!/bin/bash
# Runs the device check packed by pack.py, on the GPU machine, from the root of a
# checkout of the same commit:  bash .devcheck/run.sh
# The tests (12 shards in parallel, then the paper goldens written by the local
# PyTorch), `vtloc check` (model, --ops, paper size), the demo and the benches.
# Every step has its own timeout, and the logs are re-packed into $OUT every
# 15 s, so a run cut short still leaves what it did.
# Env: OUT (default /tmp/vtloc-device-check), BENCH=0 (no benches),
# CORRECT=0 (no tests), DEMO2=1 (demo in three processes: the driver's cache),
# TWICE=1 (the shipped-model bench twice), TT (test timeout, s, default 180).
set -u
R=$PWD; D=$(cd "$(dirname "$0")" && pwd)
O=${OUT:-/tmp/vtloc-device-check}; L=/tmp/vtloc-device-logs; mkdir -p "$O" $L
exec > >(tee "$O/run.log") 2>&1
t0=$(date +%s); step() { echo "=== $(($(date +%s) - t0))s $*"; }
(while sleep 15; do tar -czf "$O/logs.tmp" -C $L . 2>/dev/null && mv "$O/logs.tmp" "$O/logs.tgz"; done) &
SNAP=$!

step setup
V=/tmp/vtloc-device; rm -rf $V; mkdir -p $V; tar -xJf "$D/bundle.tar.xz" -C $V
# Debian's Vulkan loader and GL dispatch libraries (an NVIDIA ICD loads them),
# for a machine that has none; unpacked beside the bundle, nothing goes to /.
for f in "$D"/gl/*.deb; do dpkg -x "$f" $V/gl; done
SRC=$(cat $V/source_dir)  # compiled into the test runner
[ -e "$SRC" ] || { mkdir -p "$(dirname "$SRC")"; ln -s "$R" "$SRC"; }
mkdir -p "$SRC/build/goldens"
export LD_LIBRARY_PATH=$V/lib:$V/gl/usr/lib/x86_64-linux-gnu VK_LAYER_PATH=$V/layer VTLOC_DATA_DIR=$SRC
ICD=/usr/local/nvidia/share/vulkan/icd.d/nvidia_icd.json
[ -f $ICD ] || ICD=$(find / -xdev -name nvidia_icd.json 2>/dev/null | head -1)
echo "icd: ${ICD:-none found, the default ones}"
[ -n "$ICD" ] && export VK_DRIVER_FILES=$ICD VK_ICD_FILENAMES=$ICD
PY=
for p in $(command -v python3) /opt/torch/.venv/bin/python3 /usr/bin/python3; do
  $p -c 'import torch, numpy' 2>/dev/null && { PY=$p; break; }
done
echo "python with torch: ${PY:-none}"
export VTLOC_PYTHON=$PY PYTHONDONTWRITEBYTECODE=1
nvidia-smi -L 2>/dev/null
lscpu | grep -E 'Model name|^CPU\(s\)'
grep -o -w -E 'avx2|avx512f' /proc/cpuinfo | sort | uniq -c
head -1 /etc/os-release
for b in $V/bin/* $V/lib/*; do ldd "$b" | grep -i "not found"; done
step devices
timeout 30 $V/bin/vtloc devices

step export paper-size random weights
mkdir -p $V/bin/bench-weights
(cd "$R" && timeout 120 $PY -m weights_tools.export --config vtloc-r18 --seed 0 \
  -o $V/bin/bench-weights/vtloc-r18.safetensors) >$L/export.log 2>&1 &
EXP=$!
if [ "${BENCH:-1}" = 1 ]; then
  if [ "${DEMO2:-0}" = 1 ]; then
    for k in first second third; do
      step "demo, the $k process"
      VTLOC_VALIDATION=0 timeout 60 $V/bin/vtloc demo | grep time
    done
  fi
  step probe
  timeout 30 $V/bin/vtloc-bench-probe
  step bench, shipped model
  timeout 90 $V/bin/vtloc-bench --reps 10 --points 1024,16384 --json "$O/bench_shipped.json"
  if [ "${TWICE:-0}" = 1 ]; then
    step bench, shipped model again
    timeout 90 $V/bin/vtloc-bench --reps 10 --points 1024,16384 --json "$O/bench_shipped2.json"
  fi
  step bench tactile
  timeout 40 $V/bin/vtloc-bench-tactile
  wait $EXP
  step bench, paper size
  timeout 90 $V/bin/vtloc-bench --config vtloc-r18 --reps 10 --points 1024 --json "$O/bench_r18.json"
  step bench point
  timeout 50 $V/bin/vtloc-bench-point
fi
wait $EXP
tail -2 $L/export.log
if [ "${CORRECT:-1}" = 1 ]; then
  step tests, checks and goldens in parallel
  (cd "$R" && timeout 150 $PY -m weights_tools.make_goldens --paper --out "$SRC/build/goldens") >$L/goldens.log 2>&1 &
  GOLD=$!
  TT=${TT:-180}
  P=()
  for k in $(seq 0 11); do
    timeout "$TT" $V/bin/vtloc_tests -f "$D/shard$k.txt" -r compact --durations yes >$L/shard$k.log 2>&1 &
    P+=($!)
  done
  VTLOC_VALIDATION=1 timeout "$TT" $V/bin/vtloc check --json $L/check_model.json >$L/check_model.log 2>&1 &
  P+=($!)
  VTLOC_VALIDATION=1 timeout "$TT" $V/bin/vtloc check --ops --json $L/check_ops.json >$L/check_ops.log 2>&1 &
  P+=($!)
  wait $GOLD
  step goldens written
  timeout 120 $V/bin/vtloc_tests "[golden]" -r compact --durations yes >$L/golden_tests.log 2>&1 &
  P+=($!)
  VTLOC_VALIDATION=1 timeout 120 $V/bin/vtloc check --model $V/bin/bench-weights/vtloc-r18.safetensors \
    >$L/check_r18.log 2>&1 &
  P+=($!)
  VTLOC_VALIDATION=1 timeout 60 $V/bin/vtloc demo >$L/demo.log 2>&1
  # Each process's own exit status: a crash at exit shows here, not in the test count.
  for p in "${P[@]}"; do
    wait "$p"
    echo "exit status of $p: $?"
  done
  for f in $L/*.log; do
    echo "--- $(basename "$f"): $(grep -E '^(Passed|Failed|All tests|OK:|FAIL)' "$f" | tail -1)"
  done
fi
kill $SNAP
tar -czf "$O/logs.tgz" -C $L .
step end
