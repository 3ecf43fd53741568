#!/usr/bin/env bash
# Fails when README.md or a page of docs/ refers to material outside the repository — the shared
# development notes (`shared/…`, `../shared`), an absolute path of a development machine — or when a
# relative Markdown link leaves the repository or points at a file that does not exist.
set -u
root=$(cd "${1:?usage: check_docs.sh REPO_ROOT}" && pwd)
cd "$root" || exit 2
status=0
pages=$(find docs -name '*.md' | sort; echo README.md)
if grep -nE '(^|[^a-z_])shared/(research|formats|seeds|hooks)|\.\./shared|/work/|/home/[a-z]' $pages; then
  echo "the lines above refer to material outside the repository" >&2
  status=1
fi
for page in $pages; do
  dir=$(dirname "$page")
  # Markdown links: ](target) with an optional #anchor; skip URLs and pure anchors.
  grep -oE '\]\([^)#[:space:]]+' "$page" | cut -c3- | while read -r target; do
    case "$target" in *:*) continue ;; esac
    abs=$(realpath -m "$dir/$target")
    case "$abs" in
      "$root"/*) [ -e "$abs" ] || { echo "$page: link to a missing file: $target" >&2; exit 1; } ;;
      *) echo "$page: link leaves the repository: $target" >&2; exit 1 ;;
    esac
  done || status=1
done
[ $status -eq 0 ] && echo "docs self-contained: $(echo $pages | wc -w) pages"
exit $status
