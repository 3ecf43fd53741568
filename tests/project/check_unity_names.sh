#!/usr/bin/env bash
# The libraries, the CLI and the test executables are compiled in unity batches (CMakeLists.txt, BALLBAR_UNITY_BUILD):
# several .cpp files of one library, of app/, or of one folder of tests/, in one translation unit, so the helpers each file keeps in its anonymous namespace meet. Two of the same name do not always fail to compile: an overload of another file can
# be chosen silently (a CSV helper `opt` once turned `sessions show`'s null temperatures into ""). This
# fails when two files of one target define a free function or a namespace-scope constant of the same
# name (a test folder counts as one target, and so does each library's src/). usage: check_unity_names.sh SOURCE_DIR
set -u
root="${1:?usage: check_unity_names.sh SOURCE_DIR}"
status=0
for dir in app $(cd "$root" && ls -d */src tests/*/ | sed 's|/$||'); do
  files=$(find "$root/$dir" -name '*.cpp' | sort)
  [ -n "$files" ] || continue
  # Definitions at column 0: "type name(" (not "Class::name(", not a control statement) and
  # "constexpr/const type name =".
  dups=$(for f in $files; do
      grep -oE '^[A-Za-z_][A-Za-z0-9_:<>,*& ]*[ *&]([A-Za-z_][A-Za-z0-9_]*)\(|^(static )?(inline )?(constexpr|const) [A-Za-z0-9_:<>*& ]+ (k?[A-Za-z_][A-Za-z0-9_]*)( =|\[)' "$f" |
        grep -vE '^(return|else|case|namespace|using|typedef|if|for|while|switch|INSERT|CREATE|SELECT|UPDATE|DELETE) ' |
        sed -E 's/\($//; s/( =|\[)$//; s/.*[ *&]//' | grep -v '::' | sort -u | sed "s|\$| ${f#$root/}|"
    done | sort | awk '{n[$1]++; f[$1]=f[$1] " " $2} END {for (k in n) if (n[k] > 1) print k ":" f[k]}' |
    while IFS= read -r line; do
      # A library's public overloads (to_string(Kind), to_string(State), ...) are declared in its
      # include/ and meant to share a name; only file-private helpers must not.
      name=${line%%:*}
      if [ "${dir%/src}" != "$dir" ] && grep -rqE "[ *&]$name\(" "$root/${dir%/src}/include" 2>/dev/null; then continue; fi
      printf '%s\n' "$line"
    done)
  if [ -n "$dups" ]; then
    echo "$dir: names defined in more than one file of the target (rename one, or share it):" >&2
    printf '%s\n' "$dups" >&2
    status=1
  fi
done
[ $status -eq 0 ] && echo "no name defined twice in one unity target"
exit $status
