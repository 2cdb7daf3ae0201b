#!/usr/bin/env bash
# Runs a sanitizer build's tests with the sanitizers' options set:
#   scripts/sanitize.sh address|thread BUILD_DIR [ctest arguments...]
# address: the default test suite (labels bench, long and fuzz excluded) under
# ASan, LSan and UBSan. thread: the tests of flowplan's threaded parts under TSan.
# Suppressions come from scripts/sanitizer_suppressions.txt, the only list.
set -euo pipefail
mode=${1:?usage: sanitize.sh address|thread BUILD_DIR [ctest args]}
build=${2:?usage: sanitize.sh address|thread BUILD_DIR [ctest args]}
shift 2
build=$(cd "$build" && pwd)
here=$(cd "$(dirname "$0")" && pwd)
list=$here/sanitizer_suppressions.txt
[ -r "$list" ] || { echo "sanitize.sh: $list: cannot read the suppression list" >&2; exit 2; }
supp=$build/sanitizers
mkdir -p "$supp"
pick() { grep -E "^($1):" "$list" || true; }
pick 'leak' > "$supp/lsan.supp"
pick 'race|race_top|deadlock|mutex|signal|thread|called_from_lib' > "$supp/tsan.supp"

# UBSan is built not to recover (-fno-sanitize-recover): its reports cannot be suppressed, only fixed.
export UBSAN_OPTIONS="print_stacktrace=1:halt_on_error=1"
case "$mode" in
  address)
    export ASAN_OPTIONS="detect_leaks=1:abort_on_error=0:strict_string_checks=1:detect_stack_use_after_return=1:check_initialization_order=1"
    export LSAN_OPTIONS="suppressions=$supp/lsan.supp:print_suppressions=0"
    exec ctest --test-dir "$build" -LE 'bench|long|fuzz' --output-on-failure "$@"
    ;;
  thread)
    export TSAN_OPTIONS="halt_on_error=1:second_deadlock_stack=1:suppressions=$supp/tsan.supp"
    # LibTorch's intra-op pool is OpenMP, which TSan cannot see into: one thread there.
    export OMP_NUM_THREADS=1
    # flowplan's own threads (core/parallel.h: data generation, chunked planning and evaluation, scene
    # families, sharded gradients) and the processes of a distributed job. Not the native kernels' tests
    # for several thread counts (SameBitsForAnyThreadCount): those threads are LibTorch's OpenMP pool.
    # Cases are selected by name: the build must register each as a CTest test (a thread build does by default).
    if ! grep -q '^FLOWPLAN_TEST_EACH_CASE:BOOL=ON$' "$build/CMakeCache.txt"; then
      echo "sanitize.sh: $build: configured without FLOWPLAN_TEST_EACH_CASE=ON; the thread mode selects test cases by name" >&2
      exit 2
    fi
    threaded='ParallelTest|GeneratorTest|FrankaDatasetTest|ThreadCount|Shard|InChunks|DistributedTest|SceneFamil'
    exec ctest --test-dir "$build" -R "$threaded" -E 'SameBitsForAnyThreadCount' -LE 'bench|long|fuzz' \
      --output-on-failure "$@"
    ;;
  *) echo "sanitize.sh: unknown mode '$mode' (expected address or thread)" >&2; exit 2 ;;
esac
