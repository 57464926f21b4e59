"""How accurate is the lumped spheroid force's exact-kernel quadrature for stiff branches? (Hertz law.)

``python -m tissuemech.compare.bench stiff-kernel`` (or ``tissuemech bench stiff-kernel``)

``reduced.spheroid.force`` (method "quadrature", Hertz equilibrium, C = 150 Pa, a0 = 500 um, 10 %
approach in a 0.2 s ramp, one branch beta = 3, the largest of ``tests/test_properties.py``'s range:
the relative error grows with beta) at t = 0.05, 0.1, 0.2, 0.3 and 2 s, against the exact force
F_eq + beta int_0^t e^{-(t-s)/tau} dF_eq/ds ds, whose integral is tau^1.5 (sqrt(X) - D(sqrt(X))) with
X = min(t, t_r)/tau and D Dawson's integral (``scipy.special.dawsn``), and by ``scipy.integrate.quad``
(epsrel 1e-13) where that form cancels (X < 0.1). Scans tau / t_r over [1e-4, 1e3] (701 values, log
spaced) and prints the largest relative error per decade and overall.
"""

from __future__ import annotations

import sys

import numpy as np
from scipy.integrate import quad
from scipy.special import dawsn

import tissuemech.reduced.spheroid as sp

A0, C, TR, X_APP, BETA = 500e-6, 150.0, 0.2, 0.1, 3.0
T = np.array([0.05, 0.1, 0.2, 0.3, 2.0])


def exact(t: float, tau: float) -> float:
    """The exact force (N) at time t (s) for the branch (BETA, tau)."""
    te = min(t, TR)
    k = C * A0**2 * 16.0 * np.sqrt(X_APP / TR) * X_APP / TR  # dF_eq/ds = k sqrt(s)
    X = te / tau
    if X >= 0.1:
        integral = tau**1.5 * (np.sqrt(X) - dawsn(np.sqrt(X)))
    else:
        integral = quad(lambda s: np.exp(-(te - s) / tau) * np.sqrt(s), 0.0, te, epsabs=0, epsrel=1e-13, limit=200)[0]
    return C * A0**2 * (32.0 / 3.0) * (X_APP * te / TR) ** 1.5 + BETA * k * integral * np.exp(-(t - te) / tau)


def main(argv: list[str] | None = None) -> int:
    print("nodes: Gauss-Legendre in zeta = sqrt(eta) (the rule in use)")
    ratios = np.logspace(-4, 3, 701)
    errs = []
    for r in ratios:
        tau = TR * r
        F = np.asarray(
            sp.force(
                T, radius=A0, C=C, alpha=0.2, branches=[(BETA, tau)], displacement=2 * A0 * X_APP, ramp_time=TR,
                equilibrium="hertz",
            )
        )  # fmt: skip
        errs.append(max(abs(Fi / exact(ti, tau) - 1.0) for ti, Fi in zip(T, F)))
    errs_a = np.array(errs)
    for lo in range(-4, 3):
        sel = (ratios >= 10.0**lo) & (ratios <= 10.0 ** (lo + 1))
        print(f"tau / t_r in [1e{lo}, 1e{lo + 1}]: largest |F / F_exact - 1| = {errs_a[sel].max():.1e}")
    i = int(np.argmax(errs_a))
    print(f"overall: {errs_a[i]:.2e} at tau / t_r = {ratios[i]:.3g}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main(sys.argv[1:]))
