"""One study: every curve through contact point, indentation history, the 1- and 2-branch fits, and the table.

Used by ``tissuemech afm`` and ``examples/afm_relaxation.py``: :func:`run` returns a :class:`Study`
whose :meth:`Study.report` is the printed table (per curve: contact, depth, creep, the fitted parameters with
95 % HAC intervals, diagnostics, AIC/BIC of two branches against one; then the spread across curves).
"""

from __future__ import annotations

import time
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from tissuemech.compare.afm.contact import ContactPoint, Indentation, find_contact, indentation
from tissuemech.compare.afm.fit import CurveFit, fit_curve, spread
from tissuemech.compare.afm.records import Curve

__all__ = ["Study", "run"]


@dataclass
class Study:
    """``contacts``, ``indentations``, ``one`` (1-branch fits), ``two`` (2-branch fits), per curve;
    ``seconds``: wall time of the fits (first fit of each model includes its compilation)."""

    contacts: list[ContactPoint]
    indentations: list[Indentation]
    one: list[CurveFit]
    two: list[CurveFit]
    seconds: float

    def report(self) -> str:
        """The table (module doc)."""
        g = self.one[0].geometry
        lines = [
            f"probe radius R_p = {g['probe_radius'] * 1e6:g} um, ball radius a0 = {g['radius'] * 1e6:g} um, "
            f"series radius R_s = {g['series_radius'] * 1e6:.4g} um; alpha fixed at 0 (not identifiable)",
            f"{'curve':>24} {'contact sd':>10} {'depth':>7} {'creep':>6} | 1 branch: {'C':>6} {'beta':>6} {'tau':>6} "
            f"{'rms':>5} {'lag1':>5} | 2 branches: {'C':>6} {'beta1':>6} {'tau1':>6} {'beta2':>6} {'tau2':>6} {'rms':>5} "
            f"{'lag1':>5} {'runs z':>6} | {'dAIC':>6} {'dBIC':>6}",
            f"{'':>24} {'(nm)':>10} {'(um)':>7} {'(nm)':>6} | {'':>9} {'(Pa)':>6} {'(-)':>6} {'(s)':>6} {'(nN)':>5} "
            f"{'':>5} | {'':>11} {'(Pa)':>6} {'(-)':>6} {'(s)':>6} {'(-)':>6} {'(s)':>6} {'(nN)':>5}",
        ]
        for c, ind, a, b in zip(self.contacts, self.indentations, self.one, self.two):
            p, q = a.params, b.params
            lines.append(
                f"{a.name:>24} {c.height_sd * 1e9:10.0f} {np.max(ind.approach) * 1e6:7.2f} {ind.creep * 1e9:6.0f} | "
                f"{'':>9} {p['C']:6.1f} {p['beta']:6.3f} {p['tau']:6.2f} {a.rms * 1e9:5.2f} {a.lag1:5.2f} | "
                f"{'':>11} {q['C']:6.1f} {q['beta_1']:6.3f} {q['tau_1']:6.2f} {q['beta_2']:6.3f} {q['tau_2']:6.2f} "
                f"{b.rms * 1e9:5.2f} {b.lag1:5.2f} {b.runs_z:6.1f} | {b.aic - a.aic:6.0f} {b.bic - a.bic:6.0f}"
            )
        lines.append("")
        lines.append("95 % intervals (HAC, Newey-West) of the 2-branch fit, curve by curve:")
        for b in self.two:
            lines.append(
                f"  {b.name}: "
                + ", ".join(f"{k} {lo:.4g}..{hi:.4g}" for k, (lo, hi) in b.intervals.items())
                + ("" if b.success else f"  [{b.message}]")
            )
        lines.append("")
        lines.append(f"spread across {len(self.one)} curves: median [quartiles] (min..max), coefficient of variation")
        for label, fits in (("1 branch", self.one), ("2 branches", self.two)):
            for k, s in spread(fits).items():
                lines.append(
                    f"  {label:>10} {k:>7}: {s['median']:.4g} [{s['q1']:.4g}, {s['q3']:.4g}] "
                    f"({s['min']:.4g}..{s['max']:.4g}), cv {100 * s['cv']:.1f} %"
                )
        n2 = sum(b.aic < a.aic for a, b in zip(self.one, self.two))
        m2 = sum(b.bic < a.bic for a, b in zip(self.one, self.two))
        lines.append(
            f"two branches preferred by AIC on {n2}/{len(self.one)} curves, by BIC on {m2}/{len(self.one)}; "
            f"median lag-1 autocorrelation of the residuals: 1 branch {np.median([a.lag1 for a in self.one]):.2f}, "
            f"2 branches {np.median([b.lag1 for b in self.two]):.2f}"
        )
        warm = [f.seconds for f in self.two[1:]] or [self.two[0].seconds]
        lines.append(
            f"fit time: {self.seconds:.1f} s in all; warm 2-branch fit {np.median(warm):.2f} s per curve (median)"
        )
        return "\n".join(lines)


def run(
    curves: Sequence[Curve], *, probe_radius: float, radius: float, n_hold: int = 240, window: float = 0.2
) -> Study:
    """Contact point, indentation history, and the 1- and 2-branch fits of every curve (module doc)."""
    start = time.perf_counter()
    contacts = [find_contact(c, window=window) for c in curves]
    inds = [indentation(c, cp) for c, cp in zip(curves, contacts)]
    one = [fit_curve(i, probe_radius=probe_radius, radius=radius, n_branches=1, n_hold=n_hold) for i in inds]
    two = []
    for i, a in zip(inds, one):
        p = a.params
        start2 = [p["C"], 0.7 * p["beta"], 0.4 * p["beta"], 0.4 * p["tau"], 2.5 * p["tau"]]
        two.append(fit_curve(i, probe_radius=probe_radius, radius=radius, n_branches=2, n_hold=n_hold, initial=start2))
    return Study(contacts, inds, one, two, time.perf_counter() - start)
