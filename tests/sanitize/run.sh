#!/usr/bin/env bash
# Sanitizer runs of the C++ test suite (clang; docs/testing.md):
#   asan: every target built with ASan + UBSan (build-asan/), the
#         vtloc_tests suite but the long and variant sweeps, a share per core,
#         leaks checked (LSan) at exit;
#   tsan: the libraries and vtloc_thread_tests (test_api.cpp, test_made_once.cpp) built with
#         TSan (build-tsan/), the tests that use threads ([threads]).
# Vulkan runs on lavapipe; Mesa, the loader and the validation layer are
# Debian's, not instrumented: the suppression files next to this script name
# what is theirs and why. Any report in our code fails the run.
#   bash tests/sanitize/run.sh [asan|tsan ...]      (default: asan tsan)
# Run after the README's test command (build/): the paper-size [golden] cases read
# build/goldens, which the long suite's fixture writes (made here if missing).
set -euo pipefail
set -f  # test filters such as [threads] are Catch tags, not globs
root="$(cd "$(dirname "$0")/../.." && pwd)"
here="$root/tests/sanitize"
kinds=("$@")
[ ${#kinds[@]} -gt 0 ] || kinds=(asan tsan)
goldens="$root/build/goldens"
if [ ! -f "$goldens/vtloc-r18.golden.safetensors" ]; then
  ctest --test-dir "$root/build" -R '^goldens\.paper$' --output-on-failure > /dev/null || {
    echo "sanitize: writing the paper-size goldens ($goldens) failed: run 'ctest --test-dir build -R goldens.paper' to see why" >&2
    exit 1
  }
fi

. "$here/asan_build.sh"

# run BUILD-DIR SANITIZERS TARGET REPORT-PATTERN TEST-FILTERS [ENV=VALUE ...]: builds the
# test binary TARGET, runs it once per filter of TEST-FILTERS ('|' between them; the
# processes run side by side, one per core), fails on any exit status or any report in
# their logs (reports do not halt a run, so one run shows them all).
status=0
# shard BUILD-DIR TARGET SPEC: the test cases SPEC selects, dealt to one list per
# process by their measured cost (durations.tsv beside this script: seconds, a tab,
# the case's name, from a --durations run; an unlisted case counts 1 s, none less than
# 0.01 s so that every list gets a case), the
# costliest first, each to the list with the least so far; each list a Catch input
# file (-f: a name per line, quoted by Catch); prints the filters. Dealt in
# declaration order instead, the two lists ended 2-2.5 minutes apart.
# Processes: one per core, at least 2, at most one per 6 GiB available (each holds
# ~5.5 GB with ASan's shadow); SANITIZE_JOBS overrides.
shard() {
  local n k mem_gib out="" names="$1/shard.names" durations="$here/durations.tsv"
  [ -f "$durations" ] || durations=/dev/null
  n=$(nproc)
  [ "$n" -ge 2 ] || n=2
  mem_gib=$(awk '/^MemAvailable:/ { print int($2 / 1048576) }' /proc/meminfo 2> /dev/null || echo 12)
  [ "$n" -le $((mem_gib / 6)) ] || n=$((mem_gib / 6))
  [ "$n" -ge 1 ] || n=1
  n=${SANITIZE_JOBS:-$n}
  find "$1" -maxdepth 1 -name 'shard.*.txt' -delete  # a shorter list must not leave old ones (set -f: no globs)
  # Catch 2's listing exits with the number of cases it lists: its output is what counts.
  (cd "$1" && "tests/$2" --list-test-names-only "$3" > "$names") || true
  if [ "$(sed '/^$/d' "$names" | wc -l)" -lt "$n" ]; then
    echo "sanitize: listing $2's cases ($3) gave fewer than $n" >&2
    exit 1
  fi
  sed '/^$/d' "$names" |
    awk -F '\t' -v costs="$durations" 'FILENAME == costs { cost[$2] = $1; next }
      { c = ($0 in cost) ? cost[$0] + 0 : 1; printf "%s\t%s\n", (c > 0.01 ? c : 0.01), $0 }' "$durations" - |
    sort -t "$(printf '\t')" -k1,1gr -k2,2 |
    awk -F '\t' -v n="$n" -v dir="$1" '{
      best = 0
      for (k = 1; k < n; k++) if (load[k] < load[best]) best = k
      load[best] += $1
      name = substr($0, index($0, "\t") + 1)
      gsub(/[\\",]/, "\\\\&", name)
      print name > (dir "/shard." best ".txt")
    }'
  for ((k = 0; k < n; k++)); do out+="${out:+|}--order decl --durations yes -f shard.$k.txt"; done
  printf '%s' "$out"
}

run() {
  local build="$root/$1" sanitizers="$2" target="$3" pattern="$4" filters="$5"
  shift 5
  sanitizer_build "$root" "$build" "$sanitizers" "$target"
  local pids=() logs=() k=0 filter
  case "$filters" in
    shards:*) filters=$(shard "$build" "$target" "${filters#shards:}") ;;
  esac
  IFS='|' read -r -a parts <<< "$filters"
  for filter in "${parts[@]}"; do
    logs+=("$build/sanitize.$k.log")
    (cd "$build" && env VTLOC_VALIDATION=1 "$@" "tests/$target" $filter > "$build/sanitize.$k.log" 2>&1) &
    pids+=($!)
    k=$((k + 1))
  done
  for pid in "${pids[@]}"; do wait "$pid" || status=1; done
  cat "${logs[@]}" > "$build/sanitize.log"
  if grep -q "$pattern" "$build/sanitize.log"; then
    grep "$pattern" "$build/sanitize.log" | sort | uniq -c >&2
    status=1
  fi
  for log in "${logs[@]}"; do tail -n 2 "$log"; done
}

for kind in "${kinds[@]}"; do
  case "$kind" in
    asan)
      echo "sanitize: ASan + UBSan, the whole vtloc_tests suite but the point-MLP variant sweeps (a share per core, side by side)"
      # ~[long]: the full-size sweeps and chamfer at 16,384 points (the quick versions cover the same paths);
      # ~[sweep]: those quick versions too, the three point-MLP variant sweeps (~210 of
      # ~1,225 test-seconds here: the CPU reference's loops instrumented); their host
      # code (group_linear's tile and pipeline choice, its CPU reference) runs in the
      # other [group_linear] cases, and a variant's numbers are the shader's, which
      # ASan does not see;
      # ~[subgroup_sweep]: the same sweeps on the subgroup shader's variants (for the subgroup-4 run);
      # ~[picture]: the hidden case that rewrites a picture in docs/ (exclusions alone match hidden cases);
      # ~[selftest]: the op self-test, whose host code is every op's CPU reference and recording,
      # which the ops' own cases run here (it runs at both subgroup sizes in the long suite; here
      # it compiled ~100 pipelines cold and took 36 s);
      # ~[paper]: the paper size's end-to-end, tactile and point-encoder goldens (50 s here,
      # its CPU reference in instrumented loops); the tiny models' goldens run the same graph
      # building and recording; GMA's paper-size goldens (the split W^d; [post][paper], in the
      # long suite under ctest) stay.
      # GALLIVM_PERF=nopt, as the README's command runs lavapipe: ASan sees our host code, not
      # the JIT's, and Mesa's disk cache keys on the flag, so the run reuses the command's
      # compiled pipelines instead of compiling each cold with LLVM's passes (most of this
      # run's time on a fresh machine: docs/testing.md). The optimised JIT still runs every
      # op in the long suite (long/opt/: the op self-test) and the TSan run below.
      run build-asan "address,undefined" vtloc_tests "runtime error:" \
        "shards:~[long]~[sweep]~[subgroup_sweep]~[picture]~[selftest]~[paper],[post][paper]" \
        GALLIVM_PERF="${GALLIVM_PERF-nopt}" \
        ASAN_OPTIONS="detect_leaks=1:strict_string_checks=1:detect_stack_use_after_return=1" \
        LSAN_OPTIONS="suppressions=$here/lsan.supp:print_suppressions=0" \
        UBSAN_OPTIONS="print_stacktrace=1:halt_on_error=0"
      ;;
    tsan)
      echo "sanitize: TSan, the [threads] tests (their own binary: test_api.cpp and test_made_once.cpp)"
      run build-tsan "thread" vtloc_thread_tests "WARNING: ThreadSanitizer" "[threads]" \
        TSAN_OPTIONS="suppressions=$here/tsan.supp:halt_on_error=0:second_deadlock_stack=1"
      ;;
    *) echo "sanitize: unknown kind $kind (asan, tsan)" >&2; exit 2 ;;
  esac
done
exit $status
