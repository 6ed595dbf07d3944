#!/usr/bin/env bash
# Sanitizer runs of the C++ test suite (clang; README "Development"):
#   asan: every target built with ASan + UBSan (build-asan/), the whole
#         vtloc_tests suite in one process, leaks checked (LSan) at exit;
#   tsan: every target built with TSan (build-tsan/), the tests that use
#         threads ([threads]).
# Vulkan runs on lavapipe; Mesa, the loader and the validation layer are
# Debian's, not instrumented: the suppression files next to this script name
# what is theirs and why. Any report in our code fails the run.
#   bash tests/sanitize/run.sh [asan|tsan ...]      (default: asan tsan)
# Run after the README's test command: the [golden] tests read build/goldens.
set -euo pipefail
root="$(cd "$(dirname "$0")/../.." && pwd)"
here="$root/tests/sanitize"
kinds=("$@")
[ ${#kinds[@]} -gt 0 ] || kinds=(asan tsan)
goldens="$root/build/goldens"
if [ ! -d "$goldens" ]; then
  echo "sanitize: $goldens is missing: run the README's test command first" >&2
  exit 1
fi

configure() {  # build-dir sanitizers
  if [ ! -f "$1/CMakeCache.txt" ]; then
    CC=clang CXX=clang++ cmake -S "$root" -B "$1" -DVTLOC_SANITIZE="$2" -DVTLOC_BUILD_PYTHON=OFF \
      -DCMAKE_BUILD_TYPE=RelWithDebInfo -DVTLOC_GOLDENS_DIR="$goldens" > /dev/null
  fi
  cmake --build "$1" -j"$(nproc)" --target vtloc_tests > /dev/null
}

status=0
for kind in "${kinds[@]}"; do
  case "$kind" in
    asan)
      build="$root/build-asan"
      configure "$build" "address,undefined"
      echo "sanitize: ASan + UBSan, the whole vtloc_tests suite"
      if ! (cd "$build" && VTLOC_VALIDATION=1 \
            ASAN_OPTIONS="detect_leaks=1:abort_on_error=0:strict_string_checks=1:detect_stack_use_after_return=1" \
            LSAN_OPTIONS="suppressions=$here/lsan.supp:print_suppressions=0" \
            UBSAN_OPTIONS="print_stacktrace=1:halt_on_error=0" \
            tests/vtloc_tests --order decl > "$build/sanitize.log" 2>&1); then
        status=1
      fi
      # UBSan reports and goes on (every finding of a run in one log); any report fails.
      if grep -q "runtime error:" "$build/sanitize.log"; then
        grep "runtime error:" "$build/sanitize.log" | sort | uniq -c >&2
        status=1
      fi
      tail -n 4 "$build/sanitize.log"
      ;;
    tsan)
      build="$root/build-tsan"
      configure "$build" "thread"
      echo "sanitize: TSan, the [threads] tests"
      if ! (cd "$build" && VTLOC_VALIDATION=1 \
            TSAN_OPTIONS="suppressions=$here/tsan.supp:halt_on_error=0:second_deadlock_stack=1" \
            tests/vtloc_tests "[threads]" > "$build/sanitize.log" 2>&1); then
        status=1
      fi
      if grep -q "WARNING: ThreadSanitizer" "$build/sanitize.log"; then
        grep "WARNING: ThreadSanitizer" "$build/sanitize.log" | sort | uniq -c >&2
        status=1
      fi
      tail -n 4 "$build/sanitize.log"
      ;;
    *) echo "sanitize: unknown kind $kind (asan, tsan)" >&2; exit 2 ;;
  esac
done
exit $status
