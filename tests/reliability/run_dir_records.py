#!/usr/bin/python3
# SPDX-License-Identifier: MIT
"""A run directory records the deck, version, command line, rank count and wall time (issue 8),
for every problem type: run_dir_records.py MSCALE DECK...

Each DECK (one small deck per problem type, tests/reliability/records/) is copied into a folder
whose name holds a double quote, a backslash and a space, and run there with `mscale run`; the
output directory must then hold run.log, deck.resolved.yaml (naming the deck's problem type)
and run_info.yaml, whose values (read back with YAML's double-quoted escapes) give the program,
a version, the exact command line, the deck path, 1 rank, a status and a wall time.
"""
import os
import re
import shutil
import subprocess
import sys
import tempfile


# Sanitizer build: Open MPI's MPI_Init (in `mscale run`) leaks in dlopen'ed components that
# LeakSanitizer cannot suppress by name (as tests/restart_check.sh); address and UB errors still
# stop the run, and tools/valgrind_unit.sh checks leaks with Open MPI suppressed.
RUN_ENV = dict(os.environ, ASAN_OPTIONS=os.environ.get("ASAN_OPTIONS", "") + ":detect_leaks=0")


def read_run_info(path):
    info = {}
    with open(path) as f:
        for line in f:
            if line.startswith("#") or ":" not in line:
                continue
            key, value = line.rstrip("\n").split(":", 1)
            value = value.strip()
            if value.startswith('"'):
                if not value.endswith('"') or len(value) < 2:
                    raise ValueError("unterminated string in %s" % line)
                value = value[1:-1].encode("utf-8").decode("unicode_escape")
            info[key] = value
    return info


def check(mscale, deck, tmp):
    fail = []
    folder = os.path.join(tmp, 'a "quoted\\n dir')  # a backslash before n: no newline
    os.makedirs(folder, exist_ok=True)
    local = os.path.join(folder, os.path.basename(deck))
    shutil.copy(deck, local)
    out = os.path.join(folder, "out " + os.path.basename(deck)[:-5])
    r = subprocess.run([mscale, "run", local, "-o", out, "--quiet"], env=RUN_ENV,
                       capture_output=True,
                       text=True, timeout=300)
    if r.returncode != 0:
        return ["exit code %d: %s" % (r.returncode, r.stderr)]
    for name in ("run.log", "deck.resolved.yaml", "run_info.yaml"):
        if not os.path.exists(os.path.join(out, name)):
            fail.append("no %s" % name)
    if fail:
        return fail
    problem = re.search(r"^problem: *(\S+)", open(deck).read(), re.M).group(1)
    if not re.search(r"^problem: *\"?%s\"?$" % problem,
                     open(os.path.join(out, "deck.resolved.yaml")).read(), re.M):
        fail.append("deck.resolved.yaml does not say problem: %s" % problem)
    info = read_run_info(os.path.join(out, "run_info.yaml"))
    want = {"program": "mscale", "command": "mscale run %s -o %s --quiet" % (local, out),
            "deck": local, "ranks": "1", "status": "completed"}
    for key, value in want.items():
        if info.get(key) != value:
            fail.append("run_info %s = %r, expected %r" % (key, info.get(key), value))
    if not re.match(r"^\d+\.\d+", info.get("version", "")):
        fail.append("run_info version = %r" % info.get("version"))
    try:
        if not float(info.get("wall_time_s", "nan")) >= 0:
            fail.append("run_info wall_time_s = %r" % info.get("wall_time_s"))
    except ValueError:
        fail.append("run_info wall_time_s = %r" % info.get("wall_time_s"))
    return fail


def main():
    mscale, decks = sys.argv[1], sys.argv[2:]
    nfail = 0
    with tempfile.TemporaryDirectory() as tmp:
        for deck in decks:
            fail = check(mscale, deck, tmp)
            for f in fail:
                print("FAIL %s: %s" % (os.path.basename(deck), f))
            if not fail:
                print("ok %s" % os.path.basename(deck))
            nfail += len(fail)
    return 1 if nfail or not decks else 0


if __name__ == "__main__":
    sys.exit(main())
