"""The outcome of a fit: :class:`FitResult` (values, 95 % intervals, noise, flags, identifiability) and its
summary and JSON forms."""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from tissuemech.compare.fit.diagnostics import RecordDiagnostics
from tissuemech.compare.fit.intervals import Identifiability
from tissuemech.compare.fit.model import PARAMETER_UNITS

__all__ = ["FitResult"]


@dataclass
class FitResult:
    """Outcome of :func:`relaxation`.

    params        best-fit values: C [Pa], alpha [-], beta(_m) [-], tau(_m) [s]
    intervals     95 % confidence interval (lo, hi) per parameter; an end at a search bound is the
                  physical limit (0 for alpha and beta), an unbounded end is 0 or inf; (nan, nan) when
                  no interval can be given (noise-free data)
    kinds         per parameter: "two-sided", "upper" (only an upper bound: "p < hi at 95 %"),
                  "lower" ("p > lo"), "none" (not identified), "n/a" (no interval)
    methods       per parameter: "wald" (Gauss-Newton ellipse confirmed by the profile), "profile"
                  (profile-likelihood ends), "bound", "n/a"
    residual      root-mean-square residual (Pa)
    noise         estimated noise standard deviation of each record (Pa)
    model_error   relative 1-sigma model-error term used (0: none)
    identifiability  :class:`Identifiability` (Fisher eigen-decomposition and ``report``)
    covariance    covariance of log-parameters (P x P) the intervals rest on (``errors``), model-error
                  factors marginalised; ``covariances`` the same under each error model considered
    diagnostics   per record: lag-1 autocorrelation and runs test of the residuals (:class:`RecordDiagnostics`)
    errors        the error model of the intervals ("robust" or "white", :mod:`.diagnostics`)
    discrepancy   estimated relative RMS size of each record's smooth discrepancy term (0: none found)
    correlation   per record: the residuals' lag-1 autocorrelation used for prewhitening (0 .. 0.97)
    wald_by_error_model  the Wald 95 % interval of each parameter under each error model (comparison studies)
    protocols, units  per record of :func:`~tissuemech.compare.fit.protocols.records_fit`: "relaxation", "creep" or
                  "history", and the unit of its observable and noise (Pa, m, N); empty: all relaxation (Pa)
    bins          per record: the number of bins it was fitted in (``compress=``; 0: sample by sample)
    success       True when the optimizer converged AND the intervals are usable (no flag below)
    flags         warnings that make intervals unusable or one-sided, in words
    message       optimizer message (and flags); ``nfev`` model evaluations of the final pass
    """

    params: dict[str, float]
    intervals: dict[str, tuple[float, float]]
    residual: float
    identifiability: Identifiability
    covariance: np.ndarray
    success: bool
    message: str
    nfev: int
    names: tuple[str, ...] = field(default=())
    kinds: dict[str, str] = field(default_factory=dict)
    methods: dict[str, str] = field(default_factory=dict)
    noise: tuple[float, ...] = field(default=())
    model_error: float = 0.0
    flags: tuple[str, ...] = field(default=())
    dof: int = 0
    model_error_factors: tuple[float, ...] = field(default=())
    diagnostics: tuple[RecordDiagnostics, ...] = field(default=())
    errors: str = "white"
    discrepancy: float = 0.0
    covariances: dict[str, np.ndarray] = field(default_factory=dict)
    correlation: tuple[float, ...] = field(default=())
    wald_by_error_model: dict[str, dict[str, tuple[float, float]]] = field(default_factory=dict)
    units: tuple[str, ...] = field(default=())
    protocols: tuple[str, ...] = field(default=())
    bins: tuple[int, ...] = field(default=())

    @property
    def report(self) -> str:
        return self.identifiability.report

    def interval_text(self, name: str) -> str:
        """The 95 % statement for one parameter in words: ``148.3 .. 152.6``, ``< 0.9``, ``> 3``,
        ``not identified`` or ``n/a``."""
        lo, hi = self.intervals[name]
        kind = self.kinds.get(name, "two-sided")
        if kind == "upper":
            return f"< {hi:.4g}"
        if kind == "lower":
            return f"> {lo:.4g}"
        if kind == "none":
            return "not identified"
        if kind == "n/a" or not (np.isfinite(lo) and np.isfinite(hi)):
            return "n/a"
        return f"{lo:.4g} .. {hi:.4g}"

    def summary(self) -> str:
        """Parameters with their 95 % intervals, the RMS residual, flags and the identifiability report."""
        lines = [f"{'parameter':>10} {'value':>12} {'95% lo':>12} {'95% hi':>12}  95% statement"]
        for n in self.names:
            lo, hi = self.intervals[n]
            unit = PARAMETER_UNITS[n.split("_")[0]]
            method = self.methods.get(n, "")
            lines.append(
                f"{n + ' [' + unit + ']':>10} {self.params[n]:12.5g} {lo:12.5g} {hi:12.5g}  "
                f"{n} {self.interval_text(n)}" + (f"  ({method})" if method else "")
            )
        if self.units:
            lines.append(f"RMS residual: {100 * self.residual:.3g} % of each record's peak")
            lines.append(
                "noise sd per record: "
                + ", ".join(f"{s:.3g} {u} ({k})" for s, u, k in zip(self.noise, self.units, self.protocols))
            )
        else:
            lines.append(f"RMS residual: {self.residual:.4g} Pa")
            if self.noise:
                lines.append("noise sd per record: " + ", ".join(f"{s:.3g}" for s in self.noise) + " Pa")
        if self.model_error:
            lines.append(f"model-error term: {100 * self.model_error:.3g} % (1 sigma, per record, on the force)")
        if self.errors == "robust":
            rho = ", ".join(f"{v:.2f}" for v in self.correlation)
            misfit = (
                f"a smooth model misfit (estimated {100 * self.discrepancy:.2g} % RMS per shape term) and "
                if self.discrepancy > 0
                else ""
            )
            lines.append(
                f"intervals allow for {misfit}correlated, uneven noise (lag-1 correlation used per record: {rho})"
                + ("" if self.discrepancy > 0 else "; no smooth model misfit found in the residuals")
            )
        elif self.errors != "white":
            lines.append(f"intervals: error model {self.errors!r}")
        for j, dg in enumerate(self.diagnostics):
            tag = "  <- not white noise" if dg.correlated else ""
            of = f" ({self.bins[j]} bin means)" if j < len(self.bins) and self.bins[j] else ""
            lines.append(f"residuals of record {j + 1}{of}: {dg.text()}{tag}")
        for f in self.flags:
            lines.append(f"WARNING: {f}")
        return "\n".join(lines) + "\n" + self.report

    def to_dict(self) -> dict[str, Any]:
        """Everything as plain JSON-ready types."""

        def num(v):
            v = float(v)
            return v if math.isfinite(v) else (None if math.isnan(v) else ("inf" if v > 0 else "-inf"))

        ident = self.identifiability
        return {
            "names": list(self.names),
            "params": {k: num(v) for k, v in self.params.items()},
            "intervals_95": {k: [num(a), num(b)] for k, (a, b) in self.intervals.items()},
            "interval_kinds": dict(self.kinds),
            "interval_methods": dict(self.methods),
            "interval_text": {n: self.interval_text(n) for n in self.names},
            "units": {n: PARAMETER_UNITS[n.split("_")[0]] for n in self.names},
            **(
                {
                    "protocols": list(self.protocols),
                    "rms_residual_rel": num(self.residual),
                    "noise_sd": [num(s) for s in self.noise],
                    "noise_units": list(self.units),
                }
                if self.units
                else {"rms_residual_Pa": num(self.residual), "noise_sd_Pa": [num(s) for s in self.noise]}
            ),
            "model_error_rel": num(self.model_error),
            "model_error_factors": [num(v) for v in self.model_error_factors],
            "errors": self.errors,
            "discrepancy_rel": num(self.discrepancy),
            "prewhitening_rho": [num(v) for v in self.correlation],
            "residual_diagnostics": [
                {
                    "n": d.n,
                    "lag1_autocorrelation": num(d.r1),
                    "runs": d.runs,
                    "runs_expected": num(d.runs_expected),
                    "runs_z": num(d.runs_z),
                    "runs_p": num(d.runs_p),
                }
                for d in self.diagnostics
            ],
            "covariance_log_by_error_model": {
                k: [[num(v) for v in row] for row in np.asarray(c)] for k, c in self.covariances.items()
            },
            "covariance_log": [[num(v) for v in row] for row in np.asarray(self.covariance)],
            "dof": int(self.dof),
            "bins": list(self.bins),
            "success": bool(self.success),
            "flags": list(self.flags),
            "message": self.message,
            "nfev": int(self.nfev),
            "identifiability": {
                "eigenvalues": [num(v) for v in ident.eigenvalues],
                "eigenvectors": [[num(v) for v in row] for row in ident.eigenvectors],
                "poorly": list(ident.poorly),
                "report": ident.report,
            },
        }
