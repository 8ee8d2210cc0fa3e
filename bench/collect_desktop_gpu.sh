#!/usr/bin/env bash
# Packs the desktop app (the Debian build in build/, CUDA sm_90 included) with the shared libraries
# it links, except glibc and libstdc++ (the GPU machine's newer ones serve), into .desk/ (git-ignored)
# for measuring the desktop on the lent GPU machine, which has none of our Debian libraries:
#
#   bash bench/collect_desktop_gpu.sh       then, on the GPU machine (device tool, carry .desk and .gl):
#   bash .desk/run_desktop_on_gpu.sh        (writes the hover-sweep reports to $OUT)
#
# The libraries are xz-compressed (~19 MB; ~66 MB unpacked, mostly ICU's data) to fit the carry limit.
set -euo pipefail
cd "$(dirname "$0")/.."
ninja -C build -j2 anatomy-tutor
staging=$(mktemp -d)
trap 'rm -rf "$staging"' EXIT
mkdir -p "$staging/lib"
cp build/app/anatomy-tutor "$staging/"
ldd build/app/anatomy-tutor | awk '/=> \// {print $3}' | sort -u |
  grep -v -E '/(libc|libm|libstdc\+\+|libgcc_s|libpthread|libdl|librt)\.so' |
  while read -r lib; do cp -L "$lib" "$staging/lib/"; done
rm -rf .desk && mkdir -p .desk
tar -C "$staging" -cJf .desk/desk.tar.xz .
cp bench/run_desktop_on_gpu.sh .desk/
du -sh .desk
