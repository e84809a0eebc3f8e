# SPDX-License-Identifier: MIT
"""The Piekutowski perforation at CI size (docs/validation.md, "Piekutowski perforation").

    /usr/bin/python3 tests/python/test_piekutowski.py MSCALE_BINARY SOURCE_DIR WORKDIR

Runs the shipped deck inputs/impact-piekutowski-coarse.yaml (a 9.53 mm Al sphere at 6.7 km/s
onto a 2.21 mm Al plate, h = t/3, 4 µs, ~5 s) and measures it with tools/piekutowski.py:
energy and momentum balance, the hole through the plate (the areal-mass measure and the hole in
the recovered plate, the remnant that holds the plate's rim), the debris cloud's leading edge and
the back-spray. PIEK_PRINT=1 prints the numbers.
"""
import os
import subprocess
import sys

import numpy as np

mscale_bin, src, work = sys.argv[1:4]
sys.path.insert(0, os.path.join(src, "python"))
sys.path.insert(0, os.path.join(src, "tools"))
import mscale  # noqa: E402
import piekutowski  # noqa: E402

EXP_HOLE = 17.3  # mm, [Piekutowski1993] via [Davydov] Table 2

out = os.path.join(work, "piek_coarse")
env = dict(os.environ, ASAN_OPTIONS=os.environ.get("ASAN_OPTIONS", "") + ":detect_leaks=0")
res = subprocess.run([mscale_bin, "run", os.path.join(src, "inputs",
                                                      "impact-piekutowski-coarse.yaml"),
                      "-o", out, "--force", "--quiet"], env=env, capture_output=True, text=True)
if res.returncode != 0:
    sys.exit(f"test_piekutowski: mscale run failed ({res.returncode}):\n{res.stderr}")
run = mscale.Run(out)
s = run.table("impact_summary")
hist = run.table("impact_history")
P = np.stack([np.asarray(hist[c], float) for c in ("p_x", "p_y", "p_z")], axis=1)
dP = np.max(np.linalg.norm(P - P[0], axis=1)) / np.linalg.norm(P[0])
m = piekutowski.measure(out)
hole = 10 * m["hole"]
hole_rem = 10 * m["hole_rem"]
g = m["g"]
# the holed plate's mass: the plate's lattice sites outside the recovered plate's equal-area hole
snap = run.snapshots[-1]
X0 = np.asarray(snap["X0"], float)
body = np.asarray(snap["body"]).astype(int)
r0 = np.hypot(X0[:, 0] - g["axis"][0], X0[:, 1] - g["axis"][1])
m_site = m["rem_mass"] / max(np.count_nonzero(m["rem"]), 1)  # ρ0 h³, one plate particle
holed = m_site * np.count_nonzero((body == 1) & (r0 >= 0.5 * m["hole_rem"]))
plate = m_site * np.count_nonzero(body == 1)
if os.environ.get("PIEK_PRINT"):
    print(f"energy_err {float(s['energy_err'][0]):.3g}, contact |W + E|/E0 "
          f"{float(s['wall_err'][0]):.3g}, |dP|/|P0| {dP:.3g}, failed {int(s['failed'][0])}, "
          f"broken {float(s['broken'][0]):.4g} kJ; hole {hole:.3f} mm (innermost particle "
          f"{10 * m['hole_min']:.3f}, unbroken plate {10 * m['hole_unbroken']:.3f}); hole in the "
          f"recovered plate {hole_rem:.3f} mm, remnant {m['rem_mass']:.4f} g against the holed "
          f"plate {holed:.4f} g, rim in it {m['rim_frac']:.3f}; theta_v {m['theta_v']:.2f} deg, "
          f"leading edge {m['v_edge']:.3f} km/s")
checks = [
    # K + U + E_hg + broken − W_contact = E0 per half kick (dm_finite.c, dm_fracture.c):
    # round-off over ~500 steps
    (float(s["energy_err"][0]) < 1e-11, "energy balance to round-off"),
    # the contact's stored energy against its work: the penalty's time discretisation, measured
    # 8.2e-4 E0 (the first contact at 6.7 km/s); 1e-2 fails a contact that leaks energy
    (float(s["wall_err"][0]) < 1e-2, "contact work = -stored energy"),
    # pairwise central contact forces and the model's internal forces: momentum is conserved
    (dP < 1e-12, "momentum conserved"),
    # LOOSE BOUND (issue 25's criterion for the full size is 5 %). The hole (where the areal
    # mass of the plate's particles, failed or not, reaches half the intact plate's:
    # tools/piekutowski.py) at h = t/3 = 0.74 mm: one ring of width h on the radius is 1.47 mm
    # of diameter, 8.5 % of 17.3 mm. Measured +8.6 % here at 4 µs (+2.7 % before a failed
    # member left F), −4.7 % and −8.9 % on the t/4 and t/6 quarters (docs/validation.md).
    # 17 % (two rings) admits the coarse lattice with a margin for round-off in ~400 steps of a
    # fracturing run, and fails a plate that is not perforated (no hole), or a hole a ring
    # larger than the model's converged one.
    (abs(hole / EXP_HOLE - 1) < 0.17, f"hole {hole:.2f} mm within 17 % of {EXP_HOLE}"),
    # LOOSE BOUND for the hole in the recovered plate (the remnant holding the plate's rim by
    # unbroken, untorn bonds, seen along the axis: tools/piekutowski.py). Since a failed member
    # leaves an intact particle's F (docs/particles-dm.md "Fracture") it is measured 20.33 mm
    # (+17.5 %) here at 4 µs but 16.33 and 15.53 mm (−5.6 %, −10.2 %) on the t/4 and t/6
    # quarters: at t/3 the plate is three layers and a lip particle's family 13–18 members, so
    # its lost members leave it with a one-sided family sooner (the isolated-particle rule
    # fails a third of the failed particles here, a sixth at t/6) and the lip opens ~2.5
    # spacings wider. 20 % (2.3 rings of width h on the diameter) admits that lattice; it fails
    # a plate that is not perforated or one whose bonds never break (6.9 mm), and the earlier
    # model's unzipping lip (t/6: 22.7 mm at 8 µs, +31 %). Before the change: 19.47 mm, 17 %.
    (abs(hole_rem / EXP_HOLE - 1) < 0.20, f"recovered plate's hole {hole_rem:.2f} mm within 20 % "
     f"of {EXP_HOLE}"),
    # the remnant is the holed plate: its rim in one piece, and its mass at least the lattice
    # outside its equal-area hole and at most 14 % more: measured +4.5 % (4.25 g against 4.07 g;
    # +9.0 % before a failed member left F: 4.58 g against 4.20 g, the
    # lip's material pushed outwards beyond the hole's radius and still attached: the hole is
    # measured at its innermost particles, the lip's mass lies outside them); a remnant that
    # keeps the failed lip (failed-failed bonds left unbroken: +18 %, 5.44 g, hole 17.2 mm) or
    # the whole plate (6.0 g), or misses a torn-off part, falls outside
    (m["rim_frac"] == 1.0 and holed < m["rem_mass"] < 1.14 * holed,
     f"remnant {m['rem_mass']:.4f} g within 0-14 % above the holed plate {holed:.4f} g "
     f"(the plate {plate:.4f} g), rim in one piece"),
    # the debris cloud's front (its fastest particle): the projectile's rear loses little speed
    # through a plate of t/D = 0.23 (measured 6.63 km/s = 0.99 v here, 7.9 km/s = 1.18 v at
    # t/4 and 8 µs: a few grains run ahead); a front slower than 0.85 v or faster than 1.25 v
    # is wrong
    (0.85 < m["v_edge"] / 6.7 < 1.25, f"leading edge {m['v_edge']:.3f} km/s"),
    # a back-spray exists and is a cone between the plate and the axis
    (m["back_mass"] > 0 and 10 < m["theta_v"] < 80, f"back-spray angle {m['theta_v']:.1f}"),
]
bad = [what for ok, what in checks if not ok]
if bad:
    sys.exit("test_piekutowski: FAILED: " + "; ".join(bad))
print("test_piekutowski: all checks passed")
