#!/bin/bash
# Runs the device check packed by pack.py, on the GPU machine, from the root of a
# checkout of the same commit:  bash .devcheck/run.sh
# Benches first (the GPU otherwise idle), then the tests (the shards in parallel;
# the paper goldens written by the machine's PyTorch, if it has one), the
# `vtloc check`s (the model, the ops, the tracker) and the demo. Every step has its own timeout, and the logs are
# re-packed into $OUT every 15 s, so a run cut short still leaves what it did.
# Env: OUT (default /tmp/vtloc-device-check), BENCH=0 (no benches), CORRECT=0 (no
# tests), DEMO2=1 (the demo in three processes: the driver's shader cache),
# TWICE=1 (the shipped-model bench twice), TT (test timeout, s, default 180),
# TESTS (Catch2 test specs or shard names, one per line: each its own process, instead of the
# shards, checks and goldens: a short rerun of what failed),
# VTLOC_PYTHON (a Python with torch; default: the first found).
# Exit status 0 only when every test process and check exited 0.
set -u
R=$(pwd -P); D=$(cd "$(dirname "$0")" && pwd)
O=${OUT:-/tmp/vtloc-device-check}; L=/tmp/vtloc-device-logs
rm -rf $L; mkdir -p "$O" $L
exec > >(tee "$O/run.log") 2>&1
t0=$(date +%s); step() { echo "=== $(($(date +%s) - t0))s $*"; }
(while sleep 15; do tar -czf "$O/logs.tmp" -C $L . 2>/dev/null && mv "$O/logs.tmp" "$O/logs.tgz"; done) &
SNAP=$!
trap 'kill $SNAP 2>/dev/null; tar -czf "$O/logs.tgz" -C $L . 2>/dev/null; rm -f "$O/logs.tmp"' EXIT

step setup
V=/tmp/vtloc-device; rm -rf $V; mkdir -p $V; tar -xJf "$D/bundle.tar.xz" -C $V
# The test runner has the build's source and goldens paths compiled in: the source
# path must lead to this checkout (a link where nothing is there).
SRC=$(cat $V/source_dir); GOLDENS=$(cat $V/goldens_dir)
if [ -L "$SRC" ] || [ ! -e "$SRC" ]; then
  mkdir -p "$(dirname "$SRC")" && ln -sfn "$R" "$SRC" || { echo "cannot link $SRC to $R"; exit 1; }
elif [ "$(cd "$SRC" && pwd -P)" != "$R" ]; then
  echo "$SRC (the packed build's source path) is another tree; run from there, or move it"; exit 1
fi
# Only the packed programs see the packed libraries (Debian 12's; gl/ holds its
# Vulkan loader and GL dispatch, which an NVIDIA ICD loads).
LIBS=$V/lib:$V/gl/usr/lib/x86_64-linux-gnu
vt() { LD_LIBRARY_PATH=$LIBS VK_LAYER_PATH=$V/layer VTLOC_DATA_DIR=$R "$@"; }
ICD=
for f in /usr/share/vulkan/icd.d/nvidia_icd.json /etc/vulkan/icd.d/nvidia_icd.json \
         /usr/local/nvidia/share/vulkan/icd.d/nvidia_icd.json; do [ -f $f ] && { ICD=$f; break; }; done
echo "icd: ${ICD:-not NVIDIA, the loader finds the drivers}"
[ -n "$ICD" ] && export VK_DRIVER_FILES=$ICD VK_ICD_FILENAMES=$ICD
PY=
for p in ${VTLOC_PYTHON:-} $(command -v python3) /usr/bin/python3 /opt/torch/.venv/bin/python3; do
  [ -n "$p" ] && $p -c 'import torch, numpy' 2>/dev/null && { PY=$p; break; }
done
echo "python with torch: ${PY:-none: no paper-size bench, goldens or paper-size check}"
export VTLOC_PYTHON=$PY PYTHONDONTWRITEBYTECODE=1
nvidia-smi -L 2>/dev/null
lscpu | grep -E 'Model name|^CPU\(s\)'
grep -o -w -E 'avx2|avx512f' /proc/cpuinfo | sort | uniq -c
head -1 /etc/os-release
for b in $V/bin/* $V/lib/*; do vt ldd "$b" | grep -i "not found"; done
step devices
vt timeout 30 $V/bin/vtloc devices
R18=$V/bin/bench-weights/vtloc-r18.safetensors  # where vtloc-bench --config looks
if [ -n "$PY" ]; then
  step export paper-size random weights
  mkdir -p $V/bin/bench-weights
  (cd "$R" && timeout 120 $PY -m weights_tools.export --config vtloc-r18 --seed 0 -o $R18) 2>&1 | tail -1
fi

if [ "${BENCH:-1}" = 1 ]; then
  if [ "${DEMO2:-0}" = 1 ]; then
    for k in first second third; do
      step "demo, the $k process"
      VTLOC_VALIDATION=0 vt timeout 60 $V/bin/vtloc demo | grep time
    done
  fi
  step probe
  vt timeout 30 $V/bin/vtloc-bench-probe
  step bench, shipped model
  vt timeout 90 $V/bin/vtloc-bench --reps 10 --points 1024,16384 --json "$O/bench_shipped.json"
  if [ "${TWICE:-0}" = 1 ]; then
    step bench, shipped model again
    vt timeout 90 $V/bin/vtloc-bench --reps 10 --points 1024,16384 --json "$O/bench_shipped2.json"
  fi
  step bench tactile
  vt timeout 40 $V/bin/vtloc-bench-tactile
  if [ -f $R18 ]; then
    # PyTorch side by side on the same GPU where the machine's torch has CUDA.
    VS=; [ -n "$PY" ] && $PY -c 'import torch; assert torch.cuda.is_available()' 2>/dev/null \
      && VS="--vs-pytorch --pytorch-device cuda"
    step bench, paper size ${VS:+with PyTorch on the GPU}
    vt timeout 150 $V/bin/vtloc-bench --config vtloc-r18 --reps 10 --points 1024 $VS --json "$O/bench_r18.json"
  fi
  step bench point
  vt timeout 50 $V/bin/vtloc-bench-point
fi

FAILED=0
if [ "${CORRECT:-1}" = 1 ]; then
  step tests, checks and goldens in parallel
  TT=${TT:-180}
  declare -A P
  # One test process: its log $L/NAME.log, its pid in P[NAME].
  tests_proc() { local k=$1; shift; vt timeout "$TT" $V/bin/vtloc_tests "$@" -r compact --durations yes >$L/$k.log 2>&1 & P[$k]=$!; }
  if [ -n "${TESTS:-}" ]; then
    i=0
    while IFS= read -r spec; do
      [ -n "$spec" ] || continue
      i=$((i + 1)); echo "test$i: $spec"
      case $spec in  # a shard's name: that shard's list
        shard[0-9]*) tests_proc test$i -f "$D/$spec.txt" ;;
        *) tests_proc test$i "$spec" ;;
      esac
    done <<<"$TESTS"
  else
    for f in "$D"/shard*.txt; do tests_proc "$(basename "$f" .txt)" -f "$f"; done
  fi
  [ -n "${TESTS:-}" ] || {
  VTLOC_VALIDATION=1 vt timeout "$TT" $V/bin/vtloc check --json $L/check_model.json >$L/check_model.log 2>&1 &
  P[check_model]=$!
  VTLOC_VALIDATION=1 vt timeout "$TT" $V/bin/vtloc check --ops --json $L/check_ops.json >$L/check_ops.log 2>&1 &
  P[check_ops]=$!
  VTLOC_VALIDATION=1 vt timeout "$TT" $V/bin/vtloc check --tracker --json $L/check_tracker.json >$L/check_tracker.log 2>&1 &
  P[check_tracker]=$!
  VTLOC_VALIDATION=1 VTLOC_MAX_TEXEL_ELEMENTS=65536 vt timeout "$TT" $V/bin/vtloc check --tracker --verbose >$L/check_tracker_small_texel.log 2>&1 &
  P[check_tracker_small_texel]=$!
  VTLOC_VALIDATION=1 vt timeout "$TT" $V/bin/vtloc check --tracker --terms --json $L/check_tracker_terms.json >$L/check_tracker_terms.log 2>&1 &
  P[check_tracker_terms]=$!
  VTLOC_VALIDATION=1 vt timeout "$TT" $V/bin/vtloc check --tracker --shapes --rendered --json $L/check_tracker_shapes.json >$L/check_tracker_shapes.log 2>&1 &
  P[check_tracker_shapes]=$!
  if [ -n "$PY" ]; then
    mkdir -p "$GOLDENS"
    (cd "$R" && timeout 150 $PY -m weights_tools.make_goldens --paper --out "$GOLDENS") >$L/goldens.log 2>&1
    step goldens written
    vt timeout 120 $V/bin/vtloc_tests "[golden]" -r compact --durations yes >$L/golden_tests.log 2>&1 &
    P[golden_tests]=$!
    VTLOC_VALIDATION=1 vt timeout 120 $V/bin/vtloc check --model $R18 >$L/check_r18.log 2>&1 &
    P[check_r18]=$!
  fi
  VTLOC_VALIDATION=1 vt timeout 60 $V/bin/vtloc demo >$L/demo.log 2>&1 || FAILED=1
  }
  # Each process's own exit status: a crash at exit does not show in Catch2's count.
  for k in $(printf '%s\n' "${!P[@]}" | sort); do
    wait "${P[$k]}"
    rc=$?
    [ $rc = 0 ] || FAILED=1
    echo "--- $k: exit status $rc; $(grep -E '^(Passed|Failed|All tests|OK:|FAIL)' $L/$k.log | tail -1)"
  done
  [ -n "${TESTS:-}" ] || echo "--- demo: $(grep -iE '^error' $L/demo.log)last touch (n, mm, ND %, belief, ms): $(grep -E '^ +[0-9]+ +[0-9.]+ ' $L/demo.log | tail -1)"
fi
step end
exit $FAILED
