#!/usr/bin/env bash
# One sweep-kernel build against another on the lent GPU (device tool), and where the new one's
# warps stall: test_cuda of NEW; wdt_cuda_bench of both alternately at 128³–512³, two rounds (the
# first NEW round checks GPU = CPU at 256³); ncu of four 256³ and four 512³ sweep launches of each
# (time, instructions, issue activity, stalls per issued instruction); ncu's per-instruction stall
# samples (source page) of one 256³ launch of each, summed between block barriers, so that stalls
# before the first plane step (waiting for the previous group) and inside the plane steps show
# apart; the SASS of NEW's sweep kernels. Results in $OUT/s.tgz; a summary is printed last.
#   bash bench/wdt_stalls_on_gpu.sh BASE_DIR NEW_DIR   (each with wdt_cuda_bench; NEW also test_cuda)
set -uo pipefail
B=${1:?baseline build folder}; N=${2:?new build folder}
R=$OUT/s; mkdir -p "$R"
nvidia-smi --query-gpu=name,driver_version,clocks.max.sm,memory.total,uuid --format=csv > "$R/machine.txt" 2>&1
cat "$R/machine.txt"
cuobjdump -sass "$N/wdt_cuda_bench" 2>/dev/null | awk '/Function :/{f=/sweepGroup/} f' > "$R/sass_new.txt"
timeout 150 "$N/test_cuda" > "$R/test_cuda_new.log" 2>&1
echo "test_cuda new exit $? $(grep -E '^\[doctest\] (test cases|assertions)' "$R/test_cuda_new.log" | tr '\n' ' ')"
grep -B3 -A12 "ERROR" "$R/test_cuda_new.log" | head -30
for round in 1 2; do
  for c in base new; do
    d=$N; [ $c = base ] && d=$B; chk=0; [ $round = 1 ] && [ $c = new ] && chk=256
    timeout 120 "$d/wdt_cuda_bench" --sizes 128,256,512 --reps 10 --check-max $chk 2>> "$R/bench.err" \
      | sed "s/^{/{\"build\":\"$c\",\"round\":$round,/" >> "$R/bench.jsonl"
  done
done
M=gpu__time_duration.sum,smsp__inst_executed.sum,smsp__issue_active.avg.pct_of_peak_sustained_active
for w in long_scoreboard barrier wait not_selected short_scoreboard; do
  M=$M,smsp__average_warps_issue_stalled_${w}_per_issue_active.ratio
done
for c in base new; do
  d=$N; [ $c = base ] && d=$B
  for n in 256 512; do
    timeout 60 ncu --clock-control none --metrics $M -k regex:sweepGroup --launch-skip 40 --launch-count 4 \
      "$d/wdt_cuda_bench" --sizes $n --reps 1 --check-max 0 > "$R/ncu${n}_$c.txt" 2>&1
  done
  timeout 60 ncu --clock-control none --section SourceCounters --section WarpStateStats -k regex:sweepGroup \
    --launch-skip 40 --launch-count 1 -o "$R/src_$c" "$d/wdt_cuda_bench" --sizes 256 --reps 1 --check-max 0 > /dev/null 2>&1
  timeout 60 ncu -i "$R/src_$c.ncu-rep" --page source --csv --print-source sass > "$R/src_$c.csv" 2>&1
  rm -f "$R/src_$c.ncu-rep"
done
tar czf "$OUT/s.tgz" -C "$OUT" s
python3 - "$R" <<'PY'
import collections, csv, glob, json, os, sys
r = sys.argv[1]
rows = [json.loads(l) for l in open(r + "/bench.jsonl") if l.startswith("{")]
t = collections.defaultdict(list)
for x in rows:
    t[(x["size"], x["mode"], x["build"])].append(x["ms_per_pass_median"] if x["mode"] != "converge" else x["ms_device_median"])
for k in sorted(t): print(k, t[k])
for x in rows:
    if "max_rel_diff_gpu_cpu" in x:
        print(x["build"], x["size"], x["mode"], "gpu-cpu", x["max_rel_diff_gpu_cpu"], "max rel err", x["gpu_max_rel_err"])
for f in sorted(glob.glob(r + "/ncu*_*.txt")):
    print(os.path.basename(f), " | ".join(l.split()[0].split("__")[1][:40] + " " + l.split()[-1] for l in open(f) if "__" in l and "==" not in l))
# Stall samples summed between block barriers (segment 0: before the first plane step).
for f in sorted(glob.glob(r + "/src_*.csv")):
    lines = open(f).read().splitlines()
    head = [i for i, l in enumerate(lines) if l.startswith('"Address"')]
    if not head: print(os.path.basename(f), "no source page"); continue
    seg, sums = 0, collections.defaultdict(lambda: [0, 0])
    for x in csv.DictReader(lines[head[0]:]):
        try: sums[seg][0] += int(x["stall_long_sb"]); sums[seg][1] += int(x["Warp Stall Sampling (All Samples)"])
        except (KeyError, ValueError): continue
        if "BAR.SYNC" in x["Source"]: seg += 1
    print(os.path.basename(f), "long-scoreboard / all samples per segment:", [tuple(v) for _, v in sorted(sums.items())])
PY
