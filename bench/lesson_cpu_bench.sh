#!/usr/bin/env bash
# Inside a lesson on the CPU (Mesa llvmpipe under Xvfb, fields on the CPU): how long each step's
# view takes to be final after Next (the student having read the step before for 8 s), with the
# next steps' fields prefetched while the student reads and without (--no-prefetch), and the hover
# highlight latency of a sweep over every structure in the middle of the lesson.
#   bash bench/lesson_cpu_bench.sh [BUILD_DIR] [RUNS]
# Prints one line per run: mode, load average before, each step's settle time (ms: its field on
# screen and the full-quality image of it rendered, what the student finally sees), when its field
# alone was on screen (ms, 0 = the step before's field, already there), highlight p50/p99/max (ms).
# Uses a fresh database in a temporary folder each run.
set -euo pipefail
build=${1:-build}
runs=${2:-1}
here=$(cd "$(dirname "$0")/.." && pwd)
app="$here/$build/app/anatomy-tutor"
script="$here/bench/lesson_steps_cpu.json"
for run in $(seq 1 "$runs"); do
  for mode in prefetch no-prefetch; do
    work=$(mktemp -d)
    extra=""
    [ "$mode" = no-prefetch ] && extra="--no-prefetch"
    load=$(cut -d' ' -f1-3 /proc/loadavg)
    (cd "$work" && xvfb-run -a -s "-screen 0 1280x800x24" "$app" desktop --size 1280x720 --render-scale 0.4 \
        --max-fps 60 --db "$work/tutor.db" --user bench $extra --ui-script "$script" >events.jsonl 2>stderr.txt) || {
      echo "run failed: see $work/stderr.txt" >&2; exit 1; }
    python3 - "$work" "$mode" "$load" <<'PY'
import json, sys, os
work, mode, load = sys.argv[1:4]
settled = []
field_on_screen = []
prefetched = 0
for line in open(os.path.join(work, "events.jsonl")):
    if not line.startswith("{"): continue
    e = json.loads(line)
    if e.get("event") == "field_settled":
        settled.append(round(e["ms"]))
        field_on_screen.append(round(e["field_ms"]))
    if e.get("event") == "field_prefetched": prefetched += 1
report = json.load(open(os.path.join(work, "lesson_hover_report.json")))
after_next = settled[1:]  # the first is the lesson's first view (nothing to prefetch before it)
fields_after_next = field_on_screen[1:]
print(f"{mode:12s} load {load}  steps after Next (ms): {after_next}  max {max(after_next)}  "
      f"field on screen (ms): {fields_after_next}  max {max(fields_after_next)}  "
      f"fields prefetched {prefetched}  highlight p50/p99/max {report['highlight_ms_p50']:.0f}/"
      f"{report['highlight_ms_p99']:.0f}/{report['highlight_ms_max']:.0f} ms ({report['highlights']} highlights)")
PY
    rm -rf "$work"
  done
done
