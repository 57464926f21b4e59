r"""Fit the lumped generalized-Maxwell spheroid model to compression-relaxation records.

Model (``reduced.spheroid``; SI units): for a ball of radius ``a0`` (m) pressed by a total approach
``delta(t)`` (m, linear ramp over ``ramp_time`` then held), the nominal stress is

    sigma~(t) = F(t) / A_mid(t),   F(t) = F_eq(delta(t); C, alpha) + sum_m q_m(t),
    dq_m/dt = -q_m / tau_m + beta_m dF_eq(delta(t))/dt,

with the Fung stiffness ``C`` (Pa), exponent ``alpha`` (-), energy factors ``beta_m`` (-) and
relaxation times ``tau_m`` (s).

Statistical model
-----------------
Record j (one compression level) is  y_jk = m_jk(theta) (1 + e_j) + s_j eps_jk  with white Gaussian
noise eps of unknown standard deviation ``s_j`` (Pa, estimated per record, so records of different
stress levels are weighted by their own noise) and an optional **model-error** factor
e_j ~ N(0, model_error^2): a relative error of the equilibrium law common to the whole record (a
mis-tabulated F_eq at that compression scales the elastic and the viscous force alike). The e_j are
nuisance parameters with a Gaussian prior, estimated jointly and marginalised in the covariance. By
default (``model_error="auto"``) the FE master table's own error estimate is used (metadata key
``model_error_rel``, relative 1-sigma error of the equilibrium force; :data:`DEFAULT_MODEL_ERROR_REL`
when the table lacks it); for ``"hertz"``, a user table or a callable the law is taken as exact (0).

Estimation: weighted least squares in log-parameters ``theta = log p`` (all positive; ``alpha`` kept
in ``[1e-6, alpha_max]``, alpha_max = the table's upper alpha for table laws, else 10), by
``scipy.optimize.least_squares`` (trust region) with the exact Jacobian ``jax.jacfwd`` through the
JAX model: an unweighted pass, the per-record noise estimate s_j^2 = RSS_j / (n_j - P n_j / N), a
weighted pass.

Intervals (95 %): the Gauss-Newton (Wald) interval ``theta_i +- t sd_i`` is checked against the
profile likelihood: at each Wald end the other parameters are re-optimised, and if the rise of the
chi-square there is not within 10 % of ``t^2`` (t the 97.5 % Student quantile with N - P degrees of
freedom) the end is replaced by the root of the profile (``chi2_profile(theta_i) - chi2_min = t^2``,
Brent). A profile that stays below ``t^2`` up to a search bound gives a one-sided interval (e.g.
alpha in [0, 0.9]: "alpha < 0.9 at 95 %"), one that stays below it without bound an open end (inf).
Records without information raise ValueError (fewer points than parameters, constant or
non-positive stress); round-off-level residuals (noise-free data) and a model that does not depend
on a parameter are flagged, with NaN or full-range intervals instead of zero widths. Records that scatter
about the model by less than the equilibrium table's own stated accuracy (metadata ``model_error_rel``; noise
sd below that fraction of the record's peak) are flagged too (``success`` False): their residuals are then the
records' own discretisation error and the model's rather than noise (noise-free FE-made records: the fit
moves alpha to absorb the mesh's error and the intervals shrink below that bias).

Identifiability: the eigen-decomposition of the (model-error-marginalised) Fisher matrix in log
space: an eigenvector ``v`` with eigenvalue ``lam`` says the combination ``prod_i p_i^{v_i}`` is known
to a relative standard deviation of about ``1/sqrt(lam)``. With ONE compression level only
``F_eq(delta)`` is seen, so ``C`` and ``alpha`` trade off along one direction (tiny eigenvalue,
eigenvector mixing C and alpha); two or more levels separate them (provided the equilibrium law
depends on alpha; the small-strain Hertz law does not).
"""

from __future__ import annotations

import functools
import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import Any, NamedTuple

import jax
import jax.numpy as jnp
import numpy as np

import tissuemech.reduced  # noqa: F401  (enables float64 in JAX)
from tissuemech.reduced.material import validate_positive

__all__ = [
    "Record",
    "FitResult",
    "Identifiability",
    "relaxation",
    "read_csv",
    "parameter_names",
    "check_record",
    "model_error_of",
    "Z95",
    "DEFAULT_MODEL_ERROR_REL",
]

Z95 = 1.959963984540054  # two-sided 95 % normal quantile
ALPHA_BOUNDS = (1e-6, 10.0)
BETA_BOUNDS = (1e-8, 1e4)
# tau is searched within TAU_SPAN = (1e-3 ramp times, 1e3 times the last record time): beyond either end a branch is
# indistinguishable in the records from one at that end (relaxed within the ramp's start / not relaxing during the
# records: extra permanent stiffness), and an unbounded search ran tau to 1e302 s on records that do not relax
TAU_SPAN = (1e-3, 1e3)
POOR_SD = 0.5  # a log-combination with standard deviation above this (a factor ~2.7 at 95 %) is "poor"
DEFAULT_MODEL_ERROR_REL = 0.005  # 1-sigma relative error of F_eq assumed for a table without `model_error_rel`
NOISE_FREE_REL = 1e-9  # RMS residual below this fraction of the record's peak: noise-free (synthetic) data
WALD_TOL = 0.10  # accept a Wald end when the profile chi-square rise there is within 10 % of t^2
LOG_SPAN = 12.0  # profile search at most e^12 away from the estimate (beyond: unbounded)


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
    covariance    covariance of log-parameters (P x P), model-error factors marginalised
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
            unit = _UNITS[n.split("_")[0]]
            method = self.methods.get(n, "")
            lines.append(
                f"{n + ' [' + unit + ']':>10} {self.params[n]:12.5g} {lo:12.5g} {hi:12.5g}  "
                f"{n} {self.interval_text(n)}" + (f"  ({method})" if method else "")
            )
        lines.append(f"RMS residual: {self.residual:.4g} Pa")
        if self.noise:
            lines.append("noise sd per record: " + ", ".join(f"{s:.3g}" for s in self.noise) + " Pa")
        if self.model_error:
            lines.append(f"model-error term: {100 * self.model_error:.3g} % (1 sigma, per record, on the force)")
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
            "units": {n: _UNITS[n.split("_")[0]] for n in self.names},
            "rms_residual_Pa": num(self.residual),
            "noise_sd_Pa": [num(s) for s in self.noise],
            "model_error_rel": num(self.model_error),
            "model_error_factors": [num(v) for v in self.model_error_factors],
            "covariance_log": [[num(v) for v in row] for row in np.asarray(self.covariance)],
            "dof": int(self.dof),
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
        if t.shape != s.shape:
            raise ValueError(f"record {k}: time and nominal_stress need the same length; got {t.size} and {s.size}")
        if t.size < 2:
            raise ValueError(f"record {k}: {t.size} sample; a record needs at least 2 (time, stress) samples")
        if not (np.all(np.isfinite(t)) and np.all(np.isfinite(s))):
            raise ValueError(f"record {k}: time and stress must be finite numbers (found NaN or inf)")
        if np.any(t < 0):
            raise ValueError(f"record {k}: time must not be negative (s); got {t.min():g}")
        validate_positive(f"record {k}: displacement (the total approach of the plates)", d, "m")
        out.append(Record(t, s, float(d)))
    if not out:
        raise ValueError("at least one record (time, nominal_stress, displacement) is needed")
    return out


def _check_information(recs: Sequence[Record], names: tuple[str, ...]) -> None:
    """ValueError for records that cannot determine the parameters (one line, naming the record)."""
    for k, r in enumerate(recs):
        check_record(r, f"record {k}")
    n = sum(r.time.size for r in recs)
    if n <= len(names):
        raise ValueError(
            f"the records hold {n} data points in all, not more than the {len(names)} parameters "
            f"{names}: at least {len(names) + 1} are needed (more for a noise estimate worth having)"
        )


def check_record(r: Any, what: str = "record") -> None:
    """ValueError (one line, starting with ``what``: a record number, a file name) for one record that cannot
    inform the fit: fewer than 2 samples, all at one time, a constant or non-positive nominal stress. ``r``: a
    :class:`Record` or a ``(time [s], nominal_stress [Pa], displacement [m])`` tuple."""
    if not isinstance(r, Record):
        try:
            r = _as_records([r])[0]
        except ValueError as e:
            raise ValueError(f"{what}: {str(e).removeprefix('record 0: ')}") from None
    if np.ptp(r.time) == 0:
        raise ValueError(f"{what}: all {r.time.size} samples are at the same time ({r.time[0]:g} s)")
    if np.ptp(r.nominal_stress) == 0:
        raise ValueError(
            f"{what}: the nominal stress is constant ({r.nominal_stress[0]:g} Pa at all "
            f"{r.time.size} times): no information on the parameters"
        )
    if np.max(r.nominal_stress) <= 0 or np.mean(r.nominal_stress) <= 0:
        raise ValueError(
            f"{what}: the nominal stress must be positive in compression (Pa); its mean is "
            f"{np.mean(r.nominal_stress):g} Pa (negate data recorded tension-positive)"
        )


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


def _table(equilibrium: Any):
    """The master-curve object behind an equilibrium spec ("fem", a MasterCurve or a FEMTable), else None."""
    from tissuemech.reduced import spheroid

    if isinstance(equilibrium, str) and equilibrium == "fem":
        return spheroid.master_curve()
    if isinstance(equilibrium, spheroid.MasterCurve):
        return equilibrium
    if isinstance(equilibrium, spheroid.FEMTable):
        return equilibrium.master
    return None


def model_error_of(equilibrium: Any) -> float:
    """The relative 1-sigma model error of an equilibrium law's force (the ``"auto"`` choice).

    For the FE master table ("fem" or a MasterCurve): its metadata ``model_error_rel``, else
    :data:`DEFAULT_MODEL_ERROR_REL`. For "hertz", an (x, f) table or a callable: 0 (taken as exact;
    pass ``model_error=`` to :func:`relaxation` to add one).
    """
    if _table(equilibrium) is None:
        return 0.0
    v = _stated_accuracy(equilibrium)
    return DEFAULT_MODEL_ERROR_REL if v is None else v


def _stated_accuracy(equilibrium: Any) -> float | None:
    """The equilibrium table's own stated accuracy (metadata ``model_error_rel``, relative, >= 0), or None where
    the law is no table or states none. ``relaxation`` flags records that scatter about the model by less than
    it: they carry no noise the intervals could rest on."""
    mc = _table(equilibrium)
    if mc is None:
        return None
    try:
        v = float(mc.metadata.get("model_error_rel"))
    except (TypeError, ValueError):
        return None
    return v if math.isfinite(v) and v >= 0 else None


def _inverse_eigenvalues(lam: np.ndarray) -> np.ndarray:
    """1/lambda with a relative floor (1e-16 of the largest): a null direction gets a huge but finite
    variance, so it does not leak round-off into the well-determined parameters."""
    floor = max(float(np.max(lam)), 1e-300) * 1e-16
    return 1.0 / np.maximum(lam, floor)


def _identifiability(fisher: np.ndarray, names: tuple[str, ...], dead: Sequence[int] = ()) -> Identifiability:
    """Eigen-decomposition of the log-space Fisher matrix (already in units of the noise)."""
    lam, V = np.linalg.eigh(0.5 * (fisher + fisher.T))
    lam = np.where(lam > 1e-13 * max(float(np.max(lam)), 1e-300), lam, 0.0)
    with np.errstate(divide="ignore"):
        sd = 1.0 / np.sqrt(lam)
    poorly = tuple(int(i) for i in np.nonzero(sd > POOR_SD)[0])
    ident = Identifiability(lam, V, names, sd, poorly, "")
    lines = ["Identifiability (Fisher matrix in log-parameters; each row a combination prod p_i^v_i):"]
    for i in range(len(lam)):
        tag = "POORLY determined" if i in poorly else "well determined"
        rel = f"+-{100 * (math.exp(Z95 * sd[i]) - 1):.3g} %" if np.isfinite(sd[i]) and sd[i] < 20 else "unbounded"
        lines.append(f"  {ident.combination(i):<45} eigenvalue {lam[i]:10.3e}  95% factor {rel:>12}  {tag}")
    for i in dead:
        lines.append(
            f"  -> the model does not depend on {names[i]} at the estimate (alpha with equilibrium='hertz'; a "
            "relaxation time whose branch has vanished, beta -> 0, as in records that do not relax): "
            "it is not identified by these data."
        )
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


class _Problem:
    """Weighted residuals of the statistical model in z = (theta (P), eta (R, model-error factors))."""

    def __init__(self, recs, res_fn, jac_fn, scale, P, eps):
        self.res_fn, self.jac_fn, self.scale = res_fn, jac_fn, scale
        self.y = np.concatenate([r.nominal_stress for r in recs])
        self.idx = np.concatenate([np.full(r.time.size, j) for j, r in enumerate(recs)])
        self.R, self.P, self.eps = len(recs), P, float(eps)
        self.nz = P + (self.R if self.eps > 0 else 0)
        self.sig = np.full(self.y.size, scale)  # per-point noise sd (Pa), set by set_noise

    def model(self, th: np.ndarray) -> np.ndarray:
        return np.asarray(self.res_fn(jnp.asarray(th))) * self.scale + self.y

    def factor(self, z: np.ndarray) -> np.ndarray | float:
        return np.exp(z[self.P :])[self.idx] if self.eps > 0 else 1.0

    def data_residual(self, z: np.ndarray) -> np.ndarray:
        """Model minus data (Pa), model-error factors applied."""
        return self.model(z[: self.P]) * self.factor(z) - self.y

    def resid(self, z: np.ndarray) -> np.ndarray:
        r = self.data_residual(z) / self.sig
        if self.eps > 0:
            r = np.concatenate([r, z[self.P :] / self.eps])
        return r

    def jac(self, z: np.ndarray) -> np.ndarray:
        th = jnp.asarray(z[: self.P])
        f = self.factor(z)
        Jm = np.asarray(self.jac_fn(th)) * self.scale  # d model / d theta (Pa)
        J = Jm * (f / self.sig)[:, None]
        if self.eps > 0:
            m = self.model(z[: self.P])
            Je = np.zeros((self.y.size, self.R))
            Je[np.arange(self.y.size), self.idx] = m * f / self.sig
            J = np.vstack([np.hstack([J, Je]), np.hstack([np.zeros((self.R, self.P)), np.eye(self.R) / self.eps])])
        return J

    def set_noise(self, z: np.ndarray, floor: np.ndarray) -> np.ndarray:
        """Per-record noise sd s_j^2 = RSS_j / (n_j - P n_j / N) from the residuals at z (Pa)."""
        r = self.data_residual(z)
        n = self.y.size
        s = np.empty(self.R)
        for j in range(self.R):
            rj = r[self.idx == j]
            dof = max(rj.size * (1.0 - self.P / n), 1.0)
            s[j] = math.sqrt(float(rj @ rj) / dof)
        self.sig = np.maximum(s, floor)[self.idx]
        return s


def _solve(fun, jac, z0, lo, hi, max_nfev):
    """scipy's trust-region least squares within [lo, hi]; its overflow warnings on trial points far out (which
    ``_safe`` turns into a large residual, so the step is refused) are not the user's concern and stay here."""
    import warnings

    from scipy.optimize import least_squares

    with warnings.catch_warnings(), np.errstate(over="ignore", invalid="ignore", divide="ignore"):
        warnings.simplefilter("ignore", RuntimeWarning)
        return least_squares(
            fun,
            np.clip(z0, lo + 1e-12, hi - 1e-12),
            jac=jac,
            bounds=(lo, hi),
            method="trf",
            x_scale="jac",
            xtol=1e-12,
            ftol=1e-12,
            gtol=1e-12,
            max_nfev=max_nfev,
        )


def _masked_solver(fun, jac, z_template, free, lo, hi):
    """least squares over the ``free`` components of z only (the others held at ``z_template``);
    the returned solution's ``x`` is the full z."""
    if free.all():
        return lambda z0, n: _solve(fun, jac, z0, lo, hi, n)

    def solve(z0, n):
        def full(w):
            z = np.asarray(z_template, dtype=float).copy()
            z[free] = w
            return z

        sol = _solve(lambda w: fun(full(w)), lambda w: jac(full(w))[:, free], z0[free], lo[free], hi[free], n)
        sol.x = full(sol.x)
        return sol

    return solve


def _safe(fn):
    def wrapped(z):
        r = fn(z)
        return r if np.all(np.isfinite(r)) else np.full_like(r, 1e6)  # steer away from failed evaluations

    return wrapped


class _Profiler:
    """chi2_profile(theta_i = c) - chi2_min by re-optimising the other components of z."""

    def __init__(self, prob, z_hat, chi2_min, cov_z, lo, hi, max_nfev=30):
        self.prob, self.z_hat, self.chi2_min, self.cov = prob, z_hat, chi2_min, cov_z
        self.lo, self.hi, self.max_nfev = lo, hi, max_nfev
        self.better: np.ndarray | None = None  # a point with lower chi2 than the "optimum", if met
        self.free = np.ones(z_hat.size, dtype=bool)  # components re-optimised (not held fixed)

    def delta(self, i: int, c: float) -> float:
        keep = (np.arange(self.z_hat.size) != i) & self.free

        def full(w):
            z = self.z_hat.copy()
            z[keep], z[i] = w, c
            return z

        fun = _safe(lambda w: self.prob.resid(full(w)))
        jac = lambda w: np.nan_to_num(self.prob.jac(full(w))[:, keep], nan=0.0, posinf=0.0, neginf=0.0)
        if keep.sum() == 0:
            r = fun(np.zeros(0))
            chi2 = float(r @ r)
        else:
            # start: the conditional optimum of the quadratic approximation (clipped), or the estimate
            ci = self.cov[:, i] / self.cov[i, i] if self.cov[i, i] > 0 else np.zeros(self.z_hat.size)
            move = np.nan_to_num(np.clip((c - self.z_hat[i]) * ci, -LOG_SPAN, LOG_SPAN))
            starts = [np.clip((self.z_hat + move)[keep], self.lo[keep], self.hi[keep]), self.z_hat[keep]]
            cost = [float(np.sum(fun(w) ** 2)) for w in starts]
            w0 = starts[int(np.argmin(cost))]
            sol = _solve(fun, jac, w0, self.lo[keep], self.hi[keep], self.max_nfev)
            chi2 = float(sol.fun @ sol.fun)
            if chi2 < self.chi2_min - max(1e-3, 1e-8 * self.chi2_min):  # 1e-3 << t^2 ~ 3.8
                self.better = full(sol.x)
        return max(chi2 - self.chi2_min, 0.0)

    def end(self, i: int, side: int, h: float, q: float) -> tuple[float, str]:
        """(theta_i at the interval end on this side, how: 'wald' | 'profile' | 'bound' | 'open')."""
        from scipy.optimize import brentq

        th0 = self.z_hat[i]
        bound = self.hi[i] if side > 0 else self.lo[i]
        limit = th0 + side * LOG_SPAN
        edge = bound if np.isfinite(bound) else limit
        if side * (edge - th0) <= 1e-12:
            return float(edge), "bound"
        h = min(max(h, 1e-6), LOG_SPAN) if np.isfinite(h) else 1.0
        c = th0 + side * min(h, side * (edge - th0))
        D = self.delta(i, c)
        if abs(D - q) <= WALD_TOL * q and side * (edge - c) > 1e-12:
            return float(c), "wald"
        below = th0
        for _ in range(12):
            if D >= q:
                break
            below = c
            if side * (edge - c) <= 1e-12:
                return float(edge), ("bound" if np.isfinite(bound) else "open")
            step = abs(c - th0) * (math.sqrt(q / D) * 1.3 if D > 1e-12 * q else 4.0)
            step = min(max(step, 1.5 * abs(c - th0)), 4.0 * abs(c - th0) + 1.0)
            c = th0 + side * min(step, side * (edge - th0))
            D = self.delta(i, c)
        if D < q:
            return float(c), ("bound" if np.isfinite(bound) else "open")
        g = lambda x: math.sqrt(self.delta(i, x)) - math.sqrt(q)
        root = brentq(g, below, c, xtol=1e-3 * max(abs(c - th0), 1e-6), rtol=1e-10, maxiter=30)
        return float(root), "profile"


def _bounds(names, n_branches, equilibrium, ramp_time: float, t_end: float):
    lo = np.full(len(names), -np.inf)
    hi = np.full(len(names), np.inf)
    a_lo, a_hi = ALPHA_BOUNDS
    mc = _table(equilibrium)
    if mc is not None and mc.alpha is not None:
        a_lo, a_hi = max(a_lo, mc.alpha_range[0]), min(a_hi, mc.alpha_range[1])
    lo[1], hi[1] = np.log(a_lo), np.log(a_hi)
    lo[2 : 2 + n_branches], hi[2 : 2 + n_branches] = np.log(BETA_BOUNDS[0]), np.log(BETA_BOUNDS[1])
    taus = slice(2 + n_branches, 2 + 2 * n_branches)
    lo[taus], hi[taus] = np.log(TAU_SPAN[0] * ramp_time), np.log(TAU_SPAN[1] * max(t_end, ramp_time))
    return lo, hi


def _exp(th: float) -> float:
    """exp(th), inf beyond the float range (a Wald end of a poorly determined log-parameter can lie there)."""
    return math.exp(th) if th < 709.0 else math.inf


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
    model_error: float | str | None = "auto",
    intervals: str = "profile",
) -> FitResult:
    r"""Fit ``(C, alpha, beta_m, tau_m)`` to compression-relaxation records (module doc: the statistics).

    records      list of ``(time [s], nominal_stress [Pa], displacement [m])``, one per compression
                 level (``displacement`` is the total plate approach reached at the end of the ramp).
    radius       reference ball radius a0 (m); ramp_time the loading ramp duration (s).
    n_branches   number of Maxwell branches (parameters ``beta``, ``tau`` or ``beta_1.., tau_1..``).
    equilibrium  the equilibrium law passed to the model ("fem" table, "hertz", an (x, f) table, a callable).
    initial      optional starting values (dict by name, or a sequence in :func:`parameter_names` order).
    model        ``model(t, *, radius, C, alpha, branches, displacement, ramp_time, equilibrium)`` ->
                 nominal stress (Pa), JAX-traceable; default ``reduced.spheroid.nominal_stress``.
    model_error  relative 1-sigma error of the model's force per record (e.g. 0.005), ``"auto"``
                 (:func:`model_error_of`: the FE table's ``model_error_rel``), or None/0 for none.
    intervals    "profile" (Wald checked against, and where poor replaced by, the profile likelihood)
                 or "wald" (Gauss-Newton ellipse only; fast, for large studies of well-posed problems).

    Returns a :class:`FitResult` (95 % intervals, flags and the identifiability report).
    Raises ValueError for malformed or uninformative records (fewer points than parameters, constant
    or non-positive stress, compression beyond the table) and RuntimeError when the model fails at
    the starting point.
    """
    recs = _as_records(records)
    validate_positive("radius (of the spheroid)", radius, "m")
    validate_positive("ramp_time (duration of the loading ramp)", ramp_time, "s")
    names = parameter_names(n_branches)
    _check_information(recs, names)
    if intervals not in ("profile", "wald"):
        raise ValueError(f"intervals must be 'profile' or 'wald'; got {intervals!r}")
    mc = _table(equilibrium)
    x = max(r.displacement for r in recs) / (2 * radius)
    if x >= 0.999:  # the plates would (nearly) touch: no law of this model holds there
        raise ValueError(
            f"the approach {max(r.displacement for r in recs):.4g} m is {x:.3g} of the ball's diameter 2 radius = "
            f"{2 * radius:.4g} m: it must be below it (check the displacement and the radius; on the command line "
            "--displacement-um and --radius-um)"
        )
    if mc is not None and x > mc.x_max * (1 + 1e-12):
        raise ValueError(
            f"compression delta/(2 a0) = {x:.4g} is beyond the calibrated table (up to {mc.x_max:.4g}); "
            "use equilibrium='hertz' (small compressions only) or a shorter approach"
        )
    if isinstance(model_error, str):
        if model_error != "auto":
            raise ValueError(
                f"model_error must be a number (relative, e.g. 0.005), 'auto' or None; got {model_error!r}"
            )
        eps = model_error_of(equilibrium)
    else:
        eps = 0.0 if model_error is None else float(model_error)
        if not (math.isfinite(eps) and eps >= 0):
            raise ValueError(
                f"model_error (relative 1-sigma error of the force, -) must be a finite number >= 0; got {model_error}"
            )
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
    P, R = len(names), len(recs)
    lo_t, hi_t = _bounds(names, n_branches, equilibrium, float(ramp_time), max(float(np.max(r.time)) for r in recs))
    theta0 = np.clip(np.log(p0), lo_t + 1e-9, hi_t - 1e-9)

    res_fn, jac_fn, scale = _builder(recs, float(radius), float(ramp_time), n_branches, equilibrium, model)
    if not np.all(np.isfinite(np.asarray(res_fn(jnp.asarray(theta0))))):
        raise RuntimeError(
            f"the model returned NaN/inf at the starting point {dict(zip(names, p0))}. "
            "Hint: give initial=... closer to the data, or check units (m, Pa, s)."
        )
    prob = _Problem(recs, res_fn, jac_fn, scale, P, eps)
    extra = prob.nz - P
    lo = np.concatenate([lo_t, np.full(extra, -np.inf)])
    hi = np.concatenate([hi_t, np.full(extra, np.inf)])
    peaks = np.array([np.max(np.abs(r.nominal_stress)) for r in recs])
    floor = NOISE_FREE_REL * 1e-3 * peaks  # keeps the weights finite for noise-free data
    fun = _safe(prob.resid)
    jac = lambda z: np.nan_to_num(prob.jac(z), nan=0.0, posinf=0.0, neginf=0.0)

    # pass 1: common weights; noise estimate per record; pass 2: weighted by each record's noise
    prob.sig = np.full(prob.y.size, 0.01 * scale)
    z0 = np.concatenate([theta0, np.zeros(extra)])
    # a parameter the model does not depend on (alpha with the Hertz law) is held at its start value
    norm0 = np.linalg.norm(jac(z0)[: prob.y.size, :P], axis=0)
    dead0 = [i for i in range(P) if norm0[i] <= 1e-10 * max(float(np.max(norm0)), 1e-300)]
    free = np.array([i not in dead0 for i in range(prob.nz)])
    solve = _masked_solver(fun, jac, z0, free, lo, hi)
    sol = solve(z0, max_nfev)
    nfev = int(sol.nfev)
    noise = prob.set_noise(sol.x, floor)
    if R > 1 or extra:
        for _ in range(2):  # weights from the previous pass's residuals; the last pass is optimal for its weights
            sol = solve(sol.x, max_nfev)
            nfev += int(sol.nfev)
            noise_prev, noise = noise, prob.set_noise(sol.x, floor)
            if np.all(np.abs(noise - noise_prev) <= 0.01 * noise_prev):
                break
        prob.sig = np.maximum(noise_prev, floor)[prob.idx]  # the weights z is the optimum for
    z = sol.x
    flags: list[str] = []
    noise_free = bool(np.any(noise < NOISE_FREE_REL * peaks))
    if noise_free:
        flags.append(
            "the residuals are at round-off level (noise-free, synthetic data?): there is no noise to "
            "estimate, so no confidence interval can be given (intervals are NaN); add the measurement noise"
        )
    r = prob.resid(z)
    chi2 = float(r @ r)
    Jz = prob.jac(z)
    if not np.all(np.isfinite(Jz)):
        flags.append("the model's sensitivities are not finite at the estimate: the intervals cannot be trusted")
        Jz = np.nan_to_num(Jz, nan=0.0, posinf=0.0, neginf=0.0)
    N = prob.y.size
    dof = N - P
    from scipy.stats import t as student_t

    tq = float(student_t.ppf(0.975, dof))
    q = tq * tq
    fisher_z = Jz.T @ Jz
    lam, V = np.linalg.eigh(0.5 * (fisher_z + fisher_z.T))
    cov_z = (V * _inverse_eigenvalues(lam)) @ V.T
    cov = cov_z[:P, :P]
    colnorm = np.linalg.norm(Jz[:N, :P], axis=0)
    dead = sorted(set(dead0) | {i for i in range(P) if colnorm[i] <= 1e-10 * max(float(np.max(colnorm)), 1e-300)})
    lam_t, V_t = np.linalg.eigh(0.5 * (cov + cov.T))
    fisher_t = (V_t * _inverse_eigenvalues(lam_t)) @ V_t.T  # marginal Fisher of theta
    for i in dead:
        fisher_t[i, :] = fisher_t[:, i] = 0.0
    ident = _identifiability(fisher_t, names, dead)
    at_bound = [names[i] for i in range(P) if min(z[i] - lo[i], hi[i] - z[i]) < 1e-6 and i not in dead]
    if at_bound:
        ident.report += (
            "\n  -> at a bound of the search: "
            + ", ".join(at_bound)
            + f" (alpha in [{math.exp(lo[1]):.3g}, {math.exp(hi[1]):.3g}], beta in {BETA_BOUNDS}, tau in "
            f"[{math.exp(lo[2 + n_branches]):.3g}, {math.exp(hi[2 + n_branches]):.3g}] s); e.g. alpha "
            "at its lower bound means the data are consistent with a neo-Hookean law (alpha = 0), tau at its upper "
            "bound that a branch does not relax within the records (beta then trades off against C)."
        )
    if not sol.success:
        flags.append(f"the optimizer did not converge: {sol.message}")
    acc = _stated_accuracy(equilibrium) or 0.0
    too_clean = [] if noise_free else [j for j in range(R) if noise[j] < acc * peaks[j]]
    if too_clean:
        flags.append(
            f"record(s) {', '.join(str(j + 1) for j in too_clean)} scatter about the model by less (noise sd "
            f"{min(noise[j] / peaks[j] for j in too_clean):.2g} of the peak stress) than the equilibrium table is "
            f"accurate ({acc:.2g}, its model_error_rel): the residuals are then the records' own discretisation "
            "error and the model's, not noise, and the intervals can miss the truth (noise-free synthetic data?); "
            "add the measurement noise"
        )

    sd = np.sqrt(np.abs(np.diag(cov)))
    p = np.exp(z[:P])
    ivals: dict[str, tuple[float, float]] = {}
    kinds: dict[str, str] = {}
    methods: dict[str, str] = {}
    phys_lo = np.where(np.isfinite(lo_t), 0.0, 0.0)  # a lower search bound stands for the limit 0

    def to_linear(i, th, how, side):
        if how in ("bound", "open"):
            if side < 0:
                return float(phys_lo[i])
            return math.inf if how == "open" else _exp(th)
        return _exp(th)

    prof = _Profiler(prob, z, chi2, cov_z, lo, hi)
    prof.free = free.copy()
    prof.free[dead] = False
    for i, nm in enumerate(names):
        if i in dead:
            ivals[nm] = (float(phys_lo[i]), float(math.exp(hi_t[i])) if np.isfinite(hi_t[i]) else math.inf)
            kinds[nm], methods[nm] = "none", "bound"
            continue
        if noise_free:
            ivals[nm], kinds[nm], methods[nm] = (math.nan, math.nan), "n/a", "n/a"
            continue
        h = tq * sd[i]
        ends, hows = [], []
        for side in (-1, 1):
            if intervals == "wald":
                c = z[i] + side * h
                edge = hi[i] if side > 0 else lo[i]
                if side * (c - edge) >= 0:
                    c, how = edge, "bound"
                elif not np.isfinite(c):
                    c, how = z[i] + side * LOG_SPAN, "open"
                else:
                    how = "wald"
            else:
                c, how = prof.end(i, side, h, q)
            ends.append(to_linear(i, c, how, side))
            hows.append(how)
        lo_open = hows[0] in ("bound", "open")
        hi_open = hows[1] in ("bound", "open")
        kinds[nm] = "none" if (lo_open and hi_open) else "upper" if lo_open else "lower" if hi_open else "two-sided"
        real = [h_ for h_ in hows if h_ in ("wald", "profile")]
        methods[nm] = "profile" if "profile" in real else "wald" if real else "bound"
        ivals[nm] = (ends[0], ends[1])
    if prof.better is not None:
        flags.append(
            "the profile search met parameters fitting better than the reported optimum (a local "
            "minimum): refit with initial= near the profile's values"
        )
    for nm in names:
        if kinds[nm] == "upper":
            ident.report += f"\n  -> {nm}: only an upper bound at 95 %: {nm} < {ivals[nm][1]:.4g}"
        elif kinds[nm] == "lower":
            ident.report += f"\n  -> {nm}: only a lower bound at 95 %: {nm} > {ivals[nm][0]:.4g}"
        elif kinds[nm] == "none" and names.index(nm) not in dead:
            ident.report += f"\n  -> {nm}: not bounded by these records at 95 % (any value in the search range fits)"
    rdata = prob.data_residual(z)
    success = bool(sol.success) and not noise_free and not too_clean and prof.better is None
    return FitResult(
        params={nm: float(v) for nm, v in zip(names, p)},
        intervals=ivals,
        residual=float(np.sqrt(np.mean(rdata**2))),
        identifiability=ident,
        covariance=cov,
        success=success,
        message=str(sol.message) + "".join(f"; {f}" for f in flags),
        nfev=nfev,
        names=names,
        kinds=kinds,
        methods=methods,
        noise=tuple(float(s) for s in noise),
        model_error=eps,
        flags=tuple(flags),
        dof=int(dof),
        model_error_factors=tuple(float(v) for v in np.exp(z[P:])) if extra else (),
    )


def read_csv(path: str, *, displacement: float, time_column: str | int = 0, stress_column: str | int = 1) -> Record:
    """Read a relaxation record from a CSV file: a time column (s) and a nominal-stress column (Pa).

    A header line is optional (columns may then be chosen by name; a unit in it, ``time_ms`` or ``stress [kPa]``,
    is converted to SI, an unknown one refused), ``#`` lines are comments;
    ``displacement`` is the total plate approach in m. Returns a :class:`Record` ready for
    :func:`relaxation`. Raises ValueError (one line naming the file and line) for malformed files.
    """
    from tissuemech.compare.fit_cli import read_table

    validate_positive("displacement (the total approach of the plates)", displacement, "m")
    table = read_table(path)
    cols = []
    for c in (time_column, stress_column):
        if isinstance(c, int):
            if c >= table.values.shape[1]:
                raise ValueError(f"{path}: column {c} not found; it has {table.values.shape[1]} columns")
            cols.append(c)
        else:
            if c not in table.header:
                raise ValueError(f"{path}: column {c!r} not found; it has {list(table.header)}")
            cols.append(table.header.index(c))
    from tissuemech.compare.fit_cli import _UNITS, _column

    scaled = []
    for c, want in zip(cols, ("time", "stress")):
        kind, unit = _column(table.header[c]) if c < len(table.header) else (None, None)
        if kind not in (None, want):
            raise ValueError(f"{path}: column {table.header[c]!r} holds {kind}, not {want}")
        if unit is not None and unit not in _UNITS[want]:
            raise ValueError(
                f"{path}: column {table.header[c]!r}: unit {unit!r} is not one of {', '.join(_UNITS[want])} ({want})"
            )
        scaled.append(table.values[:, c] * (1.0 if unit is None else _UNITS[want][unit]))
    return _as_records([(scaled[0], scaled[1], displacement)])[0]
