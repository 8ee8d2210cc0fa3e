#!/usr/bin/env bash
# Fetches the real scans that built-in dataset names open, into the cache folder anatomy-tutor
# searches: ${XDG_CACHE_HOME:-~/.cache}/anatomy-tutor/scans/<debian package>/. The repository never
# carries them. Today one:
#   skull  Cranium.inv3 (head CT, InVesalius project) from Debian's invesalius-examples (GPL-2)
# It uses `apt-get download` and `dpkg-deb -x` rather than an install: no root is needed, nothing
# is installed, and minimal Debian images that exclude /usr/share/doc still get the file.
# Exits 0 when the scan is present (fetched now or before); otherwise 1 with one line saying why.
set -euo pipefail

package=invesalius-examples
member=usr/share/doc/invesalius-examples/examples/Cranium.inv3
# The file the landmarks note and the tests describe (package version 3.1.99998-4, Debian 12).
expected_sha256=3b34f11f7c4f557f4c65cd6543c412a2f6ceb0cfecfd9c41184420e02d9b7e2a

cache="${XDG_CACHE_HOME:-$HOME/.cache}/anatomy-tutor/scans"
dest="$cache/$package"
if [ -f "$dest/Cranium.inv3" ]; then
  echo "fetch-scans: skull: $dest/Cranium.inv3 already present"
  exit 0
fi

work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
download() { (cd "$work" && apt-get download -q "$package" >"$work/apt.log" 2>&1); }
if ! download; then
  # A machine that never ran `apt-get update` has no package lists; root can fetch them.
  if [ "$(id -u)" -eq 0 ] && apt-get update -qq >/dev/null 2>&1 && download; then
    :
  else
    echo "fetch-scans: skull: 'apt-get download $package' failed ($(grep -m1 -E '^(E|W):' "$work/apt.log" || echo 'see apt-get')); run 'sudo apt-get update' and try again" >&2
    exit 1
  fi
fi
deb=$(ls "$work"/"${package}"_*.deb)
dpkg-deb -x "$deb" "$work/x"
if [ ! -f "$work/x/$member" ]; then
  echo "fetch-scans: skull: $(basename "$deb") has no $member" >&2
  exit 1
fi
mkdir -p "$dest"
cp "$work/x/usr/share/doc/$package/copyright" "$dest/copyright"
dpkg-deb -f "$deb" Package Version >"$dest/PACKAGE"
cp "$work/x/$member" "$dest/Cranium.inv3.part"
mv "$dest/Cranium.inv3.part" "$dest/Cranium.inv3"
sum=$(sha256sum "$dest/Cranium.inv3" | cut -d' ' -f1)
if [ "$sum" != "$expected_sha256" ]; then
  echo "fetch-scans: skull: note: $dest/Cranium.inv3 differs from the file the project was written against (sha256 $sum, expected $expected_sha256); landmark checks may fail" >&2
fi
echo "fetch-scans: skull: $dest/Cranium.inv3 ($(dpkg-deb -f "$deb" Version), licence in $dest/copyright)"
