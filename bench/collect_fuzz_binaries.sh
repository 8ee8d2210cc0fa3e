#!/usr/bin/env bash
# Builds the libFuzzer harnesses (clang-14, ASan + UBSan, build-fuzz/ as scripts/fuzz.sh does) and
# gathers into .fuzz-gpu/ (git-ignored) what the long runs need on a machine that has none of our
# Debian libraries and no network (the 16-core host of the device tool, Ubuntu 24.04):
#   .fuzz-gpu/payload.tar.xz        bin/fuzz_* (debug info stripped; symbolize findings here with
#                                   build-fuzz's copies), lib/ (every shared library the harnesses
#                                   load except glibc, libstdc++ and libgcc_s: DCMTK, libarchive,
#                                   libpng, ICU, …, found with ldd), seeds/ (at_fuzz_seeds),
#                                   corpus/ (what earlier runs here kept), dict/<harness>.dict,
#                                   regressions/, lsan.supp, manifest.txt
#   .fuzz-gpu/run_fuzz_campaign.sh  the campaign (bench/run_fuzz_campaign.sh; see its header)
# The folder must stay under the device tool's 64 MiB carry limit; the script checks.
#
#   bash bench/collect_fuzz_binaries.sh     then, with .fuzz-gpu carried:
#   bash .fuzz-gpu/run_fuzz_campaign.sh     (results in $OUT/summary.md)
set -euo pipefail
cd "$(dirname "$0")/.."
dir=build-fuzz
launcher=()
if command -v ccache >/dev/null; then
  launcher=(-DCMAKE_C_COMPILER_LAUNCHER=ccache -DCMAKE_CXX_COMPILER_LAUNCHER=ccache)
fi
if [ ! -f "$dir/build.ninja" ]; then
  cmake -S . -B "$dir" -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo -DCMAKE_C_COMPILER=clang-14 \
    -DCMAKE_CXX_COMPILER=clang++-14 -DAT_FUZZ=ON -DAT_BUILD_TESTS=OFF "${launcher[@]}"
fi
cmake --build "$dir" -j "${AT_JOBS:-$(nproc)}" --target fuzz_all

stage=$(mktemp -d)
trap 'rm -rf "$stage"' EXIT
mkdir -p "$stage/bin" "$stage/lib" "$stage/dict" "$stage/corpus" "$stage/regressions"
harnesses=()
for binary in "$dir"/tests/fuzz/fuzz_*; do
  name=$(basename "$binary" | sed 's/^fuzz_//')
  harnesses+=("$name")
  strip --strip-debug -o "$stage/bin/fuzz_$name" "$binary"
  dict=$(bash scripts/fuzz.sh --print-dict "$name")
  [ -n "$dict" ] && cp "$dict" "$stage/dict/$name.dict"
  [ -d "tests/fuzz/regressions/$name" ] && cp -r "tests/fuzz/regressions/$name" "$stage/regressions/"
  [ -d "tests/fuzz/corpus/$name" ] && mkdir -p "$stage/corpus/$name" && cp tests/fuzz/corpus/"$name"/* "$stage/corpus/$name/"
  if [ -d "$dir/fuzz-corpus/$name" ]; then
    mkdir -p "$stage/corpus/$name"
    find "$dir/fuzz-corpus/$name" -maxdepth 1 -type f -exec cp -t "$stage/corpus/$name/" {} +
  fi
done
"$dir/tests/fuzz/at_fuzz_seeds" "$stage/seeds" >/dev/null

# Shared libraries: everything ldd resolves except the C and C++ runtimes, which the target
# (a newer Ubuntu) has in compatible newer versions. The sanitizer runtimes are linked statically.
for name in "${harnesses[@]}"; do ldd "$stage/bin/fuzz_$name"; done | awk '/=> \// {print $3}' | sort -u |
  while read -r lib; do
    case "$(basename "$lib")" in
      libc.so*|libm.so*|libpthread.so*|libdl.so*|librt.so*|libresolv.so*|ld-linux*|libstdc++.so*|libgcc_s.so*) ;;
      *) cp -L "$lib" "$stage/lib/" ;;
    esac
  done
cp tests/fuzz/lsan.supp "$stage/"
{
  echo "commit: $(git rev-parse HEAD)$(git diff --quiet HEAD -- . 2>/dev/null || echo ' (with uncommitted changes)')"
  echo "collected: $(date -u +%FT%TZ) on $(uname -n)"
  echo "harnesses: ${harnesses[*]}"
  echo "seed files: $(find "$stage/seeds" -type f | wc -l), corpus files: $(find "$stage/corpus" -type f | wc -l), libraries: $(ls "$stage/lib" | wc -l)"
} >"$stage/manifest.txt"

rm -rf .fuzz-gpu
mkdir -p .fuzz-gpu
tar -C "$stage" -cf - . | xz -T0 -6 >.fuzz-gpu/payload.tar.xz
cp bench/run_fuzz_campaign.sh .fuzz-gpu/
cat "$stage/manifest.txt"
size=$(du -sk .fuzz-gpu | cut -f1)
echo "collect_fuzz_binaries: .fuzz-gpu is $((size / 1024)) MiB ($(du -sk "$stage" | cut -f1) KiB unpacked)"
if [ "$size" -gt $((64 * 1024)) ]; then
  echo "collect_fuzz_binaries: .fuzz-gpu is over the device tool's 64 MiB carry limit" >&2
  exit 1
fi
