#!/usr/bin/env bash
# The long fuzzing runs (≥ 10^6 executions per harness, nothing found) on a machine
# with many cores and none of our Debian libraries: the 16-core GPU host of the device tool.
# bench/collect_fuzz_binaries.sh puts this script beside payload.tar.xz (the libFuzzer harnesses
# with ASan + UBSan + LeakSanitizer, the shared libraries they need, seeds, earlier corpora,
# dictionaries, past findings) in .fuzz-gpu/; run it from anywhere:
#
#   bash .fuzz-gpu/run_fuzz_campaign.sh [--runs N] [--budget SECONDS] [--cores N] [HARNESS...]
#     --runs N        executions per harness (default 1000000), shared among its workers
#     --budget S      wall seconds for the whole campaign (default 480); a harness still running
#                     at the end is stopped by libFuzzer's -max_total_time and reports the
#                     executions it reached (then below --runs: the table says so)
#     --cores N       fuzzer processes at a time (default: nproc)
#     HARNESS         names as in scripts/fuzz.sh (default: every harness in the payload)
#
# Scheduling: each harness gets workers in proportion to its cost (microseconds per execution on
# one core, measured first in an 8 s calibration run per harness, else the dev machine's table
# below) so that it finishes in about half the remaining budget; harnesses start longest first as cores come free (slow ones such as dicom_seg get the
# most workers). Each harness first replays its past findings, then runs `-jobs=W -workers=W` with
# -runs=ceil(N/W) per job on one shared corpus. Writes to $OUT (or .fuzz-gpu/out): summary.md (a
# table: executions, exec/s, workers, crashes, leaks, timeouts, out-of-memory, peak RSS per
# harness), findings/<harness>/ (inputs that failed), logs.tar.gz, machine.txt. Exit status 0
# only when every harness reached N executions with nothing found.
set -uo pipefail
here=$(cd "$(dirname "$0")" && pwd)
runs=1000000
budget=480
cores=$(nproc)
harnesses=()
while [ $# -gt 0 ]; do
  case "$1" in
    --runs) runs="$2"; shift 2 ;;
    --budget) budget="$2"; shift 2 ;;
    --cores) cores="$2"; shift 2 ;;
    -h|--help) sed -n '2,25p' "$0"; exit 0 ;;
    -*) echo "run_fuzz_campaign: unknown option $1" >&2; exit 2 ;;
    *) harnesses+=("$1"); shift ;;
  esac
done
out=${OUT:-$here/out}
mkdir -p "$out"
started=$SECONDS
deadline=$((started + budget))

work=$(mktemp -d "${TMPDIR:-/tmp}/at-fuzz-campaign.XXXXXX")
tar -xJf "$here/payload.tar.xz" -C "$work" || { echo "run_fuzz_campaign: cannot unpack $here/payload.tar.xz" >&2; exit 1; }
export LD_LIBRARY_PATH="$work/lib${LD_LIBRARY_PATH:+:$LD_LIBRARY_PATH}"
export ASAN_OPTIONS="abort_on_error=1:detect_leaks=1"
export UBSAN_OPTIONS="halt_on_error=1:print_stacktrace=1"
export LSAN_OPTIONS="suppressions=$work/lsan.supp:print_suppressions=0"
# The harnesses write each input (and a package's extracted files) to a scratch folder: /dev/shm
# unless it is small, as in many containers.
shm_kb=$(df -Pk /dev/shm 2>/dev/null | awk 'NR == 2 {print $2}')
if [ -z "$shm_kb" ] || [ "$shm_kb" -lt $((4 * 1024 * 1024)) ]; then
  export AT_FUZZ_SCRATCH="$work/scratch"
  mkdir -p "$AT_FUZZ_SCRATCH"
fi

if [ ${#harnesses[@]} -eq 0 ]; then
  for binary in "$work"/bin/fuzz_*; do harnesses+=("$(basename "$binary" | sed 's/^fuzz_//')"); done
fi

# Calibration: every harness alone on one core for 8 s on its corpus (as many at a time as there
# are cores); the executions per second it reaches (corpus loading included, so slightly low)
# give its cost on this machine.
declare -A measured
calibrate() {
  mkdir -p "$work/calibration"
  local name pids=()
  for name in "${harnesses[@]}"; do
    (
      mkdir -p "$work/calibration/$name"
      sources=("$work/calibration/$name")
      for extra in "$work/corpus/$name" "$work/seeds/$name"; do [ -d "$extra" ] && sources+=("$extra"); done
      timeout 60 "$work/bin/fuzz_$name" "${sources[@]}" -max_total_time=8 -timeout=10 -rss_limit_mb=2048 \
        -print_final_stats=1 -artifact_prefix="$work/calibration/$name-" >"$work/calibration/$name.log" 2>&1
    ) &
    pids+=($!)
    if [ ${#pids[@]} -ge "$cores" ]; then wait "${pids[0]}"; pids=("${pids[@]:1}"); fi
  done
  wait
  for name in "${harnesses[@]}"; do
    measured[$name]=$(awk '/stat::average_exec_per_sec:/ {print $2}' "$work/calibration/$name.log")
  done
}
calibrate

# Microseconds per execution on one core: from the calibration, else the dev machine's (20 s runs
# on the seed corpus, bench/RESULTS.md).
cost_us() {
  local rate=${measured[$1]:-0}
  if [ "$rate" -gt 0 ] 2>/dev/null; then
    echo $((1000000 / rate + 1))
    return
  fi
  case "$1" in
    png|question) echo 80 ;;
    nifti|preset|study_protocol) echo 100 ;;
    label_names|segment_seeds) echo 150 ;;
    nrrd_detached) echo 200 ;;
    answer) echo 230 ;;
    nrrd|seg_nrrd|dicom_series) echo 420 ;;
    course) echo 460 ;;
    inv3|package) echo 620 ;;
    dicom_seg) echo 820 ;;
    *) echo 500 ;;
  esac
}

# Workers per harness: enough to do --runs in about half the remaining budget, at most half the cores.
declare -A workers
total_work=0
half=$(( (deadline - SECONDS) / 2 ))
[ "$half" -lt 1 ] && half=1
for name in "${harnesses[@]}"; do
  work_s=$(( $(cost_us "$name") * runs / 1000000 ))
  total_work=$((total_work + work_s))
  w=$(( (work_s + half - 1) / half ))
  [ "$w" -lt 1 ] && w=1
  # At most half the cores each, unless the campaign is this one harness.
  most=$(( ${#harnesses[@]} == 1 ? cores : (cores / 2 > 0 ? cores / 2 : 1) ))
  [ "$w" -gt "$most" ] && w=$most
  workers[$name]=$w
done
# Longest first.
mapfile -t order < <(for name in "${harnesses[@]}"; do echo "$(( $(cost_us "$name") * runs / ${workers[$name]} )) $name"; done |
  sort -rn | awk '{print $2}')

{
  echo "date: $(date -u +%FT%TZ)"
  lscpu 2>/dev/null | grep -E "Model name|^CPU\(s\)" || true
  grep MemTotal /proc/meminfo || true
  echo "cores used: $cores; budget: $budget s; executions per harness: $runs"
  echo "estimated work: $total_work core-seconds"
  for name in "${order[@]}"; do echo "  $name: $(cost_us "$name") us per execution (calibration: ${measured[$name]:-none} exec/s), ${workers[$name]} workers"; done
  cat "$work/manifest.txt" 2>/dev/null
} > "$out/machine.txt"
echo "run_fuzz_campaign: ${#order[@]} harnesses, $runs executions each, $cores cores, $budget s (estimated $total_work core-s)"
if [ "$total_work" -gt $((cores * (deadline - SECONDS))) ]; then
  echo "run_fuzz_campaign: the estimate exceeds $cores cores × the $((deadline - SECONDS)) s left: some harnesses will stop below $runs (give them a run of their own)"
fi

# Runs one harness with W workers until its executions or its time are spent; the summary is
# written afterwards from its logs.
run_harness() {
  local name="$1" w="$2" seconds="$3"
  local dir="$work/run/$name"
  mkdir -p "$dir/corpus" "$dir/findings"
  local sources=("$dir/corpus")
  for extra in "$work/corpus/$name" "$work/seeds/$name"; do [ -d "$extra" ] && sources+=("$extra"); done
  local regressions=("$work"/regressions/"$name"/*)
  if [ -e "${regressions[0]}" ]; then
    "$work/bin/fuzz_$name" -timeout=10 -rss_limit_mb=2048 "${regressions[@]}" >"$dir/regressions.log" 2>&1
    echo $? >"$dir/regressions.status"
  fi
  local dict=()
  [ -f "$work/dict/$name.dict" ] && dict=(-dict="$work/dict/$name.dict")
  local per_job=$(( (runs + w - 1) / w ))
  local begun=$SECONDS
  (cd "$dir" && "$work/bin/fuzz_$name" "${sources[@]}" -jobs="$w" -workers="$w" -runs="$per_job" \
      -max_total_time="$seconds" -timeout=10 -rss_limit_mb=2048 -print_final_stats=1 \
      -artifact_prefix="$dir/findings/" "${dict[@]}" >"$dir/main.log" 2>&1)
  echo $((SECONDS - begun)) >"$dir/seconds"
}

declare -A pid_of slots_of
free=$cores
for name in "${order[@]}"; do
  w=${workers[$name]}
  [ "$w" -gt "$cores" ] && w=$cores
  while [ "$free" -lt "$w" ]; do
    wait -n -p done_pid
    for n in "${!pid_of[@]}"; do
      if [ "${pid_of[$n]}" = "$done_pid" ]; then free=$((free + slots_of[$n])); unset "pid_of[$n]"; fi
    done
  done
  left=$((deadline - SECONDS - 10))
  # A harness gets three times its estimated time (at least 120 s), not the whole budget: otherwise
  # the first ones started hold their cores to the end and the rest never start. (The calibration
  # is optimistic: executions slow down as the corpus grows.)
  estimate=$(( $(cost_us "$name") * runs / 1000000 / w ))
  cap=$(( 3 * estimate > 120 ? 3 * estimate : 120 ))
  [ "$cap" -lt "$left" ] && left=$cap
  if [ "$left" -lt 30 ]; then
    echo "run_fuzz_campaign: $name not started (budget spent)"
    mkdir -p "$work/run/$name" && echo "not started: budget spent" >"$work/run/$name/skipped"
    continue
  fi
  echo "run_fuzz_campaign: $(date -u +%T) $name with $w workers, at most $left s"
  run_harness "$name" "$w" "$left" &
  pid_of[$name]=$!
  slots_of[$name]=$w
  free=$((free - w))
done
wait

# The table.
summary="$out/summary.md"
failed=0
{
  echo "Fuzz campaign: $runs executions per harness, $cores cores, budget $budget s, wall $((SECONDS - started)) s"
  echo
  echo "| harness | executions | exec/s | workers | seconds | crashes | leaks | timeouts | out of memory | peak RSS MB | past findings | result |"
  echo "|---|---|---|---|---|---|---|---|---|---|---|---|"
} >"$summary"
for name in "${order[@]}"; do
  dir="$work/run/$name"
  if [ -f "$dir/skipped" ]; then
    echo "| $name | 0 | – | ${workers[$name]} | – | – | – | – | – | – | – | NOT RUN (budget spent) |" >>"$summary"
    failed=1
    continue
  fi
  executed=$(cat "$dir"/fuzz-*.log 2>/dev/null | awk '/stat::number_of_executed_units:/ {s += $2} END {print s + 0}')
  peak=$(cat "$dir"/fuzz-*.log 2>/dev/null | awk '/stat::peak_rss_mb:/ {if ($2 > m) m = $2} END {print m + 0}')
  seconds=$(cat "$dir/seconds" 2>/dev/null || echo 0)
  rate=$(( seconds > 0 ? executed / seconds : 0 ))
  count() { find "$dir/findings" -maxdepth 1 -type f -name "$1-*" | wc -l; }
  crashes=$(( $(count crash) + $(count deadly-signal) ))
  leaks=$(count leak)
  timeouts=$(count timeout)
  ooms=$(count oom)
  past="–"
  if [ -f "$dir/regressions.status" ]; then
    past=$([ "$(cat "$dir/regressions.status")" = 0 ] && echo "ok" || echo "FAILED")
  fi
  result="ok"
  if [ $((crashes + leaks + timeouts + ooms)) -gt 0 ] || [ "$past" = FAILED ]; then
    result="FOUND"
  elif [ "$executed" -lt "$runs" ]; then
    result="below $runs"
  fi
  [ "$result" = ok ] || failed=1
  echo "| $name | $executed | $rate | ${workers[$name]} | $seconds | $crashes | $leaks | $timeouts | $ooms | $peak | $past | $result |" >>"$summary"
  if [ -n "$(ls -A "$dir/findings" 2>/dev/null)" ]; then
    mkdir -p "$out/findings/$name" && cp "$dir"/findings/* "$out/findings/$name/"
  fi
done
(cd "$work" && tar -czf "$out/logs.tar.gz" run/*/*.log 2>/dev/null)
cat "$summary"
rm -rf "$work"
exit "$failed"
