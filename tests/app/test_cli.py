#!/usr/bin/python3
# SPDX-License-Identifier: MIT
"""The front end's command line (issue 23 items 1, 7, 8): test_cli.py MSCALE SOURCE_DIR WORKDIR

- `mscale --version` names the version from `git describe` (when the source is a git checkout)
  and the commit, compiler and library versions;
- run_info.yaml (read with PyYAML) records version, commit, compiler and flags, the MPI, HDF5,
  SUNDIALS, METIS and libyaml versions, ranks, threads (OMP_NUM_THREADS), host and overrides;
- `--set PATH=VALUE` gives the same outputs as the same value edited into the deck, and is
  recorded in run_info.yaml and deck.resolved.yaml, which re-runs to the same outputs;
- getopt_long: `--output=DIR`, a missing value is named, an unknown option gets a suggestion;
- a misspelt subcommand gets "did you mean".
"""
import filecmp
import os
import re
import shutil
import socket
import subprocess
import sys

import yaml

MSCALE, SRC, WORK = sys.argv[1], sys.argv[2], sys.argv[3]
ENV = dict(os.environ, OMP_NUM_THREADS="1")
failures = []


def check(cond, what):
    if not cond:
        failures.append(what)
        print("FAIL:", what)


def mscale(*args):
    return subprocess.run([MSCALE, *args], env=ENV, capture_output=True, text=True, timeout=120,
                          cwd=WORK)


def git(*args):
    try:
        r = subprocess.run(["git", "-C", SRC, *args], capture_output=True, text=True, timeout=30)
    except OSError:
        return None
    return r.stdout.strip() if r.returncode == 0 else None


def same_file(fa, fb):
    if not os.path.exists(fb):
        return False
    if fa.endswith(".h5"):  # by value, as tools/compare_builds.sh (the bytes hold HDF5's layout)
        return subprocess.run(["h5diff", "-q", fa, fb], capture_output=True).returncode == 0
    return filecmp.cmp(fa, fb, False)


def outputs_equal(a, b):
    """Every CSV/XDMF file of run a equals b's byte for byte, every HDF5 file by value."""
    names = sorted(f for f in os.listdir(a) if f.endswith((".csv", ".xmf", ".h5")))
    check(names, "no data files in %s" % a)
    for f in names:
        check(same_file(os.path.join(a, f), os.path.join(b, f)),
              "%s differs between %s and %s" % (f, a, b))


shutil.rmtree(WORK, ignore_errors=True)
os.makedirs(WORK)

# --version
r = mscale("--version")
check(r.returncode == 0, "--version exit %d" % r.returncode)
lines = r.stdout.splitlines()
m = re.match(r"^mscale (\S+)$", lines[0] if lines else "")
check(m, "--version first line: %r" % (lines[:1],))
version = m.group(1) if m else ""
# The commit the build recorded (HEAD when it was built; a later commit without a rebuild moves
# HEAD on) must be a commit of this repository whose `git describe` gives the version.
mc = re.search(r"^commit ([0-9a-f]{40})$", r.stdout, re.M)
head = mc.group(1) if mc else None
in_git = git("rev-parse", "--git-dir") is not None
if in_git:
    check(head and git("cat-file", "-e", head + "^{commit}") is not None,
          "--version names no commit of this repository: %r" % r.stdout)
    describe = git("describe", "--tags", "--always", head) if head else None
    # tagged: the describe text; untagged: PROJECT+gHASH; -dirty may follow either
    check(describe and (version.startswith(describe.lstrip("v")) or
                        ("+g" + describe) in version),
          "version %r does not come from git describe %r" % (version, describe))
check(re.search(r"libraries: MPI .*; HDF5 \d+\.\d+\.\d+; SUNDIALS \d+\.\d+\.\d+; METIS \d+\.\d+"
                r"\.\d+; libyaml \d+\.\d+\.\d+", r.stdout), "--version libraries: %r" % r.stdout)

# --set against the same value edited into the deck
deck = os.path.join(WORK, "sod.yaml")
shutil.copy(os.path.join(SRC, "inputs", "continuum-sod.yaml"), deck)
text = open(deck).read()
edited = text.replace("time: {end: 0.2, cfl: 0.5}", "time: {end: 0.02, cfl: 0.5}").replace(
    "output: {times: [0.1, 0.2],", "output: {times: [0.02],")
check(edited != text, "the sod deck changed: this test's edit does not apply")
open(os.path.join(WORK, "sod-edited.yaml"), "w").write(edited)
sets = ["continuum.time.end=0.02", "continuum.output.times=[0.02]"]
r = mscale("run", deck, "--output=set", "--quiet", "--set", sets[0], "--set=" + sets[1])
check(r.returncode == 0, "run --set exit %d: %s" % (r.returncode, r.stderr))
r = mscale("run", "sod-edited.yaml", "-o", "edited", "--quiet")
check(r.returncode == 0, "run edited exit %d: %s" % (r.returncode, r.stderr))
outputs_equal(os.path.join(WORK, "edited"), os.path.join(WORK, "set"))

info = yaml.safe_load(open(os.path.join(WORK, "set", "run_info.yaml")))
check(info.get("version") == version, "run_info version %r != %r" % (info.get("version"), version))
if head:
    check(info.get("git_commit") == head, "run_info git_commit %r" % info.get("git_commit"))
build = info.get("build") or {}
check(re.match(r"^\S+ \d+", build.get("compiler", "")), "build.compiler %r" % build)
check("-O" in build.get("flags", ""), "build.flags %r" % build.get("flags"))
check(build.get("cd_kernel") in ("scalar", "avx2", "avx512"), "build.cd_kernel %r" % build)
r = mscale("--version")  # the same kernel, and MSCALE_CD_KERNEL lowers it
check("cluster-dynamics kernels: %s" % build.get("cd_kernel") in r.stdout, "--version kernel")
r = subprocess.run([MSCALE, "--version"], env=dict(ENV, MSCALE_CD_KERNEL="scalar"),
                   capture_output=True, text=True, timeout=60)
check("cluster-dynamics kernels: scalar" in r.stdout, "MSCALE_CD_KERNEL=scalar: %r" % r.stdout)
libs = info.get("libraries") or {}
for lib in ("hdf5", "sundials", "metis", "libyaml"):
    check(re.match(r"^\d+\.\d+\.\d+$", str(libs.get(lib, ""))), "libraries.%s = %r" %
          (lib, libs.get(lib)))
check(len(str(libs.get("mpi", ""))) > 3, "libraries.mpi = %r" % libs.get("mpi"))
check(info.get("ranks") == 1, "ranks %r" % info.get("ranks"))
check(info.get("threads") == 1, "threads %r with OMP_NUM_THREADS=1" % info.get("threads"))
check(info.get("host") == socket.gethostname(), "host %r" % info.get("host"))
check(info.get("overrides") == sets, "overrides %r" % info.get("overrides"))
resolved_path = os.path.join(WORK, "set", "deck.resolved.yaml")
resolved_text = open(resolved_path).read()
for s in sets:
    check("# overridden on the command line: --set " + s in resolved_text,
          "deck.resolved.yaml does not list --set %s" % s)
resolved = yaml.safe_load(resolved_text)
check(resolved["continuum"]["time"]["end"] == 0.02, "resolved time.end %r" %
      resolved["continuum"]["time"]["end"])
r = mscale("run", resolved_path, "-o", "rerun", "--quiet")
check(r.returncode == 0, "rerun of deck.resolved.yaml exit %d: %s" % (r.returncode, r.stderr))
outputs_equal(os.path.join(WORK, "set"), os.path.join(WORK, "rerun"))
info = yaml.safe_load(open(os.path.join(WORK, "rerun", "run_info.yaml")))
check(info.get("overrides") == [], "no --set: overrides %r" % info.get("overrides"))

# two ranks: run_info.yaml counts them (the continuum problem runs on rank 0; the rest wait)
mpiexec = shutil.which("mpirun")
check(mpiexec, "no mpirun (Open MPI is a dependency)")
if mpiexec:
    r = subprocess.run([mpiexec, "--oversubscribe", "--allow-run-as-root", "-np", "2", MSCALE,
                        "run", deck, "-o", "np2", "--quiet", "--set", sets[0], "--set", sets[1]],
                       env=ENV, capture_output=True, text=True, timeout=120, cwd=WORK)
    check(r.returncode == 0, "2-rank run exit %d: %s" % (r.returncode, r.stderr))
    if r.returncode == 0:
        info = yaml.safe_load(open(os.path.join(WORK, "np2", "run_info.yaml")))
        check(info.get("ranks") == 2, "2-rank run: ranks %r" % info.get("ranks"))

# a bad override is a located error before anything runs
r = mscale("run", deck, "-o", "bad", "--set", "continuum.time.end=abc", "--set",
           "continuum.geometry=planer", "--set", "materials[5].name=x", "--set", "noequals")
check(r.returncode == 2, "bad --set exit %d" % r.returncode)
for want in ("--set continuum.time.end=abc: continuum.time.end: expected a number",
             "--set continuum.geometry=planer: continuum.geometry: expected one of: planar",
             "(did you mean 'planar'?)", "--set materials[5].name=x: materials", "has no item [5]",
             "--set: 'noequals': expected PATH=VALUE"):
    check(want in r.stderr, "bad --set: no %r in %r" % (want, r.stderr))
# a path that fails halfway leaves no new key behind: one error, not also "unknown key 'nw'"
r = mscale("check", deck, "--set", "continuum.nw.key[0]=1")
errors = [l for l in r.stderr.splitlines() if l.startswith("--set")]
check(r.returncode == 2 and len(errors) == 1 and "has no item [0]" in errors[0],
      "failed --set path: %r" % r.stderr)
check(not os.path.exists(os.path.join(WORK, "bad")), "bad --set created its output directory")
r = mscale("check", deck, "--set", "continuum.time.end=-1")
check(r.returncode == 2 and "--set continuum.time.end=-1: continuum.time.end:" in r.stderr,
      "check --set: %d %r" % (r.returncode, r.stderr))

# getopt_long messages
for args, want in ((["run", deck, "-o"], "option '-o' (--output) needs a value"),
                   (["run", deck, "--restart"], "option '--restart' needs a value"),
                   (["run", deck, "--set"], "option '--set' needs a value"),
                   (["run", deck, "-o", "--force"],
                    "option '-o' needs a value (found the option '--force' instead)"),
                   (["run", deck, "--forse"], "unknown option '--forse' (did you mean '--force'?)"),
                   (["run", deck, deck], "unexpected argument"),
                   (["run"], "no deck given"),
                   (["check", deck, "--sett=a=1"], "did you mean '--set'?"),
                   (["chek", deck], "unknown command 'chek' (did you mean 'check'?)"),
                   (["export", "x.h5", "--format"], "option '--format' needs a value"),
                   (["export", "x.h5", "--formt=extxyz"], "did you mean '--format'?"),
                   (["spectrum", "x.h5", "--bond"], "option '--bond' needs a value"),
                   (["spectrum", "--bond=abc", "x.h5"], "--bond needs a positive number")):
    r = mscale(*args)
    check(r.returncode == 2 and want in r.stderr,
          "%s: exit %d, stderr %r (wanted %r)" % (" ".join(args), r.returncode, r.stderr, want))

if failures:
    print("%d failure(s)" % len(failures))
    sys.exit(1)
print("PASS")
