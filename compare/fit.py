r"""Fit the lumped generalized-Maxwell spheroid model to compression-relaxation records.

Model (``reduced.spheroid``; SI units): for a ball of radius ``a0`` (m) pressed by a total approach
``delta(t)`` (m, linear ramp over ``ramp_time`` then held), the nominal stress is

    sigma~(t) = F(t) / A_mid(t),   F(t) = F_eq(delta(t); C, alpha) + sum_m q_m(t),
    dq_m/dt = -q_m / tau_m + beta_m dF_eq(delta(t))/dt,

with the Fung stiffness ``C`` (Pa), exponent ``alpha`` (-), energy factors ``beta_m`` (-) and
relaxation times ``tau_m`` (s).

Least squares in log-parameters ``theta = log p`` (every parameter stays positive; ``alpha`` is kept
in ``[1e-6, 10]``): minimise ``sum_k r_k(theta)^2`` with ``r = sigma~_model - sigma~_data`` over all
records, by ``scipy.optimize.least_squares`` (trust region) with the exact Jacobian ``jax.jacfwd``
through the diffrax model. Gauss-Newton covariance in log space

    Cov(theta) = s^2 (J^T J)^-1,   s^2 = RSS / (N - P),

gives 95 % intervals ``p exp(+-1.96 sd)``. The identifiability report is the eigen-decomposition of
the Fisher matrix ``J^T J / s^2`` in log space: an eigenvector ``v`` with eigenvalue ``lam`` says the
combination ``prod_i p_i^{v_i}`` is known to a relative standard deviation of about ``1/sqrt(lam)``.
With ONE compression level only ``F_eq(delta)`` is seen, so ``C`` and ``alpha`` trade off along one
direction (tiny eigenvalue, eigenvector mixing C and alpha); two or more levels separate them
(provided the equilibrium law depends on alpha; the small-strain Hertz law does not).
"""

from __future__ import annotations

import functools
import math
import re
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import Any, NamedTuple

import jax
import jax.numpy as jnp
import numpy as np

import tissuemech.reduced  # noqa: F401  (enables float64 in JAX)
from tissuemech.reduced.material import validate_positive

__all__ = ["Record", "FitResult", "Identifiability", "relaxation", "read_csv", "parameter_names", "Z95"]

Z95 = 1.959963984540054  # two-sided 95 % normal quantile
ALPHA_BOUNDS = (1e-6, 10.0)
BETA_BOUNDS = (1e-8, 1e4)
POOR_SD = 0.5  # a log-combination with standard deviation above this (a factor ~2.7 at 95 %) is "poor"


class Record(NamedTuple):
    """One compression level: ``time`` (s), ``nominal_stress`` (Pa), ``displacement`` (total approach, m)."""

    time: np.ndarray
    nominal_stress: np.ndarray
    displacement: float


@dataclass
class Identifiability:
    """Eigen-decomposition of the Gauss-Newton Fisher matrix in log-parameter space.

    eigenvalues   ascending (1 / variance of each log-combination)
    eigenvectors  columns, in the order of ``names``
    names         parameter names
    sd            standard deviation of each log-combination, 1/sqrt(eigenvalue)
    poorly        indices of the poorly determined combinations (sd > POOR_SD)
    report        human-readable summary
    """

    eigenvalues: np.ndarray
    eigenvectors: np.ndarray
    names: tuple[str, ...]
    sd: np.ndarray
    poorly: tuple[int, ...]
    report: str

    def combination(self, i: int, threshold: float = 0.01) -> str:
        """The i-th eigen-direction as a product of powers, e.g. ``C^0.71 * alpha^0.70``."""
        v = self.eigenvectors[:, i]
        v = v * np.sign(v[np.argmax(np.abs(v))])
        parts = [f"{n}^{c:+.3g}" for n, c in zip(self.names, v) if abs(c) >= threshold]
        return " * ".join(parts)

    def correlation(self) -> np.ndarray:
        """Correlation matrix of the log-parameters (from the pseudo-inverse Fisher matrix)."""
        lam, V = self.eigenvalues, self.eigenvectors
        cov = (V * _inverse_eigenvalues(lam)) @ V.T
        d = np.sqrt(np.abs(np.diag(cov)))
        return cov / np.outer(d, d)

    def mixes(self, a: str, b: str, threshold: float = 0.9) -> bool:
        """True if log(a) and log(b) are correlated beyond ``threshold`` (they trade off in the fit)
        and the weakest direction carries weight on both (|v| >= 0.01)."""
        ia, ib = self.names.index(a), self.names.index(b)
        v = self.eigenvectors[:, 0]
        return abs(self.correlation()[ia, ib]) >= threshold and abs(v[ia]) >= 0.01 and abs(v[ib]) >= 0.01


@dataclass
class FitResult:
    """Outcome of :func:`relaxation`.

    params        best-fit values: C [Pa], alpha [-], beta(_m) [-], tau(_m) [s]
    intervals     95 % confidence interval (lo, hi) per parameter (Gauss-Newton, log space)
    residual      root-mean-square residual (Pa)
    identifiability  :class:`Identifiability` (Fisher eigen-decomposition and ``report``)
    covariance    covariance of log-parameters (P x P)
    success       optimizer convergence flag; ``message`` its text; ``nfev`` evaluations
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

    @property
    def report(self) -> str:
        return self.identifiability.report

    def summary(self) -> str:
        """Parameters with their 95 % intervals, the RMS residual and the identifiability report."""
        lines = [f"{'parameter':>10} {'value':>12} {'95% lo':>12} {'95% hi':>12}"]
        for n in self.names:
            lo, hi = self.intervals[n]
            lines.append(f"{n + ' [' + _UNITS[n.split('_')[0]] + ']':>10} {self.params[n]:12.5g} {lo:12.5g} {hi:12.5g}")
        lines.append(f"RMS residual: {self.residual:.4g} Pa")
        return "\n".join(lines) + "\n" + self.report


_UNITS = {"C": "Pa", "alpha": "-", "beta": "-", "tau": "s"}


def parameter_names(n_branches: int = 1) -> tuple[str, ...]:
    """``(C, alpha, beta, tau)`` for one branch, ``(C, alpha, beta_1, .., tau_1, ..)`` for more."""
    if n_branches < 1:
        raise ValueError(f"n_branches must be at least 1; got {n_branches}")
    if n_branches == 1:
        return ("C", "alpha", "beta", "tau")
    return (
        ("C", "alpha")
        + tuple(f"beta_{m}" for m in range(1, n_branches + 1))
        + tuple(f"tau_{m}" for m in range(1, n_branches + 1))
    )


@functools.lru_cache(maxsize=1)
def _default_model() -> Callable:
    """reduced.spheroid.nominal_stress with forward-mode sensitivities (the fit uses jax.jacfwd);
    cached, so compiled residuals are reused between fits."""
    from tissuemech.reduced import spheroid

    return functools.partial(spheroid.nominal_stress, adjoint="forward")


def _as_records(records: Sequence[Any]) -> list[Record]:
    if isinstance(records, Record):
        records = [records]
    out = []
    for k, r in enumerate(records):
        try:
            t, s, d = r
        except (TypeError, ValueError):
            raise ValueError(f"record {k}: expected (time [s], nominal_stress [Pa], displacement [m])") from None
        t = np.asarray(t, dtype=float).ravel()
        s = np.asarray(s, dtype=float).ravel()
        if t.shape != s.shape or t.size < 2:
            raise ValueError(
                f"record {k}: time and nominal_stress need the same length (>= 2); got {t.size} and {s.size}"
            )
        if not (np.all(np.isfinite(t)) and np.all(np.isfinite(s))):
            raise ValueError(f"record {k}: time and stress must be finite numbers (found NaN or inf)")
        if np.any(t < 0):
            raise ValueError(f"record {k}: time must not be negative (s); got {t.min():g}")
        validate_positive(f"record {k}: displacement (the total approach of the plates)", d, "m")
        out.append(Record(t, s, float(d)))
    if not out:
        raise ValueError("at least one record (time, nominal_stress, displacement) is needed")
    return out


def initial_guess(records: Sequence[Record], radius: float, ramp_time: float, n_branches: int = 1) -> np.ndarray:
    """Rough starting point (in the order of :func:`parameter_names`) from the curves' shape.

    C from the Hertz law at the long-time stress (sigma_end ~ (32/3) C sqrt(a0) (delta/2)^1.5 / (pi a0^2)),
    alpha = 0.1, sum beta = peak/end - 1, tau's log-spaced over the hold.
    """
    ends, peaks, spans = [], [], []
    for r in records:
        hertz = (32.0 / 3.0) * math.sqrt(radius) * (r.displacement / 2.0) ** 1.5 / (math.pi * radius**2)
        tail = r.nominal_stress[-max(1, r.time.size // 20) :]
        ends.append(np.mean(tail) / hertz)
        peaks.append(np.max(r.nominal_stress) / max(np.mean(tail), 1e-300))
        spans.append(r.time.max())
    C0 = max(float(np.median(ends)), 1e-3)
    beta_tot = max(float(np.median(peaks)) - 1.0, 0.05)
    span = max(float(np.max(spans)) - ramp_time, 10 * ramp_time)
    taus = np.geomspace(span / 20.0, span / 3.0, n_branches) if n_branches > 1 else np.array([span / 8.0])
    betas = np.full(n_branches, beta_tot / n_branches)
    return np.concatenate([[C0, 0.1], betas, taus])


def _predict(theta, ts, ds, radius, ramp_time, model, equilibrium, nb):
    p = jnp.exp(theta)
    branches = [(p[2 + m], p[2 + nb + m]) for m in range(nb)]
    return [
        model(
            t,
            radius=radius,
            C=p[0],
            alpha=p[1],
            branches=branches,
            displacement=d,
            ramp_time=ramp_time,
            equilibrium=equilibrium,
        )
        for t, d in zip(ts, ds)
    ]


def _residual(theta, ts, ys, ds, scale, radius, ramp_time, model, equilibrium, nb):
    pred = _predict(theta, ts, ds, radius, ramp_time, model, equilibrium, nb)
    return jnp.concatenate([(m - y) / scale for m, y in zip(pred, ys)])


_STATIC = ("radius", "ramp_time", "model", "equilibrium", "nb")
_residual_jit = jax.jit(_residual, static_argnames=_STATIC)
_jacobian_jit = jax.jit(jax.jacfwd(_residual), static_argnames=_STATIC)


def _builder(records, radius, ramp_time, n_branches, equilibrium, model):
    """residual(theta) and its jacfwd Jacobian (theta = log params), jit-compiled once per model,
    equilibrium and record shapes (records enter as arguments, so a refit of new data of the same
    shape does not recompile). Unhashable equilibria (arrays) are closed over instead."""
    args = (
        tuple(jnp.asarray(r.time) for r in records),
        tuple(jnp.asarray(r.nominal_stress) for r in records),
        tuple(jnp.asarray(r.displacement) for r in records),
    )
    scale = float(max(np.max(np.abs(r.nominal_stress)) for r in records)) or 1.0
    rest = (jnp.asarray(scale), float(radius), float(ramp_time))  # geometry static (Python floats)
    try:
        hash(equilibrium)
        kw = dict(model=model, equilibrium=equilibrium, nb=n_branches)
        return (
            lambda th: _residual_jit(th, *args, *rest, **kw),
            lambda th: _jacobian_jit(th, *args, *rest, **kw),
            scale,
        )
    except TypeError:
        f = lambda th: _residual(th, *args, *rest, model, equilibrium, n_branches)
        return jax.jit(f), jax.jit(jax.jacfwd(f)), scale


def _inverse_eigenvalues(lam: np.ndarray) -> np.ndarray:
    """1/lambda with a relative floor (1e-16 of the largest): a null direction gets a huge but finite
    variance, so it does not leak round-off into the well-determined parameters."""
    floor = max(float(np.max(lam)), 1e-300) * 1e-16
    return 1.0 / np.maximum(lam, floor)


def _identifiability(J: np.ndarray, s2: float, names: tuple[str, ...]) -> Identifiability:
    fisher = J.T @ J / s2
    lam, V = np.linalg.eigh(fisher)
    lam = np.maximum(lam, 0.0)
    with np.errstate(divide="ignore"):
        sd = 1.0 / np.sqrt(lam)
    poorly = tuple(int(i) for i in np.nonzero(sd > POOR_SD)[0])
    ident = Identifiability(lam, V, names, sd, poorly, "")
    lines = ["Identifiability (Fisher matrix in log-parameters; each row a combination prod p_i^v_i):"]
    for i in range(len(lam)):
        tag = "POORLY determined" if i in poorly else "well determined"
        rel = f"+-{100 * (math.exp(Z95 * sd[i]) - 1):.3g} %" if np.isfinite(sd[i]) and sd[i] < 20 else "unbounded"
        lines.append(f"  {ident.combination(i):<45} eigenvalue {lam[i]:10.3e}  95% factor {rel:>12}  {tag}")
    if poorly:
        weak = [ident.combination(i) for i in poorly]
        lines.append("  -> the data cannot separate the parameters along: " + "; ".join(weak) + ".")
        if "C" in names and "alpha" in names and ident.mixes("C", "alpha"):
            lines.append(
                "  -> C and alpha trade off: one compression level only fixes the equilibrium force "
                "F_eq(delta) (a single combination of C and alpha). Add records at two or more "
                "compression levels (or resolve the loading ramp) to identify them separately."
            )
    else:
        lines.append("  -> all parameters are identified by these records.")
    ident.report = "\n".join(lines)
    return ident


def relaxation(
    records: Sequence[Any],
    *,
    radius: float,
    ramp_time: float,
    n_branches: int = 1,
    equilibrium: Any = "fem",
    initial: dict[str, float] | Sequence[float] | None = None,
    model: Callable | None = None,
    max_nfev: int = 200,
) -> FitResult:
    r"""Fit ``(C, alpha, beta_m, tau_m)`` to compression-relaxation records by least squares.

    records      list of ``(time [s], nominal_stress [Pa], displacement [m])``, one per compression
                 level (``displacement`` is the total plate approach reached at the end of the ramp).
    radius       reference ball radius a0 (m); ramp_time the loading ramp duration (s).
    n_branches   number of Maxwell branches (parameters ``beta``, ``tau`` or ``beta_1.., tau_1..``).
    equilibrium  the equilibrium law passed to the model ("hertz", a master-curve table, a callable).
    initial      optional starting values (dict by name, or a sequence in :func:`parameter_names` order).
    model        ``model(t, *, radius, C, alpha, branches, displacement, ramp_time, equilibrium)`` ->
                 nominal stress (Pa), JAX-traceable; default ``reduced.spheroid.nominal_stress``.

    Minimises sum_k (sigma_model(t_k) - sigma_k)^2 over theta = log(params) with the exact JAX
    Jacobian; returns a :class:`FitResult` with 95 % intervals and the identifiability report.
    """
    recs = _as_records(records)
    validate_positive("radius (of the spheroid)", radius, "m")
    validate_positive("ramp_time (duration of the loading ramp)", ramp_time, "s")
    names = parameter_names(n_branches)
    model = _default_model() if model is None else model
    if initial is None:
        p0 = initial_guess(recs, radius, ramp_time, n_branches)
    elif isinstance(initial, dict):
        guess = initial_guess(recs, radius, ramp_time, n_branches)
        p0 = np.array([float(initial.get(n, g)) for n, g in zip(names, guess)])
    else:
        p0 = np.asarray(initial, dtype=float)
        if p0.shape != (len(names),):
            raise ValueError(f"initial needs {len(names)} values in the order {names}; got {p0.size}")
    if np.any(p0 <= 0) or not np.all(np.isfinite(p0)):
        raise ValueError(f"initial values must be positive and finite; got {dict(zip(names, p0))}")
    lo = np.full(len(names), -np.inf)
    hi = np.full(len(names), np.inf)
    lo[1], hi[1] = np.log(ALPHA_BOUNDS[0]), np.log(ALPHA_BOUNDS[1])
    lo[2 : 2 + n_branches], hi[2 : 2 + n_branches] = np.log(BETA_BOUNDS[0]), np.log(BETA_BOUNDS[1])
    theta0 = np.clip(np.log(p0), lo + 1e-9, hi - 1e-9)

    res_fn, jac_fn, scale = _builder(recs, float(radius), float(ramp_time), n_branches, equilibrium, model)
    from scipy.optimize import least_squares

    def fun(th):
        r = np.asarray(res_fn(jnp.asarray(th)))
        if not np.all(np.isfinite(r)):
            return np.full_like(r, 1e6)  # steer the trust region away from failed model evaluations
        return r

    def jac(th):
        return np.asarray(jac_fn(jnp.asarray(th)))

    if not np.all(np.isfinite(np.asarray(res_fn(jnp.asarray(theta0))))):
        raise RuntimeError(
            f"the model returned NaN/inf at the starting point {dict(zip(names, p0))}. "
            "Hint: give initial=... closer to the data, or check units (m, Pa, s)."
        )
    sol = least_squares(
        fun,
        theta0,
        jac=jac,
        bounds=(lo, hi),
        method="trf",
        x_scale="jac",
        xtol=1e-12,
        ftol=1e-12,
        gtol=1e-12,
        max_nfev=max_nfev,
    )
    theta = sol.x
    r = sol.fun * scale
    J = jac(theta) * scale
    n, P = r.size, len(names)
    s2 = float(r @ r) / max(n - P, 1)
    s2 = max(s2, 1e-300)
    ident = _identifiability(J, s2, names)
    at_bound = [nm for nm, th, a, b in zip(names, theta, lo, hi) if min(th - a, b - th) < 1e-6]
    if at_bound:
        ident.report += (
            "\n  -> at a bound of the search: "
            + ", ".join(at_bound)
            + f" (alpha in {ALPHA_BOUNDS}, beta in {BETA_BOUNDS}); e.g. alpha at 1e-6 means the "
            "data are consistent with a neo-Hookean law (alpha = 0)."
        )
    if not sol.success:
        ident.report += f"\n  -> the optimizer did not converge: {sol.message}"
    lam, V = ident.eigenvalues, ident.eigenvectors
    cov = (V * _inverse_eigenvalues(lam)) @ V.T
    with np.errstate(over="ignore", invalid="ignore"):
        sd = np.sqrt(np.abs(np.diag(cov)))
        p = np.exp(theta)
        intervals = {
            nm: (float(p[i] * np.exp(-Z95 * sd[i])), float(p[i] * np.exp(Z95 * sd[i]))) for i, nm in enumerate(names)
        }
    return FitResult(
        params={nm: float(v) for nm, v in zip(names, p)},
        intervals=intervals,
        residual=float(np.sqrt(np.mean(r**2))),
        identifiability=ident,
        covariance=cov,
        success=bool(sol.success),
        message=str(sol.message),
        nfev=int(sol.nfev),
        names=names,
    )


def read_csv(path: str, *, displacement: float, time_column: str | int = 0, stress_column: str | int = 1) -> Record:
    """Read a relaxation record from a CSV file: a time column (s) and a nominal-stress column (Pa).

    A header line is optional (columns may then be chosen by name); ``displacement`` is the total
    plate approach in m. Returns a :class:`Record` ready for :func:`relaxation`.
    """
    import pandas as pd

    validate_positive("displacement (the total approach of the plates)", displacement, "m")
    with open(path) as fh:
        first = fh.readline()
    try:
        # a first line of numbers only (comma, semicolon, tab or space separated) is data, not a header
        cells = [x for x in re.split(r"[,;\s]+", first.strip()) if x]
        if not cells:
            raise ValueError
        [float(x) for x in cells]
        header = None
    except ValueError:
        header = 0
    df = pd.read_csv(path, header=header, sep=None, engine="python")
    try:
        t = df[time_column] if not isinstance(time_column, int) else df.iloc[:, time_column]
        s = df[stress_column] if not isinstance(stress_column, int) else df.iloc[:, stress_column]
    except (KeyError, IndexError):
        raise ValueError(
            f"{path}: columns {time_column!r}/{stress_column!r} not found; it has {list(df.columns)}"
        ) from None
    try:
        t = np.asarray(t, dtype=float)
        s = np.asarray(s, dtype=float)
    except ValueError:
        raise ValueError(f"{path}: time (s) and stress (Pa) columns must be numbers") from None
    return _as_records([(t, s, displacement)])[0]
