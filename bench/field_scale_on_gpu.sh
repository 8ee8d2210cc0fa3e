#!/usr/bin/env bash
# The distance unit measure (render::applyFieldScale) and the hover cycle before and after a change,
# on the lent GPU machine: render_bench of the change and of a baseline alternately, wdt, fuzzy and
# lighting, two rounds. Packing (here): build render_bench in build-gpu of this checkout and of a
# baseline tree (cmake -DAT_BUILD_APP=OFF -DCMAKE_CUDA_ARCHITECTURES=90), strip and gzip them into
# .gpu/fs/render_bench.gz and render_bench_base.gz, libepoxy and libpng into .gpu/fs/lib, data/presets
# into .gpu/fs/presets, this script into .gpu/fs/run.sh; device: `bash .gpu/fs/run.sh` carrying .gpu
# and .gl. Results: $OUT/fs.tgz (render.jsonl, machine.txt, err.txt).
set -uo pipefail
for f in .gl/*.deb; do dpkg -x "$f" /; done; ldconfig
export __EGL_VENDOR_LIBRARY_FILENAMES=/usr/local/nvidia/share/glvnd/egl_vendor.d/10_nvidia.json
pack=$PWD/.gpu/fs
export LD_LIBRARY_PATH=$pack/lib:${LD_LIBRARY_PATH:-}
b=/tmp/b; mkdir -p $b; for f in $pack/*.gz; do gunzip -c $f > $b/$(basename $f .gz); done; chmod +x $b/*
res=/tmp/fs; mkdir -p $res
{ nvidia-smi -L; lscpu | grep -E "Model name|^CPU\(s\)"; nproc; } > $res/machine.txt 2>&1
start=$(date +%s)
for round in 1 2; do
  for mode in wdt fuzzy lighting; do
    for v in base new; do
      exe=$b/render_bench; [ $v = base ] && exe=$b/render_bench_base
      [ $(( $(date +%s) - start )) -gt 480 ] && break 3
      timeout 120 $exe --size 1920x1080 --volume 512 --hover-volume 256 --presets $pack/presets \
        --frames 10 --warmup 3 --cycles 8 --mode $mode 2>> $res/err.txt | sed "s/^{/{\"run\":\"$v-$mode-r$round\",/" >> $res/render.jsonl
      echo "$v $mode r$round rc=${PIPESTATUS[0]} at $(( $(date +%s) - start )) s" >> $res/err.txt
      tar -czf $OUT/fs.tgz -C /tmp fs
    done
  done
done
grep -h 'field_scale\|hover_summary' $res/render.jsonl | python3 -c '
import json,sys
for l in sys.stdin:
  r=json.loads(l)
  if r["bench"]=="field_scale": print(r["run"],"scale first",r["first_ms"],"median",r["ms_median"],"unit",r["distance_unit"],"rays",r["view_rays"])
  else: print(r["run"],"hover",r["total_ms_median"],"scale",r.get("field_scale_ms_median"),"with",r.get("total_with_scale_ms_median"))
'
tail -3 $res/err.txt
