# Sourced by tests/sanitize/run.sh and tests/fuzz/run.sh: the one clang build
# configuration both use, so the libraries compile once for the ASan run and
# the fuzzers (build-asan/ holds both; build-tsan/ the TSan run).
#   sanitizer_build ROOT BUILD-DIR SANITIZERS TARGET...
# configures BUILD-DIR on first use and builds the TARGETs. The [golden] tests
# read ROOT/build/goldens, which the README's test command writes.
sanitizer_build() {
  local root="$1" build="$2" sanitizers="$3"
  shift 3
  if [ ! -f "$build/CMakeCache.txt" ]; then
    CC=clang CXX=clang++ cmake -S "$root" -B "$build" -DVTLOC_SANITIZE="$sanitizers" -DVTLOC_BUILD_PYTHON=OFF \
      -DCMAKE_BUILD_TYPE=RelWithDebInfo -DVTLOC_GOLDENS_DIR="$root/build/goldens" > /dev/null
  fi
  cmake --build "$build" -j"$(nproc)" --target "$@" > /dev/null
}
