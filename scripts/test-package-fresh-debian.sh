#!/usr/bin/env bash
# Installs the .deb on a fresh, minimal Debian 12 (a debootstrap chroot: nothing but the base
# system) with apt, so that only the dependencies the package declares get installed, then plays
# the first lesson to a full score and writes the default views there. Needs root, debootstrap and
# network access to deb.debian.org; takes a few minutes (bench/RESULTS.md). Not part of CI, which
# installs the package on its own machine (scripts/test-package.sh).
#   AT_CHROOT=DIR  reuse (or keep) the chroot in DIR instead of a temporary one
set -euo pipefail
cd "$(dirname "$0")/.."
source scripts/inner-ear-answers.sh
[ "$(id -u)" -eq 0 ] || { echo "test-package-fresh-debian: needs root" >&2; exit 1; }
command -v debootstrap >/dev/null || { echo "test-package-fresh-debian: needs debootstrap (apt-get install debootstrap)" >&2; exit 1; }
stamp() { date +%s.%N; }
elapsed() { awk -v a="$1" -v b="$(stamp)" 'BEGIN { printf "%.1f s", b - a }'; }

deb=$(bash scripts/package.sh)
root=${AT_CHROOT:-$(mktemp -d)}
cleanup() {
  umount "$root/proc" 2>/dev/null || true
  # Never remove through a /proc still mounted; a kept chroot (AT_CHROOT) stays.
  if [ -z "${AT_CHROOT:-}" ] && ! mountpoint -q "$root/proc"; then rm -rf "$root" "$root.debootstrap.log"; fi
}
trap cleanup EXIT

t=$(stamp)
if [ ! -x "$root/usr/bin/apt-get" ]; then
  debootstrap --variant=minbase bookworm "$root" http://deb.debian.org/debian >"$root.debootstrap.log" 2>&1 ||
    { tail -n 5 "$root.debootstrap.log"; exit 1; }
fi
echo "test-package-fresh-debian: minimal Debian 12 in $root ($(elapsed "$t"))"
mount --bind /proc "$root/proc"   # the program finds its data from /proc/self/exe

t=$(stamp)
cp "$deb" "$root/tmp/"
chroot "$root" bash -c "apt-get update -qq && DEBIAN_FRONTEND=noninteractive apt-get install -y -qq --no-install-recommends /tmp/$(basename "$deb")" \
  >"$root/tmp/apt.log" 2>&1 || { tail -n 20 "$root/tmp/apt.log"; exit 1; }
echo "test-package-fresh-debian: apt installed the package and $(grep -c '^Setting up' "$root/tmp/apt.log") packages in all ($(elapsed "$t"))"

in_root=(chroot "$root" env -i PATH=/usr/bin:/bin HOME=/tmp/user LANG=C.UTF-8)
mkdir -p "$root/tmp/user"
"${in_root[@]}" anatomy-tutor --version
t=$(stamp)
# The locate answers ("pick:…", a click on the structure) go through an answers file: written into
# the chroot's /tmp, named as the chroot sees it.
python3 scripts/play-lesson.py --answers-dir "$root/tmp:/tmp" -- "${in_root[@]}" anatomy-tutor play inner_ear \
  --user fresh --new-user -- "${inner_ear_answers[@]}" | tail -n 1
echo "test-package-fresh-debian: played inner_ear ($(elapsed "$t"))"
t=$(stamp)
chroot "$root" bash -c 'cd /tmp/user && env -i PATH=/usr/bin:/bin HOME=/tmp/user anatomy-tutor >/dev/null && ls anatomy-tutor-views/*.png | wc -l' |
  { read -r n; [ "$n" -gt 0 ] || exit 1; echo "test-package-fresh-debian: the default command wrote $n views ($(elapsed "$t"))"; }
