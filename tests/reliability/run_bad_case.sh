#!/bin/sh
# SPDX-License-Identifier: MIT
# One case of the bad-input corpus (tests/reliability/bad/, docs/reliability.md):
#   run_bad_case.sh MSCALE CASE
# CASE is a deck (*.yaml, run as `mscale check CASE`) or a *.case file; its leading comment
# lines hold the directives:
#   # expect: LINE:COL TEXT        a stderr line starts with "CASE:LINE:COL:" and contains TEXT
#   # expect: REL:LINE:COL TEXT    the same for a data file REL (relative to CASE's folder)
#   # expect: REL: TEXT            a whole-file message "DIR/REL: ..." containing TEXT
#   # run: SUBCOMMAND ARGS         run `mscale SUBCOMMAND ARGS` instead of `check CASE`
#                                  (ARGS that name files are relative to CASE's folder)
#   # needs: WORD                  skip (exit 77) unless `mscale --help` / `mscale check --help`
#                                  mention WORD (a problem type or subcommand not built yet)
#   # also-run: yes                a deck: `mscale run CASE -o TMP` must fail the same way and
#                                  create no output directory (refused before anything runs)
#   # expect-count: N              exactly N stderr lines name CASE:LINE:COL (no knock-on
#                                  errors, no message printed twice)
# Lines naming CASE:LINE:COL must come in order of line and column (errors sorted by position),
# and no stderr line may appear twice.
# Passes if mscale exits with exactly 2, every expectation is met, and stderr shows no
# sanitizer report (a crash is a signal: exit code > 128, never 2).
# MSCALE_TEST_WRAPPER (e.g. "valgrind --error-exitcode=1 ...", tools/valgrind_unit.sh) is put in
# front of every mscale command.
# The memory limit is capped (at 64 GiB unless MSCALE_MEMORY_LIMIT is set) so that cases refused
# for their size do not depend on the machine.
set -u
mscale=$1 case=$2
dir=$(cd "$(dirname "$case")" && pwd)
case="$dir/$(basename "$case")"
out=$(mktemp) err=$(mktemp) rundir=$(mktemp -d)
trap 'rm -rf "$out" "$err" "$rundir"' EXIT
export MSCALE_MEMORY_LIMIT="${MSCALE_MEMORY_LIMIT:-64G}"

directives=$(sed -n '/^#/!q; s/^# *//p' "$case")
needs=$(printf '%s\n' "$directives" | sed -n 's/^needs: *//p')
for word in $needs; do
  # a subcommand line of `mscale --help` or a problem-type line of `mscale check --help`
  if ! { "$mscale" --help; "$mscale" check --help; } 2>&1 |
       grep -qE -- "(^ +| mscale )$word( |\$)"; then
    echo "SKIP: this mscale does not offer '$word' yet"
    exit 77
  fi
done

run=$(printf '%s\n' "$directives" | sed -n 's/^run: *//p')
if [ -n "$run" ]; then
  set -- $run
  sub=$1
  shift
  args=
  for a in "$@"; do
    case $a in -*) args="$args $a" ;; *) args="$args $dir/$a" ;; esac
  done
  (cd "$dir" && ${MSCALE_TEST_WRAPPER:-} "$mscale" "$sub" $args) >"$out" 2>"$err"
else
  ${MSCALE_TEST_WRAPPER:-} "$mscale" check "$case" >"$out" 2>"$err"
fi
rc=$?
fail=0

# check_result LABEL: the exit code in $rc and stderr in $err against the expectations
check_result() {
  echo "--- stderr of $1:"
  cat "$err"
  if [ "$rc" -ne 2 ]; then
    echo "FAIL: exit code $rc, expected 2"
    fail=1
  fi
  if grep -qE 'Sanitizer|runtime error:|Segmentation fault|Aborted' "$err"; then
    echo "FAIL: sanitizer report or crash"
    fail=1
  fi
  nexpect=0
  printf '%s\n' "$directives" | sed -n 's/^expect: *//p' > "$out.expect"
  while IFS= read -r line; do
    [ -n "$line" ] || continue
    nexpect=$((nexpect + 1))
    where=${line%% *}
    text=${line#* }
    case $where in
      [0-9]*:[0-9]*) prefix="$case:$where:" ;;
      *:) prefix="$dir/$where" ;;
      *) prefix="$dir/$where:" ;;
    esac
    if ! awk -v p="$prefix" -v t="$text" 'index($0, p) == 1 && index($0, t) > 0 { f = 1 }
                                          END { exit !f }' "$err"; then
      echo "FAIL: no stderr line starts with '$prefix' and contains '$text'"
      fail=1
    fi
  done < "$out.expect"
  rm -f "$out.expect"
  count=$(printf '%s\n' "$directives" | sed -n 's/^expect-count: *//p')
  if [ -n "$count" ]; then
    got=$(awk -v p="$case:" 'index($0, p) == 1 && substr($0, length(p) + 1) ~ /^[0-9]/ { n++ }
                             END { print n + 0 }' "$err")
    if [ "$got" -ne "$count" ]; then
      echo "FAIL: $got stderr lines name the case, expected $count"
      fail=1
    fi
  fi
  if ! awk -v p="$case:" 'index($0, p) == 1 {
         split(substr($0, length(p) + 1), f, ":")
         if (f[1] ~ /^[0-9]+$/ && f[2] ~ /^[0-9]+$/) {
           k = f[1] * 100000 + f[2]
           if (k < last) bad = 1
           last = k
         }
       }
       END { exit bad }' "$err"; then
    echo "FAIL: the messages are not sorted by line and column"
    fail=1
  fi
  if [ -n "$(sort "$err" | uniq -d)" ]; then
    echo "FAIL: a line is printed twice: $(sort "$err" | uniq -d | head -1)"
    fail=1
  fi
  if [ "$nexpect" -eq 0 ]; then
    echo "FAIL: the case states no '# expect:' line"
    fail=1
  fi
}
check_result "mscale (exit $rc)"
if printf '%s\n' "$directives" | grep -q '^also-run: *yes'; then
  # sanitizer build: Open MPI's MPI_Init (in `mscale run`) leaks in dlopen'ed components that
  # LeakSanitizer cannot suppress by name (as tests/restart_check.sh); valgrind checks leaks
  ASAN_OPTIONS="${ASAN_OPTIONS:-}:detect_leaks=0" \
    ${MSCALE_TEST_WRAPPER:-} "$mscale" run "$case" -o "$rundir/out" >"$out" 2>"$err"
  rc=$?
  check_result "mscale run (exit $rc)"
  if [ -e "$rundir/out" ]; then
    echo "FAIL: mscale run created its output directory"
    fail=1
  fi
fi
[ "$fail" -eq 0 ] && echo "PASS: exit 2 with the expected message(s)"
exit $fail
