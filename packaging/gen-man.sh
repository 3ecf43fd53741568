#!/usr/bin/env bash
# Generates the man pages from the commands' own --help: ballbar(1) and ballbar-COMMAND(1) for every
# subcommand that `ballbar completion commands` lists. help2man (Debian package help2man) does the
# conversion; pages are written gzip-compressed (as Debian installs them) into OUTDIR.
# usage: gen-man.sh BALLBAR VERSION OUTDIR
set -euo pipefail
exe=$1 version=$2 out=$3
rm -rf "$out.tmp" && mkdir -p "$out.tmp/bin"
page() {  # page NAME DESCRIPTION WRAPPER
  help2man --no-info --no-discard-stderr --version-string="$version" --name="$2" \
    --section=1 --source="ballbar $version" --manual="ballbar manual" "$3" > "$out.tmp/$1.1"
  gzip -9n -f "$out.tmp/$1.1"
}
page ballbar "guided ball-bar measurement and error analysis of five-axis machine tools" "$exe"
"$exe" completion commands | while IFS=$'\t' read -r name description; do
  wrapper="$out.tmp/bin/ballbar-$name"
  printf '#!/bin/sh\nexec "%s" %s "$@"\n' "$exe" "$name" > "$wrapper"
  chmod +x "$wrapper"
  page "ballbar-$name" "$description" "$wrapper"
done
rm -rf "$out.tmp/bin" "$out"
mv "$out.tmp" "$out"
