#!/usr/bin/env bash
# Builds the module test suites with AddressSanitizer + UndefinedBehaviorSanitizer into build-asan/
# (GCC, as the normal build) and runs each once. Every sanitizer report aborts its test binary, so
# an out-of-bounds access, a use after free, undefined behaviour or a leak fails the run.
#
# Built and run: core, volume, wdt, render, quiz, lessons, db, segment (when present): every reader
# of outside data, the storage layer and the pure logic. Not built: the desktop app and test_app
# (SDL2, ImGui and the GL window under Xvfb; its CLI commands are thin callers of the code tested
# here, and an instrumented app would add about 10 minutes to CI for little coverage of our own
# code), and the CUDA tests (no GPU in CI; nvcc code is not instrumented).
#
# usage: scripts/sanitize.sh [ctest arguments]     (AT_JOBS=N sets build parallelism)
set -euo pipefail
cd "$(dirname "$0")/.."
jobs=${AT_JOBS:-$(nproc)}
dir=build-asan
if [ ! -f "$dir/build.ninja" ]; then
  cmake -S . -B "$dir" -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo -DAT_SANITIZE=ON ${AT_SANITIZE_CMAKE_ARGS:-}
fi

modules=()
for m in core volume wdt render quiz lessons db segment; do
  if grep -q "build tests/test_$m:" "$dir/build.ninja"; then modules+=("$m"); fi
done
targets=("${modules[@]/#/test_}")
echo "sanitize: building ${targets[*]}"
cmake --build "$dir" -j "$jobs" --target "${targets[@]}"

# Leaks inside third-party libraries that the tests only call (Mesa's GL driver, fontconfig) are
# suppressed by library name in tests/fuzz/lsan.supp; leaks in project code are never suppressed.
export ASAN_OPTIONS="abort_on_error=1:detect_leaks=1:strict_string_checks=1:check_initialization_order=1${ASAN_OPTIONS:+:$ASAN_OPTIONS}"
export UBSAN_OPTIONS="halt_on_error=1:print_stacktrace=1${UBSAN_OPTIONS:+:$UBSAN_OPTIONS}"
export LSAN_OPTIONS="suppressions=$PWD/tests/fuzz/lsan.supp:print_suppressions=0${LSAN_OPTIONS:+:$LSAN_OPTIONS}"
regex="^($(IFS='|'; echo "${modules[*]}"))\$"
cd "$dir"
ctest --output-on-failure --timeout 2400 -R "$regex" "$@"
