#!/usr/bin/env bash
# Fails when a test that ctest lists has a name a reader cannot use: a raw parameter dump
# ("GetParam() = 24-byte object <0A-A7 …>") or a bare index ("Suite/Test/3") instead of a name
# saying what is tested. usage: check_test_names.sh BUILD_DIR
set -u
list=$(ctest -N --test-dir "${1:?usage: check_test_names.sh BUILD_DIR}" | sed -n 's/^ *Test *#[0-9]*: //p')
[ -n "$list" ] || { echo "no tests listed" >&2; exit 1; }
bad=$(printf '%s\n' "$list" | grep -E 'GetParam|TypeParam|byte object|/[0-9]+$|/[0-9]+\.')
if [ -n "$bad" ]; then
  echo "tests without readable names (give INSTANTIATE_TEST_SUITE_P a name generator):" >&2
  printf '%s\n' "$bad" >&2
  exit 1
fi
echo "$(printf '%s\n' "$list" | wc -l) test names, all readable"
