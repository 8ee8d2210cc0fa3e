#!/usr/bin/env bash
# Runs the libFuzzer harnesses of tests/fuzz (one per reader of outside data) with AddressSanitizer,
# UndefinedBehaviorSanitizer and LeakSanitizer. Builds them with clang-14 into build-fuzz/ first.
#
# usage: scripts/fuzz.sh [--seconds N | --runs N] [--parallel P] [HARNESS...]
#   --seconds N   fuzz each harness for N seconds (default 25: what CI runs)
#   --runs N      fuzz each harness for N executions instead (the long runs: --runs 1000000)
#   --parallel P  run P harnesses at a time (default 1)
#   HARNESS       nifti nrrd nrrd_detached dicom_series dicom_seg png inv3 label_names preset course
#                 question answer study_protocol package … (default: every harness that was built)
#   --print-dict H  print the dictionary file harness H uses (bench/collect_fuzz_binaries.sh)
#
# Each harness first replays its past findings (tests/fuzz/regressions/<harness>/), then fuzzes from
# its corpus: the generated seeds (at_fuzz_seeds: small valid files of each kind, the repository's
# JSON data, small files of ../shared/data), the hand-made seeds of tests/fuzz/corpus/<harness>/ and
# what earlier runs on this machine kept in build-fuzz/fuzz-corpus/<harness>/, with the dictionary
# tests/fuzz/dict/<name>.dict. A crash, sanitizer report, leak or input slower than 10 s fails the
# run; libFuzzer writes the input to build-fuzz/fuzz-findings/. A summary line per harness (runs,
# runs per second, corpus size, result) goes to stdout and to build-fuzz/fuzz-summary.txt.
set -euo pipefail
cd "$(dirname "$0")/.."
# The dictionary a harness uses (harnesses of one format share one).
dictionary() {
  case "$1" in
    nrrd|nrrd_detached|seg_nrrd) echo tests/fuzz/dict/nrrd.dict ;;
    dicom_series|dicom_seg) echo tests/fuzz/dict/dicom.dict ;;
    course|question) echo tests/fuzz/dict/course.dict ;;
    *) [ -f "tests/fuzz/dict/$1.dict" ] && echo "tests/fuzz/dict/$1.dict" || true ;;
  esac
}

seconds=25
runs=""
parallel=1
harnesses=()
while [ $# -gt 0 ]; do
  case "$1" in
    --seconds) seconds="$2"; shift 2 ;;
    --runs) runs="$2"; shift 2 ;;
    --parallel) parallel="$2"; shift 2 ;;
    --print-dict) dictionary "$2"; exit 0 ;;
    -h|--help) sed -n '2,20p' "$0"; exit 0 ;;
    -*) echo "fuzz.sh: unknown option $1" >&2; exit 2 ;;
    *) harnesses+=("$1"); shift ;;
  esac
done

dir=build-fuzz
jobs=${AT_JOBS:-$(nproc)}
launcher=()
if command -v ccache >/dev/null; then
  launcher=(-DCMAKE_C_COMPILER_LAUNCHER=ccache -DCMAKE_CXX_COMPILER_LAUNCHER=ccache)
  export CCACHE_BASEDIR=${CCACHE_BASEDIR:-$(dirname "$PWD")}  # another clone's build hits too
fi
if [ ! -f "$dir/build.ninja" ]; then
  cmake -S . -B "$dir" -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo -DCMAKE_C_COMPILER=clang-14 \
    -DCMAKE_CXX_COMPILER=clang++-14 -DAT_FUZZ=ON -DAT_BUILD_TESTS=OFF "${launcher[@]}" ${AT_FUZZ_CMAKE_ARGS:-}
fi
cmake --build "$dir" -j "$jobs" --target fuzz_all

if [ ${#harnesses[@]} -eq 0 ]; then
  for binary in "$dir"/tests/fuzz/fuzz_*; do harnesses+=("$(basename "$binary" | sed 's/^fuzz_//')"); done
fi

seeds="$dir/fuzz-seeds"
rm -rf "$seeds"
"$dir/tests/fuzz/at_fuzz_seeds" "$seeds"
mkdir -p "$dir/fuzz-corpus" "$dir/fuzz-findings" "$dir/fuzz-logs"

export ASAN_OPTIONS="abort_on_error=1:detect_leaks=1${ASAN_OPTIONS:+:$ASAN_OPTIONS}"
export UBSAN_OPTIONS="halt_on_error=1:print_stacktrace=1${UBSAN_OPTIONS:+:$UBSAN_OPTIONS}"
export LSAN_OPTIONS="suppressions=$PWD/tests/fuzz/lsan.supp:print_suppressions=0${LSAN_OPTIONS:+:$LSAN_OPTIONS}"

# Fuzzes one harness; prints its summary line; returns non-zero on a finding.
fuzz_one() {
  local name="$1"
  local binary="$dir/tests/fuzz/fuzz_$name"
  local log="$dir/fuzz-logs/$name.log"
  local corpus="$dir/fuzz-corpus/$name"
  mkdir -p "$corpus"
  if [ ! -x "$binary" ]; then
    echo "fuzz $name: no harness $binary" | tee -a "$dir/fuzz-summary.txt"
    return 1
  fi
  # Past findings first: each must now load or fail cleanly.
  local regressions=(tests/fuzz/regressions/"$name"/*)
  if [ -e "${regressions[0]}" ]; then
    if ! "$binary" -timeout=10 "${regressions[@]}" >"$log.regressions" 2>&1; then
      echo "fuzz $name: FAILED replaying tests/fuzz/regressions/$name (see $log.regressions)" | tee -a "$dir/fuzz-summary.txt"
      return 1
    fi
  fi
  local limit=(-max_total_time="$seconds")
  [ -n "$runs" ] && limit=(-runs="$runs")
  local dict
  dict=$(dictionary "$name")
  local sources=("$corpus")
  for extra in "$seeds/$name" "tests/fuzz/corpus/$name"; do [ -d "$extra" ] && sources+=("$extra"); done
  local started=$SECONDS status=0
  "$binary" "${sources[@]}" "${limit[@]}" -timeout=10 -rss_limit_mb=2048 -print_final_stats=1 \
    -artifact_prefix="$dir/fuzz-findings/$name-" ${dict:+-dict="$dict"} >"$log" 2>&1 || status=$?
  local executed rate peak units
  executed=$(awk '/stat::number_of_executed_units:/ {print $2}' "$log")
  rate=$(awk '/stat::average_exec_per_sec:/ {print $2}' "$log")
  peak=$(awk '/stat::peak_rss_mb:/ {print $2}' "$log")
  units=$(find "$corpus" -type f | wc -l)
  local result="ok"
  if [ "$status" -ne 0 ]; then
    result="FAILED (exit $status; $(grep -m1 -E 'ERROR|runtime error|at-fuzz:|timeout' "$log" | cut -c1-160); log $log)"
    # The finding's own lines (the message a reader produced, the sanitizer's first frames), so a
    # CI log shows what broke without the log file.
    grep -m1 -A6 -E 'ERROR|runtime error|at-fuzz:|timeout' "$log" | sed "s/^/  $name| /" >&2 || true
  fi
  printf 'fuzz %-15s %10s runs %6s/s %5s corpus files %5s MB peak %6ss  %s\n' "$name" "${executed:-0}" \
    "${rate:-0}" "$units" "${peak:-?}" "$((SECONDS - started))" "$result" | tee -a "$dir/fuzz-summary.txt"
  [ "$status" -eq 0 ]
}

budget="$seconds s"
[ -n "$runs" ] && budget="$runs runs"
echo "== fuzz.sh $(date -u +%FT%TZ): $budget per harness, $(nproc) cores" | tee -a "$dir/fuzz-summary.txt"
failed=0
pids=()
for name in "${harnesses[@]}"; do
  fuzz_one "$name" &
  pids+=($!)
  if [ ${#pids[@]} -ge "$parallel" ]; then
    wait "${pids[0]}" || failed=1
    pids=("${pids[@]:1}")
  fi
done
for pid in "${pids[@]}"; do wait "$pid" || failed=1; done
if [ "$failed" -ne 0 ]; then
  echo "fuzz.sh: a harness found a problem (inputs in $dir/fuzz-findings/)" >&2
  exit 1
fi
