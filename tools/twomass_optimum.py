#!/usr/bin/env python3
"""Independent optimum of the two-mass log-magnitude fit on the bench recording
data/twomass-bench/multisine-a.csv.gz (the reference of the test
`ident::tests_measured::fit_reaches_the_independent_optimum`).

Written without beltune's code: numpy computes the FRF current -> motor angle
from the raw columns (per-period FFT of the reference current and of the
per-sample angle increment, averaged over periods 2..20, the integrator
z/(z-1) put back: Clary's method II, thesis (3.14)-(3.15)); the lines are those
with input power within 40 dB of the strongest; scipy minimizes the unweighted
sum of squared dB residuals of the exact two-mass transfer function (2.39)
torque -> motor angle (i_t = 1, belt damping d = 0, free Theta_e) over those
lines, with differential evolution over +-3 decades of every parameter and a
least-squares polish (trust-region reflective).

Run: python3 tools/twomass_optimum.py [--all-lines]   (numpy, scipy; seeded, deterministic)
"""
import csv
import gzip
import sys

import numpy as np
from scipy.optimize import differential_evolution, least_squares

PATH = "data/twomass-bench/multisine-a.csv.gz"
N = 2500
with gzip.open(PATH, "rt") as f:
    rows = list(csv.DictReader(f))
t = np.array([float(r["t_s"]) for r in rows])
u = np.array([float(r["iq_ref_A"]) for r in rows])
phi = np.array([float(r["theta_motor_rad"]) for r in rows])
ts = (t[-1] - t[0]) / (len(t) - 1)
v = np.diff(phi, prepend=np.nan)
v[0] = v[N]  # periodic steady state
P = len(u) // N
U = np.array([np.fft.rfft(u[p * N:(p + 1) * N]) for p in range(1, P)])
V = np.array([np.fft.rfft(v[p * N:(p + 1) * N]) for p in range(1, P)])
suu = (np.abs(U) ** 2).sum(0)
svu = (V * np.conj(U)).sum(0)
f = np.arange(N // 2 + 1) / (N * ts)
w = 2 * np.pi * f
z = np.exp(1j * w * ts)
with np.errstate(divide="ignore", invalid="ignore"):
    G = svu / suu * z / (z - 1)
usable = np.where((suu > suu[1:].max() * 1e-4) & (f > 0))[0]
# Figure 3.9: n_o = 150 log-spaced targets between the lowest and highest
# usable line, each replaced by the nearest usable line (in log f), repeats removed
targets = np.exp(np.linspace(np.log(f[usable[0]]), np.log(f[usable[-1]]), 150))
near = [usable[np.argmin(np.abs(np.log(f[usable]) - np.log(x)))] for x in targets]
subset = np.array(sorted(set(near)))
lines = usable if "--all-lines" in sys.argv else subset
mag_db = 20 * np.log10(np.abs(G[lines]))
s = 1j * w[lines]


def model_db(lp):
    je, m, c, dm, dc = np.exp(lp)
    num = m * s**2 + dc * s + c
    den = s * (m * je * s**3 + (m * dm + je * dc) * s**2 + (c * (je + m) + dm * dc) * s + c * (dc + dm))
    return 20 * np.log10(np.abs(num / den))


def res(lp):
    return mag_db - model_db(lp)


# scale from the rigid-body asymptote |G| ~ 1/(J w^2) on the lowest lines
J = np.median(1 / (np.abs(G[lines[:10]]) * w[lines[:10]] ** 2))
x0 = np.log([J / 2, J / 2, J / 2 * (2 * np.pi * 60) ** 2, J, J])
bounds = [(a - 3 * np.log(10), a + 3 * np.log(10)) for a in x0]
de = differential_evolution(lambda q: float(np.sum(res(q) ** 2)), bounds, seed=1, tol=1e-12,
                            maxiter=3000, popsize=40, polish=False)
ls = least_squares(res, de.x, method="trf", x_scale=1.0, xtol=1e-14, ftol=1e-14, gtol=1e-14)
je, m, c, dm, dc = np.exp(ls.x)
rms = np.sqrt(np.mean(ls.fun**2))
fz = np.sqrt(c / m) / (2 * np.pi)
fr = np.sqrt(c * (je + m) / (je * m)) / (2 * np.pi)
print(f"lines {len(lines)} ({f[lines[0]]:.0f}-{f[lines[-1]]:.0f} Hz), periods averaged {P - 1}, ts {ts}")
print(f"rms_db {rms:.4f}")
print(f"f_r_hz {fr:.4f} f_z_hz {fz:.4f} (undamped (2.44)/(2.45))")
print(f"theta_e {je:.6e} m_c {m:.6e} c {c:.6e} d_m {dm:.6e} d_c {dc:.6e}")
