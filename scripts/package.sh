#!/usr/bin/env bash
# Builds the Debian package with CPack into build/: anatomy-tutor_<version>_<arch>.deb (binary,
# data, .desktop entry, icons, licence files; dependencies from dpkg-shlibdeps). Prints its path.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/build.sh >/dev/null
(cd build && cpack -G DEB >cpack.log 2>&1) || { tail -n 20 build/cpack.log >&2; exit 1; }
ls -t build/anatomy-tutor_*.deb | head -n1
