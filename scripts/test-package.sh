#!/usr/bin/env bash
# CI's package check (run as root): builds the .deb, installs it with dpkg -i, and runs the
# installed copy as a user would, from a temporary folder with its own HOME and no display:
#   anatomy-tutor --version from PATH; a lesson of the default course played to the end with a
#   full score (scripts/play-lesson.py types the answers); the default command writing the default
#   lesson's first views. The lesson and the default command run under strace, and any file path
#   of this checkout (source or build tree) that the installed copy opens or even looks up fails
#   the check. Prints how long each part took. AT_KEEP_PACKAGE=1 leaves the package installed.
set -euo pipefail
cd "$(dirname "$0")/.."
source scripts/inner-ear-answers.sh
checkout=$(pwd -P)
[ "$(id -u)" -eq 0 ] || { echo "test-package: needs root (dpkg -i)" >&2; exit 1; }
stamp() { date +%s.%N; }
elapsed() { awk -v a="$1" -v b="$(stamp)" 'BEGIN { printf "%.1f s", b - a }'; }

t=$(stamp)
deb=$(bash scripts/package.sh)
echo "test-package: built $deb ($(du -h "$deb" | cut -f1), $(elapsed "$t"))"
dpkg-deb -f "$deb" Depends Recommends | sed 's/^/  /'

t=$(stamp)
if ! dpkg -i "$deb" >/dev/null; then
  echo "test-package: dpkg -i left dependencies missing; installing them" >&2
  apt-get install -y -f -qq --no-install-recommends >/dev/null
fi
cleanup() { [ "${AT_KEEP_PACKAGE:-0}" = 1 ] || dpkg -r anatomy-tutor >/dev/null 2>&1 || true; rm -rf "$run"; }
run=$(mktemp -d)
trap cleanup EXIT
echo "test-package: installed ($(elapsed "$t"))"

installed=$(command -v anatomy-tutor)
[ "$installed" = /usr/bin/anatomy-tutor ] || { echo "test-package: anatomy-tutor on PATH is $installed, not the package's" >&2; exit 1; }
for f in /usr/share/anatomy-tutor/courses/temporal_bone.json /usr/share/anatomy-tutor/presets/cochlea_wdt.json \
         /usr/share/applications/anatomy-tutor.desktop /usr/share/icons/hicolor/scalable/apps/anatomy-tutor.svg \
         /usr/share/doc/anatomy-tutor/copyright /usr/share/anatomy-tutor/fetch-scans.sh; do
  [ -e "$f" ] || { echo "test-package: the package lacks $f" >&2; exit 1; }
done
desktop-file-validate /usr/share/applications/anatomy-tutor.desktop

# strace needs ptrace; a container that forbids it still runs the checks below, without the trace.
touch "$run/play.trace" "$run/default.trace"
traced="under strace"
play_trace=(strace -f -qq -e trace=%file -o "$run/play.trace")
default_trace=(strace -f -qq -e trace=%file -o "$run/default.trace")
if ! strace -qq -o /dev/null true 2>/dev/null; then
  echo "test-package: SKIPPED the no-checkout-path check: strace cannot trace here (ptrace not permitted)"
  traced="not traced"
  play_trace=()
  default_trace=()
fi

# A user's world with no trace of the checkout: own HOME, data and cache, no display, no override.
mkdir -p "$run/home"
cp scripts/play-lesson.py "$run/"
cd "$run"
env_user=(env -i PATH=/usr/bin:/bin HOME="$run/home" LANG=C.UTF-8)
t=$(stamp)
"${env_user[@]}" anatomy-tutor --version
echo "test-package: --version ($(elapsed "$t"))"

t=$(stamp)
"${env_user[@]}" "${play_trace[@]}" \
  python3 "$run/play-lesson.py" -- anatomy-tutor play inner_ear --user ci --new-user -- "${inner_ear_answers[@]}" \
  > "$run/play.log" || { cat "$run/play.log"; echo "test-package: the installed copy did not play inner_ear to a full score" >&2; exit 1; }
tail -n 1 "$run/play.log"
echo "test-package: played inner_ear from the installed copy ($(elapsed "$t"), $traced)"

t=$(stamp)
"${env_user[@]}" "${default_trace[@]}" anatomy-tutor > "$run/default.log"
views=$(ls "$run"/anatomy-tutor-views/*.png | wc -l)
[ "$views" -gt 0 ] || { cat "$run/default.log"; echo "test-package: the default command wrote no views" >&2; exit 1; }
echo "test-package: the default command wrote $views views with no display ($(elapsed "$t"), $traced)"

leaks=$(grep -h -F "$checkout" "$run/play.trace" "$run/default.trace" || true)
if [ -n "$leaks" ]; then
  echo "$leaks" | head -n 5
  echo "test-package: the installed copy touched the checkout ($checkout)" >&2
  exit 1
fi
[ "$traced" = "not traced" ] || echo "test-package: no path of $checkout was opened or looked up by the installed copy"
