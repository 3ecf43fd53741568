#!/usr/bin/env bash
# Installs the Debian package into a clean Debian 12 root, runs `ballbar demo` there (the README's
# main job), checks what the package put in place, then removes the package again and checks that it
# is gone. The root is made by mmdebstrap from Debian's own packages (the mirrors of this machine's
# apt sources) in a temporary directory this script creates, and removed at the end.
# usage: scripts/test-package.sh [build/ballbar_VERSION_ARCH.deb]     (needs root, mmdebstrap)
set -euo pipefail
cd "$(dirname "$0")/.."
deb=${1:-$(ls -t build/ballbar_*.deb 2>/dev/null | head -n 1)}
[ -n "$deb" ] && [ -f "$deb" ] || { echo "test-package: no .deb (run: cd build && cpack -G DEB)" >&2; exit 2; }
deb=$(realpath "$deb")
command -v mmdebstrap >/dev/null || { echo "test-package: mmdebstrap is not installed (apt-get install mmdebstrap)" >&2; exit 2; }

root=$(mktemp -d "${TMPDIR:-/tmp}/ballbar-debian12.XXXXXX")
trap 'rm -rf --one-file-system "$root"' EXIT

# The checks run inside the root, as a customize hook (mmdebstrap mounts /dev, /proc and /sys there).
check=$(cat <<'SH'
set -eu
r=$1
chroot "$r" sh -c 'command -v ballbar' >/dev/null
for f in /usr/bin/ballbar /usr/lib/udev/rules.d/70-ballbar.rules /usr/share/man/man1/ballbar.1.gz \
         /usr/share/man/man1/ballbar-measure.1.gz /usr/share/bash-completion/completions/ballbar \
         /usr/share/zsh/vendor-completions/_ballbar /usr/share/doc/ballbar/copyright /usr/share/doc/ballbar/README.md; do
  [ -e "$r$f" ] || { echo "test-package: $f is missing" >&2; exit 1; }
done
chroot "$r" env HOME=/root XDG_DATA_HOME=/tmp/ballbar-data ballbar demo
chroot "$r" env HOME=/root XDG_DATA_HOME=/tmp/ballbar-data ballbar sessions
chroot "$r" apt-get remove -y -q ballbar
[ ! -e "$r/usr/bin/ballbar" ] || { echo "test-package: /usr/bin/ballbar left after remove" >&2; exit 1; }
[ ! -e "$r/usr/lib/udev/rules.d/70-ballbar.rules" ] || { echo "test-package: udev rules left after remove" >&2; exit 1; }
echo "test-package: installed, ran the demo, removed: ok"
SH
)
mmdebstrap --mode=root --variant=apt --quiet \
  --setup-hook='mkdir -p "$1/tmp/pkg"' \
  --customize-hook="copy-in $deb /tmp/pkg" \
  --customize-hook='chroot "$1" sh -c "apt-get install -y -q /tmp/pkg/*.deb"' \
  --customize-hook="$check" \
  bookworm "$root"
