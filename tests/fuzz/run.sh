#!/usr/bin/env bash
# Builds the libFuzzer targets (clang; ASan + UBSan, coverage in the files each
# reads through: tests/fuzz/CMakeLists.txt) in build-asan/, the build the
# sanitizer run shares, and runs each for SECONDS on a working copy of its seed
# corpus (tests/fuzz/corpus/<target>, grown in build-asan/corpus/<target>). A
# crash, a leak, an uncaught exception other than vtloc::Error, or a 10 s hang
# fails the run and leaves the input in build-asan/findings/<target>/.
#   bash tests/fuzz/run.sh [SECONDS] [TARGET ...]     (default: 30 s, every target)
set -euo pipefail
root="$(cd "$(dirname "$0")/../.." && pwd)"
seconds="${1:-30}"
shift || true
targets=("$@")
# Every target tests/fuzz/CMakeLists.txt declares (one list: a new target runs here by itself).
[ ${#targets[@]} -gt 0 ] ||
  mapfile -t targets < <(sed -n 's/^fuzz_target(\([a-z_0-9]*\)[ )].*/\1/p' "$root/tests/fuzz/CMakeLists.txt")
[ ${#targets[@]} -gt 0 ] || { echo "tests/fuzz/run.sh: no fuzz_target() in tests/fuzz/CMakeLists.txt" >&2; exit 1; }
build="$root/build-asan"
. "$root/tests/sanitize/asan_build.sh"
sanitizer_build "$root" "$build" "address,undefined" "${targets[@]/#/fuzz_}"
# One fuzzer per core, side by side (each is single-threaded: in turn, one core sat idle
# for the whole phase); each target keeps its own corpus, findings and log, and the
# results print in the targets' order.
fuzz_one() {
  local t="$1" corpus="$build/corpus/$1" findings="$build/findings/$1" log="$build/fuzz_$1.log"
  mkdir -p "$corpus" "$findings"
  cp -n "$root/tests/fuzz/corpus/$t/"* "$corpus/"
  # Leaks and undefined behaviour (UBSan halts) are findings too; the OpenCV decoders' thread pool is not ours: one thread.
  OPENCV_FOR_THREADS_NUM=1 ASAN_OPTIONS=detect_leaks=1 UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1 \
    "$build/tests/fuzz/fuzz_$t" "$corpus" -max_total_time="$seconds" -timeout=10 -rss_limit_mb=2048 \
    -print_final_stats=1 -artifact_prefix="$findings/" > "$log" 2>&1
}
jobs_max=$(nproc)
pids=()
for t in "${targets[@]}"; do
  while [ "$(jobs -rp | wc -l)" -ge "$jobs_max" ]; do wait -n || true; done
  fuzz_one "$t" &
  pids+=($!)
done
status=0
for k in "${!targets[@]}"; do
  t="${targets[$k]}"
  log="$build/fuzz_$t.log"
  if wait "${pids[$k]}"; then
    result=ok
  else
    result="FINDING (see $log and $build/findings/$t/)"
    status=1
  fi
  execs=$(grep -o 'stat::number_of_executed_units: *[0-9]*' "$log" | grep -o '[0-9]*$' || echo "?")
  cov=$(grep -o 'cov: [0-9]*' "$log" | tail -1 | grep -o '[0-9]*' || echo "?")
  printf '%-12s %4s s  %10s executions  %6s edges  %s\n' "$t" "$seconds" "$execs" "$cov" "$result"
done
exit $status
