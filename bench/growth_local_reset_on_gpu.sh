#!/usr/bin/env bash
# The GPU growth's local reset on one lent GPU machine in one call: the whole test_cuda, the local
# reset case and the incremental case over fresh seeds, memcheck on the local reset case, and the
# per-edit cost before (growth_bench_before: the label-wide reset) and after (growth_bench_after),
# run alternately, two rounds. Built and packed by bench/pack_growth_local_reset.sh; on the
# device tool (carry .gpu):
#   mkdir -p /tmp/b && for f in .gpu/lr/*.gz; do gunzip -c $f > /tmp/b/$(basename $f .gz); done;
#   chmod +x /tmp/b/*; bash .gpu/lr/growth_local_reset_on_gpu.sh /tmp/b 520
# Results go to $OUT/lr.tgz after every step.
set -uo pipefail
bin=${1:?binary folder}
budget=${2:-520}
pack=$(cd "$(dirname "$0")" && pwd)
res=/tmp/lr && rm -rf $res && mkdir -p $res
start=$(date +%s)
left() { echo $((budget - ($(date +%s) - start))); }
save() { tar -czf "$OUT/lr.tgz" -C /tmp lr; }
{ nvidia-smi -L; nvidia-smi --query-gpu=name,driver_version,clocks.max.sm --format=csv; cat "$pack/commit.txt"; } > $res/machine.txt 2>&1
timeout 150 "$bin/test_cuda" > $res/test_cuda.log 2>&1
echo "test_cuda rc=$? at $(($(date +%s) - start)) s" >> $res/summary.txt
save
# seeds CASE N: the case over N fresh seeds; failures keep their log.
seeds() {
  local name=$1 n=$2 fail=0 i
  for i in $(seq "$n"); do
    [ "$(left)" -lt 60 ] && { echo "$name: stopped after $((i - 1)) seeds (budget)" >> $res/summary.txt; break; }
    AT_TEST_SEED=$RANDOM$RANDOM timeout 60 "$bin/test_cuda" -tc="$name" > $res/seed.log 2>&1 ||
      { fail=$((fail + 1)); cat $res/seed.log >> $res/seed_failures.log; }
  done
  echo "$name: $n fresh seeds, $fail failed, at $(($(date +%s) - start)) s" >> $res/summary.txt
  save
}
seeds 'GPU: removing or relabelling seeds*' 30
seeds 'Incremental GPU updates*' 10
for round in 1 2; do
  for v in before after; do
    [ "$(left)" -lt 70 ] && break
    timeout 65 "$bin/growth_bench_$v" --sizes 256,512 --backends cuda --reps 3 --check-max 256 2>> $res/growth.err |
      sed "s/^{/{\"run\": \"$v-r$round\", /" >> $res/growth.jsonl
    echo "growth $v-r$round rc=${PIPESTATUS[0]} at $(($(date +%s) - start)) s" >> $res/summary.txt
    save
  done
done
if [ "$(left)" -gt 100 ]; then
  timeout 90 compute-sanitizer --tool memcheck "$bin/test_cuda" -tc='GPU: removing or relabelling seeds*' \
    > $res/memcheck.log 2>&1
  echo "memcheck rc=$? at $(($(date +%s) - start)) s" >> $res/summary.txt
fi
save
# 1024³ once each, as time allows.
for v in after before; do
  [ "$(left)" -lt 75 ] && break
  timeout 70 "$bin/growth_bench_$v" --sizes 1024 --backends cuda --reps 1 --check-max 0 2>> $res/growth.err |
    sed "s/^{/{\"run\": \"$v-1024\", /" >> $res/growth.jsonl
  echo "growth $v-1024 rc=${PIPESTATUS[0]} at $(($(date +%s) - start)) s" >> $res/summary.txt
  save
done
cat $res/summary.txt
tail -n 4 $res/test_cuda.log
tail -n 3 $res/memcheck.log 2>/dev/null
python3 -c '
import json
for l in open("/tmp/lr/growth.jsonl"):
    r = json.loads(l)
    if r["step"] != "add": print(r["run"], r["size"], r["step"], "wall", r["ms_wall"], "compute", r["ms_compute"], "reset", r["voxels_reset"], "visits", r["brick_visits"], "exact", r["exact_equal"])
'
