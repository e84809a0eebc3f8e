#!/usr/bin/python3
# SPDX-License-Identifier: MIT
"""Communication-volume model of distributed cluster dynamics for 10^3-10^5 ranks
(docs/benchmarks.md "CD communication model").

Computed: METIS partitions (cd_partition_cells via bench_cd_partition grid) of periodic cubic
grids of link cells with P parts of m cells each, for m = n/k with n = 1e3..1e6 particles per
rank -- every part is interior, as in a weak-scaling run far from the domain's boundary. They
give per part: halo cells (the ghost layer: one link-cell layer holds every particle a rank's
forces need), neighbour parts (messages) and the weight imbalance.

Extrapolated: to the rank counts METIS cannot partition here (P = 1e3-1e5 with up to 1e11
particles), by the surface/volume law. The ghost layer of a part of m cells is
rho * ((m^(1/3) + 2)^3 - m) cells, the halo of a cube of the same volume times rho = the METIS
shape penalty measured at the same m (METIS parts are less compact than cubes); with every
part interior it does not depend on P. Messages and imbalance: the computed values at that m.

Time per step of the slowest rank: t = imbalance * n * c + t_comm, with c the measured compute
cost per particle-step and t_comm = neighbours * latency + ghosts_max * bytes_per_ghost /
bandwidth + 2 log2(P) latency (one small all-reduce per step: the instability check);
ghosts_max = the mean times the computed max/mean halo ratio, neighbours = the mean neighbour
parts of the computed partitions with P >= 64.

Usage: /usr/bin/python3 tools/cd_comm_model.py [--bench PATH] [--quick] [--latency 1e-6]
       [--bandwidth 10e9] [--cost 8.7e-8] [--bytes 48]
"""
import argparse
import csv
import io
import math
import subprocess
import sys

R_LIST = 1.3  # link cell width in r0: R_c = 1.2 r0 + skin 0.1 r0 (bench/cd_lammps settings)
K = R_LIST ** 3 * math.sqrt(2.0)  # fcc particles per link cell (density sqrt(2)/r0^3): 3.11


def cube_halo(m):
    """Halo cells of a cube of m cells (one-cell layer around it)."""
    s = m ** (1.0 / 3.0)
    return (s + 2.0) ** 3 - s ** 3


def run_grid(bench, side, parts):
    """METIS rows of `bench_cd_partition grid side side side 3 P... --periodic`."""
    cmd = [bench, "grid", str(side), str(side), str(side), "3"] + [str(p) for p in parts]
    cmd.append("--periodic")
    out = subprocess.run(cmd, check=True, capture_output=True, text=True).stdout
    return [r for r in csv.DictReader(io.StringIO(out)) if r["method"] == "metis"]


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--bench", default="build/bench/cd_partition/bench_cd_partition")
    ap.add_argument("--quick", action="store_true", help="skip the 1e6-particle graphs")
    ap.add_argument("--latency", type=float, default=1e-6, help="s per message (default 1 us)")
    ap.add_argument("--bandwidth", type=float, default=10e9, help="bytes/s per rank (10 GB/s)")
    ap.add_argument("--cost", type=float, default=1 / 1.15e7,
                    help="s per particle-step (default: 1/1.15e7, cd_lammps problem A, 1 core)")
    ap.add_argument("--bytes", type=float, default=48.0,
                    help="bytes per ghost per step (default 48: position + velocity)")
    a = ap.parse_args()

    # ---- computed: METIS on periodic grids, cells per part m = n/K ----
    plan = [(1e3, [64, 512]), (1e4, [64, 512]), (1e5, [8, 64]), (1e6, [8])]
    if a.quick:
        plan = plan[:3]
    computed = {}  # n -> list of (P, m, halo_mean, halo_max, nbr_mean, nbr_max, imbalance, s)
    print("# computed: METIS (cd_partition_cells) on periodic cubic link-cell grids, "
          f"k = {K:.2f} particles per cell")
    print("| particles/rank n | parts P | grid | cells/part m | halo cells mean (max) | "
          "cube halo | METIS/cube | neighbour parts mean (max) | imbalance | METIS s |")
    print("|---|---|---|---|---|---|---|---|---|---|")
    for n, parts in plan:
        m_target = n / K
        for P in parts:
            side = max(2, round((P * m_target) ** (1.0 / 3.0)))
            row = run_grid(a.bench, side, [P])[0]
            m = side ** 3 / P
            hm, hx = float(row["halo_mean"]), int(row["halo_max"])
            nm, nx = float(row["nbr_mean"]), int(row["nbr_max"])
            imb = float(row["imbalance"])
            computed.setdefault(n, []).append((P, m, hm, hx, nm, nx, imb, float(row["seconds"])))
            print(f"| {n:.0e} | {P} | {side}^3 | {m:.0f} | {hm:.0f} ({hx}) | {cube_halo(m):.0f} | "
                  f"{hm / cube_halo(m):.3f} | {nm:.1f} ({nx}) | {imb:.4f} | {row['seconds']} |",
                  flush=True)

    # messages: METIS parts of a large partition (P >= 64) touch ~15 others whatever their
    # size (a part of an 8-part periodic box touches all 7: too few parts to say)
    many = [t for pts in computed.values() for t in pts if t[0] >= 64]
    nbr_many = sum(t[4] for t in many) / len(many)
    print(f"# neighbour parts per part for P >= 64 (mean over the computed rows): {nbr_many:.1f}")

    def model(n, P):
        """Ghosts, messages, imbalance per rank at n particles per rank on P ranks."""
        pts = computed.get(n)
        if pts is None:  # nearest computed n in log
            near = min(computed, key=lambda c: abs(math.log(c / n)))
            pts = computed[near]
        big = max(pts, key=lambda t: t[0])  # the computed point with the most parts
        rho = big[2] / cube_halo(big[1])  # METIS shape penalty at this part size
        m = n / K
        exact = [t for t in pts if t[0] == P and n in computed]
        ghosts = (exact[0][2] if exact else rho * cube_halo(m)) * K
        peak = big[3] / big[2]  # the busiest rank's halo over the mean, at the same part size
        return ghosts, ghosts * peak, nbr_many, big[6], bool(exact)

    def step_time(n, P):
        """The slowest rank: the largest load (imbalance) and the largest halo."""
        ghosts, gmax, nbr, imb, exact = model(n, P)
        t_comp = imb * n * a.cost
        t_comm = nbr * a.latency + gmax * a.bytes / a.bandwidth + 2 * math.log2(P) * a.latency
        return ghosts, gmax, nbr, t_comp, t_comm, exact

    print()
    print(f"# weak scaling: latency {a.latency * 1e6:g} us, bandwidth {a.bandwidth / 1e9:g} GB/s, "
          f"{a.bytes:g} B per ghost per step, compute {a.cost * 1e9:.0f} ns per particle-step")
    print("| particles/rank n | ranks P | ghosts/rank mean (max) | ghosts/owned | messages | "
          "t_comp per step | t_comm per step | comm share | source |")
    print("|---|---|---|---|---|---|---|---|---|")
    for n in sorted(computed):
        for P in [int(x) for x in (1e3, 1e4, 1e5)]:
            g, gmax, nbr, tc, tm, exact = step_time(n, P)
            print(f"| {n:.0e} | {P:.0e} | {g:.3g} ({gmax:.3g}) | {g / n:.3f} | {nbr:.1f} | "
                  f"{tc * 1e3:.3g} ms | "
                  f"{tm * 1e3:.3g} ms | {tm / (tc + tm) * 100:.2g} % | "
                  f"{'computed' if exact else 'extrapolated'} |")
    print()
    print("# strong scaling (same model): efficiency relative to 10^3 ranks")
    print("| total N | ranks P | particles/rank | ghosts/owned | t per step | efficiency |")
    print("|---|---|---|---|---|---|")
    for N in (1e8, 1e9):
        base = None
        for P in (1e3, 1e4, 1e5):
            n = N / P
            if n < min(computed) / 1.5 or n > max(computed) * 1.5:
                continue
            g, _, nbr, tc, tm, _ = step_time(n, int(P))
            t = tc + tm
            base = base or (t * P)
            print(f"| {N:.0e} | {P:.0e} | {n:.0e} | {g / n:.3f} | {t * 1e3:.3g} ms | "
                  f"{base / (t * P) * 100:.1f} % |")
    return 0


if __name__ == "__main__":
    sys.exit(main())
