#!/usr/bin/python3
# SPDX-License-Identifier: MIT
"""Richtmyer–Meshkov microjets of the discrete model: the spike and bubble against the weakly
nonlinear (second-order) impulsive theory, time-resolved.

Usage:  /usr/bin/python3 tools/jets_history.py OUTDIR [--step 0.5]

Reads OUTDIR/jets_kh0.csv and the histories OUTDIR/trace_kh0_<i>.csv that
build/bench/dm_jets/bench_dm_jets --trace -o OUTDIR writes (docs/validation.md "Microjets").
For each case and each interval of STEP lambda/U_s after the flat strip's breakout t_b (the
first trace row with u_fs >= u_p): the mean k eta, the least-squares slopes (km/s) of the
spike x_valley - x_fs, of the bubble x_peak - x_fs and of eta = (x_valley - x_peak)/2, and the
second-order predictions from the measured eta: spike eta + (k/2)(eta^2 - eta_b^2), bubble
-eta + (k/2)(eta^2 - eta_b^2), i.e. velocities eta' (1 +- k eta) ([VelikovichDimonte1996;
ZhangSohn1997] for Atwood number -1; bench/dm_jets/jets.c, nl_prediction).
With --tip, instead, the jet-tip measures of bench/dm_jets/jets_tip.h per interval (absolute
velocities, km/s): the bulk surface (slope of x_fs), the axis particles (x_valley), the foremost
particle (x_spike), the leading-mass fronts x_m1, x_m10, x_m50 (the front of the valley half's
leading 0.01, 0.1, 0.5 rho0 h0 lambda), the mean velocity of the leading 0.1 rho0 h0 lambda
(v_m10), the jet cluster's front (x_main); and at the interval's end the jet's mass (rho0 h0
lambda), its clusters, the particles ahead of the jet cluster and the foremost particle's
cluster (traces of the bench after its jets_tip measures; older traces lack the columns).
Needs Debian's numpy (run with /usr/bin/python3).
"""
import argparse
import os
import sys

import numpy as np

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "python"))
import mscale  # noqa: E402  (python/mscale: the reader of mscale's outputs)


def slope(t, y):
    """Least-squares slope of y(t)."""
    if len(t) < 3:
        return float("nan")
    return float(np.polyfit(t, y, 1)[0])


def history(trace, kh0_row, step):
    """Rows (tau0, tau1, k eta, spike, spike_nl, bubble, bubble_nl, eta') of one case."""
    tr = mscale.read_csv(trace)
    lam, us, up = kh0_row["lambda"], kh0_row["us"], kh0_row["up"]
    k = 2 * np.pi / lam
    t = tr["t"]
    ib = int(np.argmax(tr["u_fs"] >= up))
    tb = t[ib]
    eta = tr["eta"]
    eta_b = eta[ib]
    h2 = 0.5 * k * (eta**2 - eta_b**2)
    spike = tr["x_valley"] - tr["x_fs"]
    bubble = tr["x_bubble"] - tr["x_fs"]
    tau = (t - tb) * us / lam
    rows = []
    a = 0.0
    while a + 0.5 * step < tau[-1]:  # the last interval may end a trace row early
        m = (tau >= a) & (tau <= a + step)
        rows.append((a, a + step, k * float(np.mean(eta[m])), slope(t[m], spike[m]),
                     slope(t[m], eta[m] + h2[m]), slope(t[m], bubble[m]),
                     slope(t[m], -eta[m] + h2[m]), slope(t[m], eta[m])))
        a += step
    return rows


def tip_history(trace, kh0_row, step):
    """Rows of the jet-tip measures of one case (see --tip)."""
    tr = mscale.read_csv(trace)
    lam, us, up = kh0_row["lambda"], kh0_row["us"], kh0_row["up"]
    t = tr["t"]
    ib = int(np.argmax(tr["u_fs"] >= up))
    tau = (t - t[ib]) * us / lam
    rows = []
    a = 0.0
    while a + 0.5 * step < tau[-1]:
        m = (tau >= a) & (tau <= a + step)
        last = np.nonzero(m)[0][-1]
        v = [slope(t[m], tr[key][m]) for key in
             ("x_fs", "x_valley", "x_spike", "x_m1", "x_m10", "x_m50")]
        v.append(float(np.mean(tr["v_m10"][m])))
        v.append(slope(t[m], tr["x_main"][m]))
        rows.append((a, a + step, *v, tr["m_jet"][last], int(tr["n_clusters"][last]),
                     int(tr["n_ahead"][last]), int(tr["tip_cluster"][last])))
        a += step
    return rows


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("outdir")
    ap.add_argument("--step", type=float, default=0.5, help="interval, lambda/U_s")
    ap.add_argument("--tip", action="store_true", help="the jet-tip measures instead")
    args = ap.parse_args()
    kh = mscale.read_csv(os.path.join(args.outdir, "jets_kh0.csv"))
    n = len(kh["kh0"])
    for i in range(n):
        trace = os.path.join(args.outdir, f"trace_kh0_{i}.csv")
        if not os.path.exists(trace):
            continue
        row = {key: kh[key][i] for key in kh.keys()}
        if args.tip:
            print(f"kh0 {row['kh0']:g}, lambda/h {row['ncol']:g} (km/s; masses rho0 h0 lambda)")
            print("  tau          u_fs  valley  foremost  front1  front10  front50  v_m10"
                  "  cluster  m_jet clusters ahead tip_cluster")
            for r in tip_history(trace, row, args.step):
                print(f"  {r[0]:4.2f}-{r[1]:4.2f}" + "".join(f" {x:7.3f}" for x in r[2:10])
                      + f"  {r[10]:6.3f} {r[11]:5d} {r[12]:5d} {r[13]:6d}")
            continue
        print(f"kh0 {row['kh0']:g}, lambda/h {row['ncol']:g} "
              "(units km/s; tau = (t - t_b) U_s/lambda)")
        print("  tau          k eta   spike  eta'(1+k eta)  ratio   bubble  -eta'(1-k eta)   eta'")
        for r in history(trace, row, args.step):
            ratio = r[3] / r[4] if r[4] != 0 else float("nan")
            print(f"  {r[0]:4.2f}-{r[1]:4.2f}  {r[2]:6.3f}  {r[3]:7.4f}  {r[4]:7.4f}  {ratio:10.3f}"
                  f"  {r[5]:8.4f}  {r[6]:8.4f}  {r[7]:12.4f}")


if __name__ == "__main__":
    main()
