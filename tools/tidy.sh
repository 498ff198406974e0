#!/bin/sh
# clang-tidy-14 with the checks of .clang-tidy (which says what it leaves out, and why) over the
# project's C++ sources a change touches: every .cpp under daemon/, codecs/, adapters/ and cli/
# that differs from BASE, and the .cpp beside each header that does. The whole tree takes about
# an hour of one core, too long for CI; `tools/tidy.sh --all` runs it anyway.
#
#   tools/tidy.sh [--all]
#
# BASE: what the change is measured against; default the merge base with origin/main, else with
# main; on main itself (the merge base is HEAD), HEAD~1: the last commit, or merge, in CI. BUILD_DIR: a configured and built tree (compile_commands.json, and the
# generated headers some sources include); default build. TIDY_JOBS: files at once (default 2).
# Exits non-zero when a check fires.
set -eu
cd "$(dirname "$0")/.."
build=${BUILD_DIR:-build}
jobs=${TIDY_JOBS:-2}
command -v clang-tidy-14 >/dev/null || {
  echo "tidy.sh: clang-tidy-14 not found (tools/deps.sh ci installs it)" >&2
  exit 2
}
[ -f "$build/compile_commands.json" ] || {
  echo "tidy.sh: no $build/compile_commands.json: configure and build $build first" >&2
  exit 2
}

trees="daemon codecs adapters cli"
if [ "${1:-}" = --all ]; then
  # shellcheck disable=SC2086 # $trees is a list of folders
  changed=$(git ls-files $trees)
else
  base=${BASE:-$(git merge-base HEAD origin/main 2>/dev/null || git merge-base HEAD main 2>/dev/null ||
    git rev-parse HEAD)}
  [ "$(git rev-parse "$base")" = "$(git rev-parse HEAD)" ] && base=$(git rev-parse HEAD~1)
  # shellcheck disable=SC2086 # $trees is a list of folders
  changed=$(git diff --name-only --diff-filter=d "$base" -- $trees)
fi
files=$(for f in $changed; do
  case "$f" in
    */tests/*) ;;  # the tests' own code is not held to these checks
    *.cpp) echo "$f" ;;
    *.h) [ -f "${f%.h}.cpp" ] && echo "${f%.h}.cpp" ;;
  esac
done | sort -u)
if [ -z "$files" ]; then
  echo "tidy.sh: no C++ source changed"
  exit 0
fi
echo "tidy.sh: $(echo "$files" | wc -l) file(s)"
# shellcheck disable=SC2086 # $files is a list of paths without spaces
printf '%s\n' $files | xargs -P "$jobs" -n 1 clang-tidy-14 -p "$build" --quiet
