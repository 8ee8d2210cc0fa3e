#!/usr/bin/env bash
# Runs on the GPU machine from the repository root with .desk/ and .gl/ carried (see
# collect_desktop_gpu.sh): the desktop app on NVIDIA's EGL through SDL's offscreen driver
# (AT_DESKTOP_OFFSCREEN=1), CUDA fields, the hover sweep of bench/desktop_hover_sweep.json twice at
# a 60 Hz frame cap (scripted runs swap without vsync). Reports and logs go to $OUT/run1, run2.
set -uo pipefail
for f in .gl/*.deb; do dpkg -x "$f" /; done
ldconfig
export __EGL_VENDOR_LIBRARY_FILENAMES=/usr/local/nvidia/share/glvnd/egl_vendor.d/10_nvidia.json
mkdir -p /tmp/desk && tar -C /tmp/desk -xJf .desk/desk.tar.xz
# Presets, courses and studies come from this checkout's data/ (the binary is not in an install prefix).
export AT_DATA_DIR=$PWD/data
export LD_LIBRARY_PATH=/tmp/desk/lib SDL_VIDEODRIVER=offscreen AT_DESKTOP_OFFSCREEN=1 XDG_DATA_HOME=/tmp/xdg
script=$PWD/bench/desktop_hover_sweep.json
for r in ${RUNS:-1 2}; do
  mkdir -p "$OUT/run$r" && cd "$OUT/run$r"
  timeout 200 /tmp/desk/anatomy-tutor desktop --size 1280x720 --max-fps 60 --ui-script "$script" > desk.log 2>&1
  echo "run $r: exit $?"
  grep '"event":"report"' desk.log
  cd - > /dev/null
done
