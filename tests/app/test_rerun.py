#!/usr/bin/python3
# SPDX-License-Identifier: MIT
"""Reruns never mix (issue 23): test_rerun.py MSCALE SOURCE_DIR WORKDIR

- run_info.yaml's `manifest:` lists exactly the files the run wrote;
- `mscale run --force` into a directory holding another problem's outputs (and their plots/)
  removes them first: afterwards the directory holds the new run's files and nothing of the old
  one; a file of someone else's in the directory is kept, but is not in the manifest, and
  neither mscale.Run nor tools/plot_run.py reads it;
- a previous run_info.yaml without a manifest (a run killed by SIGKILL) still has its files
  removed: those modified since its `started` time.
"""
import os
import shutil
import subprocess
import sys

import yaml

MSCALE, SRC, WORK = sys.argv[1], sys.argv[2], sys.argv[3]
sys.path.insert(0, os.path.join(SRC, "python"))
import mscale  # noqa: E402

ENV = dict(os.environ, OMP_NUM_THREADS="1")
failures = []


def check(cond, what):
    if not cond:
        failures.append(what)
        print("FAIL:", what)


def run(deck, out, *extra):
    r = subprocess.run([MSCALE, "run", os.path.join(SRC, "inputs", deck), "-o", out, "--quiet",
                        *extra], env=ENV, capture_output=True, text=True, timeout=120)
    check(r.returncode == 0, f"run {deck}: exit {r.returncode}: {r.stderr}")
    return r


def plot(out):
    r = subprocess.run(["/usr/bin/python3", os.path.join(SRC, "tools", "plot_run.py"), out],
                       env=ENV, capture_output=True, text=True, timeout=300)
    check(r.returncode == 0, f"plot_run {out}: {r.stderr}")
    return sorted(os.listdir(os.path.join(out, "plots"))) if os.path.isdir(
        os.path.join(out, "plots")) else []


def manifest(out):
    with open(os.path.join(out, "run_info.yaml")) as f:
        return (yaml.safe_load(f) or {}).get("manifest")


def main():
    shutil.rmtree(WORK, ignore_errors=True)
    os.makedirs(WORK)
    out = os.path.join(WORK, "run")

    # 1. a continuum run: the manifest is every file of the fresh directory
    run("continuum-sod.yaml", out)
    first = sorted(os.listdir(out))
    check(manifest(out) == first, f"manifest {manifest(out)} != directory {first}")
    sod_plots = plot(out)
    check(sod_plots, f"no plots of the Sod run: {sod_plots}")

    # 2. someone else's file, then --force with another problem type
    with open(os.path.join(out, "notes.txt"), "w") as f:
        f.write("kept\n")
    foreign = os.path.join(out, "hugoniot_foreign.csv")  # a name a plotter would pick up
    shutil.copy(os.path.join(out, "profile_0000.csv"), foreign)
    run("dm-rod-sine.yaml", out, "--force")
    now = sorted(os.listdir(out))
    m = manifest(out)
    left = sorted(set(first) - set(m or []) & set(now))
    check(not left, f"files of the continuum run left after --force: {left}")
    check(not any(n.startswith(("profile_", "history", "xt")) for n in now),
          f"continuum outputs left: {now}")
    check(not os.path.isdir(os.path.join(out, "plots")), "plots/ of the old run left")
    check(sorted(set(now) - {"notes.txt", "hugoniot_foreign.csv"}) == m,
          f"manifest {m} is not the new run's files {now}")
    check("notes.txt" in now and "notes.txt" not in m, "a foreign file removed or listed")
    r = mscale.Run(out)
    check("hugoniot_foreign.csv" not in r.files and "hugoniot_foreign" not in r.tables,
          "mscale.Run reads a file outside the manifest")
    check(r.problem == "discrete_model" and r.profiles, "mscale.Run misses the new run's files")
    dm_plots = plot(out)
    check("hugoniot.png" not in dm_plots, f"plot_run plotted a file outside the manifest: "
          f"{dm_plots}")
    check(dm_plots, "no plots of the new run")

    # 3. a killed run leaves run_info.yaml without a manifest: --force removes what it wrote
    run("continuum-sod.yaml", out, "--force")
    info = os.path.join(out, "run_info.yaml")
    with open(info) as f:
        d = yaml.safe_load(f)
    d.pop("manifest")
    d["status"] = "running"
    with open(info, "w") as f:
        yaml.safe_dump(d, f)
    os.utime(os.path.join(out, "notes.txt"), (0, 0))  # older than the run: not its file
    os.utime(foreign, (0, 0))
    run("hugoniot-metals.yaml", out, "--force")
    now = sorted(os.listdir(out))
    check(not any(n.startswith(("profile_", "history", "xt")) for n in now),
          f"files of the killed run left: {now}")
    check("notes.txt" in now, "a file older than the killed run was removed")

    if failures:
        print(f"{len(failures)} failure(s)")
        return 1
    print("test_rerun: all checks passed")
    return 0


if __name__ == "__main__":
    sys.exit(main())
