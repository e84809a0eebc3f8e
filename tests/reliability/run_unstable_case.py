#!/usr/bin/python3
# SPDX-License-Identifier: MIT
"""One instability case (tests/reliability/unstable/, docs/reliability.md section 5):
    run_unstable_case.py MSCALE CASE

`mscale run CASE` must stop with exit code 1; stderr must hold the guard's message
"unstable at step N, t = T: ..." and every `# expect: TEXT` of the case; the final snapshot
named by `# snapshot: FILE GROUP OFFSET` must exist in the output directory, open with h5py,
and carry the attributes time = T (to the message's 9 digits) and step = N + OFFSET (OFFSET -1
for the grid: its message names the step that failed, its snapshot holds the state before it).
"""
import os
import re
import subprocess
import sys
import tempfile

import h5py


# Sanitizer build: Open MPI's MPI_Init (in `mscale run`) leaks in dlopen'ed components that
# LeakSanitizer cannot suppress by name (as tests/restart_check.sh); address and UB errors still
# stop the run, and tools/valgrind_unit.sh checks leaks with Open MPI suppressed.
RUN_ENV = dict(os.environ, ASAN_OPTIONS=os.environ.get("ASAN_OPTIONS", "") + ":detect_leaks=0")


def main():
    mscale, case = sys.argv[1], sys.argv[2]
    expects, snapshot = [], None
    with open(case) as f:
        for line in f:
            if not line.startswith("#"):
                break
            d = line[1:].strip()
            if d.startswith("expect:"):
                expects.append(d[len("expect:"):].strip())
            elif d.startswith("snapshot:"):
                snapshot = d[len("snapshot:"):].split()
    fail = []
    if not expects or not snapshot or len(snapshot) != 3:
        fail.append("the case needs '# expect:' lines and '# snapshot: FILE GROUP OFFSET'")
    with tempfile.TemporaryDirectory() as tmp:
        out = os.path.join(tmp, "out")
        r = subprocess.run([mscale, "run", case, "-o", out, "--quiet"], env=RUN_ENV,
                           capture_output=True,
                           text=True, timeout=300)
        print("--- stderr of mscale run (exit %d):\n%s" % (r.returncode, r.stderr))
        if r.returncode != 1:
            fail.append("exit code %d, expected 1" % r.returncode)
        if re.search(r"Sanitizer|runtime error:", r.stderr):
            fail.append("sanitizer report")
        for text in expects:
            if text not in r.stderr:
                fail.append("stderr does not contain '%s'" % text)
        info = os.path.join(out, "run_info.yaml")  # the run directory records the failure too
        if not os.path.exists(info) or "status: failed" not in open(info).read():
            fail.append("run_info.yaml missing or without 'status: failed'")
        # the time in the output unit the snapshot's time attribute has too (us)
        m = re.search(r"unstable at step (\d+), t = ([-+0-9.eE]+)(?: us)?:", r.stderr)
        if not m:
            fail.append("no 'unstable at step N, t = T:' message")
        elif snapshot and len(snapshot) == 3:
            step, t = int(m.group(1)), float(m.group(2))
            name, group, offset = snapshot[0], snapshot[1], int(snapshot[2])
            path = os.path.join(out, name)
            if not os.path.exists(path):
                fail.append("no final snapshot %s" % name)
            else:
                with h5py.File(path, "r") as h:
                    a = h[group].attrs
                    # %.9g in the message: 9 significant digits
                    if abs(float(a["time"]) - t) > 1e-8 * max(abs(t), 1e-300):
                        fail.append("snapshot time %r, message t = %r" % (float(a["time"]), t))
                    if int(a["step"]) != step + offset:
                        fail.append("snapshot step %d, message step %d%+d"
                                    % (int(a["step"]), step, offset))
                    print("snapshot %s: time %r step %d" % (name, float(a["time"]), int(a["step"])))
    for f in fail:
        print("FAIL: " + f)
    if not fail:
        print("PASS: exit 1, the guard's message, the final snapshot at its step and time")
    return 1 if fail else 0


if __name__ == "__main__":
    sys.exit(main())
