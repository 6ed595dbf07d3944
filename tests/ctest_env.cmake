# Read by ctest before it starts any test (TEST_INCLUDE_FILES); the tests inherit
# ctest's environment.
#
# OpenBLAS is loaded by every test process (OpenCV's core links LAPACK) though the
# engine never calls it, and at load it starts a thread per core that spins on
# sched_yield for about 0.1 s: 0.14 s of CPU in each of ~500 processes, which the
# README's command, two tests at a time on two cores, paid in wall time. One
# thread starts none. A user's own setting is kept.
if(NOT DEFINED ENV{OPENBLAS_NUM_THREADS})
  set(ENV{OPENBLAS_NUM_THREADS} 1)
endif()
# lavapipe's JIT without LLVM's optimisation passes (Mesa's GALLIVM_PERF=nopt): the
# tests check what the shaders compute, and a first run spends most of its time
# compiling ~900 pipelines. README command, same hour: cold with an AVX2 JIT 365 s
# with the passes, 301 s without; warm and native 180 s and 236 s (docs/testing.md).
# Mesa keys its disk cache on the flag, so the two never share code. CI's ASan run
# (not under ctest) goes without them too; its TSan run keeps them. A user's own setting is kept.
if(NOT DEFINED ENV{GALLIVM_PERF})
  set(ENV{GALLIVM_PERF} nopt)
endif()
