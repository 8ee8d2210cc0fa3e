#!/usr/bin/env bash
# GPU frame times before and after a rendering change, on one lent GPU machine in one call: the
# render benchmark of the change (render_bench, with the data-aware distance unit as every front
# end sets it, `--unit field`, and with the size-based unit, `--unit size`) and of a baseline build
# (render_bench_base, with the baseline's presets) run alternately, two rounds, for the cases
# recorded in bench/RESULTS.md: 1920×1080 at the default step and at 0.2 mm (2 voxels), 3840×2160,
# and the fragment ray caster once; between the rounds the GPU growth's per-edit cost
# (growth_bench_before).
# Built and packed by bench/pack_render_frames.sh; on the device tool (carry .gpu and .gl):
#   mkdir -p /tmp/b && for f in .gpu/r31/*.gz; do gunzip -c $f > /tmp/b/$(basename $f .gz); done;
#   chmod +x /tmp/b/*; bash .gpu/r31/render_frames_on_gpu.sh /tmp/b 420
# Results go to $OUT/r31.tgz after every step (render.jsonl, growth.jsonl, logs, machine.txt).
set -uo pipefail
bin=${1:?binary folder}
budget=${2:-420}
pack=$(cd "$(dirname "$0")" && pwd)
for f in .gl/*.deb; do dpkg -x "$f" /; done
ldconfig
export __EGL_VENDOR_LIBRARY_FILENAMES=/usr/local/nvidia/share/glvnd/egl_vendor.d/10_nvidia.json
export LD_LIBRARY_PATH=$pack/lib:${LD_LIBRARY_PATH:-}
res=/tmp/r31 && rm -rf $res && mkdir -p $res
start=$(date +%s)
left() { echo $((budget - ($(date +%s) - start))); }
save() { tar -czf "$OUT/r31.tgz" -C /tmp r31; }
{ nvidia-smi -L; nvidia-smi --query-gpu=name,driver_version,clocks.max.sm,clocks.sm,temperature.gpu --format=csv;
  lscpu | grep -E "Model name|^CPU\(s\)"; cat "$pack/commit.txt"; } > $res/machine.txt 2>&1
# run NAME BINARY PRESETS ARGS…: one render_bench run, its lines tagged with NAME.
run() {
  local name=$1 exe=$2 presets=$3; shift 3
  local t=$(left)
  if [ "$t" -lt 20 ]; then echo "skipped $name (budget)" >> $res/render.err; return; fi
  timeout $((t - 5)) "$bin/$exe" --size 1920x1080 --volume 512 --hover-volume 256 --presets "$presets" "$@" \
    2>> $res/render.err | sed "s/^{/{\"run\":\"$name\",/" >> $res/render.jsonl
  echo "$name rc=${PIPESTATUS[0]} at $(($(date +%s) - start)) s" >> $res/render.err
  save
}
# The GPU growth's per-edit cost (8 labels on the phantom) at the packed code, between the rounds.
growth() {
  if [ -x "$bin/growth_bench_before" ] && [ "$(left)" -gt 90 ]; then
    timeout 80 "$bin/growth_bench_before" --sizes 256,512 --backends cuda --reps 3 --check-max 256 \
      > $res/growth.jsonl 2> $res/growth.err
    echo "growth rc=$?" >> $res/growth.err
  fi
  save
}
for round in 1 2; do
  [ $round = 2 ] && growth
  for v in base field size; do
    if [ $v = base ]; then exe=render_bench_base; presets=$pack/presets_base; extra=();
    else exe=render_bench; presets=$pack/presets; extra=(--unit $v); fi
    run "$v-default-r$round" $exe $presets --frames 30 --warmup 5 --cycles 16 "${extra[@]}"
    run "$v-step0.2-r$round" $exe $presets --frames 30 --warmup 5 --cycles 6 --step-voxels 2 "${extra[@]}"
    run "$v-4k-r$round" $exe $presets --frames 20 --warmup 3 --cycles 3 --size 3840x2160 "${extra[@]}"
  done
done
run base-fragment render_bench_base $pack/presets_base --frames 5 --warmup 1 --cycles 3 --ray-caster fragment
run field-fragment render_bench $pack/presets --frames 5 --warmup 1 --cycles 3 --ray-caster fragment --unit field
nvidia-smi --query-gpu=clocks.sm,temperature.gpu --format=csv >> $res/machine.txt 2>&1
grep -h '"bench":"render_frame"\|"bench":"field_scale"\|hover_summary' $res/render.jsonl |
  python3 -c '
import json, sys
for line in sys.stdin:
    r = json.loads(line)
    if r["bench"] == "render_frame":
        print(r["run"], "frame", r["gpu_ms_median"], "p90", r["gpu_ms_p90"], "unit", r.get("distance_unit"))
    elif r["bench"] == "field_scale":
        print(r["run"], "field_scale first", r["first_ms"], "median", r["ms_median"], "rays", r["view_rays"], "capped", r["capped_by_rays"])
    else:
        print(r["run"], "hover median", r["total_ms_median"], "p99", r["total_ms_p99"], "frame", r["frame_gpu_ms_median"],
              "scale", r.get("field_scale_ms_median"), "with scale", r.get("total_with_scale_ms_median"))
'
cat $res/growth.jsonl 2>/dev/null | cut -c1-260
tail -n 4 $res/render.err
