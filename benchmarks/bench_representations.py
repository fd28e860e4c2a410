"""Timings of simulate and inistate at T = 1e6 against a Python loop, python-control and scipy
(python benchmarks/bench_representations.py; see literate/10-representations.md, Simulation)."""
import time

import control
import numpy as np
import scipy.signal as sig

from ident.representations import inistate, kernel_to_ss, random_system, simulate, ss_to_kernel

T = 10**6


def best(f, rep=3):
    ts = []
    for _ in range(rep):
        t = time.perf_counter()
        f()
        ts.append(time.perf_counter() - t)
    return min(ts), max(ts)


def loop_sim(A, B, C, D, u, x0):
    x, Y = x0.copy(), np.empty((u.shape[0], C.shape[0]))
    for t in range(u.shape[0]):
        Y[t] = C @ x + D @ u[t]
        x = A @ x + B @ u[t]
    return Y


rng = np.random.default_rng(0)
print(f"T = {T:.0e}; times in s as (best, worst) of 3")
for m, p, ell, rad in [(1, 1, 4, (0.3, 0.95)), (1, 1, 4, (0.995, 0.9999)), (2, 2, 2, (0.3, 0.95)),
                       (0, 1, 4, (0.3, 0.95)), (1, 4, 1, (0.3, 0.95)), (2, 2, 5, (0.3, 0.95))]:
    s = random_system(m, p, ell, rng, radius=rad)
    u, x0 = rng.standard_normal((T, m)), rng.standard_normal(ell * p)
    y = simulate(s, u, x0)
    ts, ti = best(lambda: simulate(s, u, x0)), best(lambda: inistate(u, y, s))
    Tl = 10**5
    yl = loop_sim(s.A, s.B, s.C, s.D, u[:Tl], x0)
    err = np.abs(yl - y[:Tl]).max() / np.abs(yl).max()
    xerr = np.abs(inistate(u, y, s) - x0).max()
    print(f"m={m} p={p} n={ell * p} |eig| in {rad}: simulate {ts[0]:.3f}/{ts[1]:.3f}, "
          f"inistate {ti[0]:.3f}/{ti[1]:.3f}; rel. err vs loop {err:.1e}, x0 err {xerr:.1e}")

# ill-conditioned case: observer form (||A|| ~ 8e3) of a system with cond(O_ell) ~ 1e5
r2 = np.random.default_rng(2129)
m, p, ell = (int(r2.integers(0, k)) for k in (4, 4, 5))
s = random_system(m, p, ell, r2)
obs = kernel_to_ss(ss_to_kernel(s), m, ell)
u = rng.standard_normal((T, m))
y = simulate(s, u)
t = best(lambda: simulate(obs, u))
err = np.abs(simulate(obs, u) - y).max() / np.abs(y).max()
print(f"observer form, m={m} p={p} n={ell * p}, ||A|| = {np.linalg.norm(obs.A, 2):.0f}: simulate "
      f"{t[0]:.3f}/{t[1]:.3f}, rel. err vs the well-conditioned realisation {err:.1e}")

s = random_system(1, 1, 4, rng)
u, x0 = rng.standard_normal((T, 1)), rng.standard_normal(4)
Tl = 10**5
t_loop = best(lambda: loop_sim(s.A, s.B, s.C, s.D, u[:Tl], x0), 1)[0] * T / Tl
t_ctrl = best(lambda: control.forced_response(s, T=np.arange(Tl), U=u[:Tl, 0], X0=x0), 1)[0] * T / Tl
t_dlsim = best(lambda: sig.dlsim((s.A, s.B, s.C, s.D, 1), u[:Tl], x0=x0), 1)[0] * T / Tl
b, a = sig.ss2tf(s.A, s.B, s.C, s.D)
t_lf = best(lambda: sig.lfilter(b[0], a, u[:, 0]))[0]
print(f"baselines (m=p=1, n=4, extrapolated from 1e5): python loop {t_loop:.2f}, "
      f"control.forced_response {t_ctrl:.2f}, scipy dlsim {t_dlsim:.2f}; "
      f"lfilter (SISO tf, zero state) {t_lf:.3f}")
