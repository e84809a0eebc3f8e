#!/usr/bin/python3
# SPDX-License-Identifier: MIT
"""Turn an mscale run directory into PNG plots (written next to the data, under plots/).

Usage: /usr/bin/python3 tools/plot_run.py OUTDIR

Recognises the outputs of each problem type by file name and calls the matching plotter in
tools/ (plot_*.py). Uses Debian's numpy, h5py and matplotlib only. Only the files of the run
are plotted: when run_info.yaml lists them (``manifest:``), the plotters see a view of the
directory that holds those files alone, so that files of an earlier run or of another program
in the same directory never enter a plot.
"""
import glob
import importlib.util
import os
import shutil
import sys
import tempfile

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
from plot_spectrum import lab, read_csv  # noqa: E402  (python/mscale's reader, as a tuple)
import mscale  # noqa: E402  (plot_spectrum put python/ on the path)


def run_view(outdir):
    """A temporary directory of symbolic links to the files of run_info.yaml's manifest (None
    when the run has no manifest: every file of outdir is then the run's)."""
    names = mscale.Run(outdir).manifest
    if names is None:
        return None
    view = tempfile.mkdtemp(prefix="plot_run_")
    for n in sorted(names):
        src = os.path.join(os.path.abspath(outdir), n)
        if os.path.exists(src):
            os.symlink(src, os.path.join(view, n))
    return view


def plot_hugoniots(outdir, plotdir):
    files = sorted(glob.glob(os.path.join(outdir, "hugoniot_*.csv")))
    if not files:
        return []
    fig, (ax1, ax2) = plt.subplots(1, 2, figsize=(10, 4))
    for path in files:
        c, units, _ = read_csv(path)
        mat = os.path.basename(path)[len("hugoniot_"):-4]
        ax1.plot(c["up"], c["Us"], "o-", label=mat)
        ax2.plot(c["rho"], c["P"], "o-", label=mat)
    ax1.set_xlabel(lab("up", units)); ax1.set_ylabel(lab("Us", units)); ax1.legend()
    ax2.set_xlabel(lab("rho", units)); ax2.set_ylabel(lab("P", units)); ax2.legend()
    ax1.set_title("Shock velocity vs particle velocity"); ax2.set_title("Hugoniot P(rho)")
    fig.tight_layout()
    out = os.path.join(plotdir, "hugoniot.png")
    fig.savefig(out, dpi=120)
    plt.close(fig)
    return [out]


def load_plugin(name):
    path = os.path.join(HERE, name)
    if not os.path.exists(path):
        return None
    spec = importlib.util.spec_from_file_location(name[:-3], path)
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


def main():
    if len(sys.argv) != 2 or sys.argv[1] in ("-h", "--help"):
        print(__doc__)
        return 0 if len(sys.argv) == 2 else 2
    outdir = sys.argv[1]
    if not os.path.isdir(outdir):
        print(f"plot_run: '{outdir}' is not a directory", file=sys.stderr)
        return 2
    plotdir = os.path.join(outdir, "plots")
    os.makedirs(plotdir, exist_ok=True)
    view = run_view(outdir)
    try:
        data = view or outdir
        made = plot_hugoniots(data, plotdir)
        # Plotters of the other modules: each offers plot_run(outdir, plotdir) -> list of files.
        for plugin in ("plot_xt.py", "plot_particles.py", "plot_spectrum.py", "plot_coupled.py"):
            mod = load_plugin(plugin)
            if mod is not None and hasattr(mod, "plot_run"):
                made += mod.plot_run(data, plotdir) or []
    finally:
        if view:
            shutil.rmtree(view)
    for m in made:
        print(f"plot_run: wrote {m}")
    if not made:
        print(f"plot_run: nothing to plot in {outdir}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
