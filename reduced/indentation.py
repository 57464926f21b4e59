r"""A rigid spherical probe pressed on a ball resting on a rigid plate: the lumped generalized-Maxwell force.

Geometry (SI units): a rigid sphere of radius ``probe_radius`` R_p (m, the AFM colloidal probe) pushes on a
ball of radius ``radius`` a0 (m, the cell, oocyte or spheroid) that rests on a rigid, frictionless plate;
``delta`` (m) is the approach of the probe towards the plate since first contact (the AFM "indentation":
piezo travel minus cantilever deflection). ``radius=math.inf`` is the classical half-space (a probe on a
thick flat sample).

Equilibrium law (small strain)
------------------------------
Two Hertz contacts in series carry the same force F: probe on ball (rigid sphere R_p on an elastic sphere
a0: effective radius R_1 = R_p a0 / (R_p + a0)) and ball on plate (elastic sphere on a rigid flat: R_2 = a0).
Each obeys F = (4/3) E* sqrt(R_i) d_i^(3/2) with E* = E / (1 - nu^2) (the other body rigid). For the Fung
material, the small-strain shear modulus is mu = 2 C; incompressible (nu = 1/2) gives E = 3 mu = 6 C and

    E* = E / (1 - 1/4) = (4/3) 6 C = 8 C.

The approaches add, delta = d_1 + d_2, and d_i = (F / k_i)^(2/3) with k_i = (4/3) E* sqrt(R_i), so

    delta = F^(2/3) (k_1^(-2/3) + k_2^(-2/3)),   i.e.   F_eq(delta) = (4/3) E* sqrt(R_s) delta^(3/2)
    = (32/3) C sqrt(R_s) delta^(3/2),   R_s = (R_1^(-1/3) + R_2^(-1/3))^(-3)

(:func:`series_radius`): one Hertz law with a series radius R_s < min(R_1, R_2). The split is
d_i / delta = R_i^(-1/3) / (R_1^(-1/3) + R_2^(-1/3)) (:func:`contact_depths`). Limits: a0 -> inf gives
R_1 -> R_p, R_2^(-1/3) -> 0, so R_s -> R_p and F = (4/3) E* sqrt(R_p) delta^(3/2) (the half-space Hertz
law); two plates on a ball (reduced.spheroid's Hertz law) is the case R_1 = R_2 = a0, R_s = a0 / 8.

Validity of the Hertz law: small strain only (contact radii small against R_1 and a0; linear elasticity, so the
Fung exponent ``alpha`` does not enter it). Against the converged FE (``fem.indentation``) it is 1.66 % soft at
x = delta / (2 a0) = 0.005 for R_p = a0 (the finite-strain correction grows like sqrt(x): 0.236 sqrt(x)). Eager
calls reject a probe-contact depth beyond its effective radius (d_1 >= R_1) or a plate-contact depth beyond the
ball's radius (d_2 >= a0), where the law means nothing.

FE-calibrated table (``law="table"``; ``law="auto"``, the default, uses it where it applies)
------------------------------------------------------------------------------------------------
F_eq = F_Hertz,series(delta) h(y, alpha, rho), rho = R_p / a0, y = d_1 / R_1 = 2 x share(rho) / r_1(rho)
(:func:`depth_ratio`: the probe contact's small-strain depth in units of its effective radius, the quantity
that bounds what the scene resolves, so one y grid serves every probe size). h comes from static FE runs on
contact-edge-fitted meshes (``tissuemech calibrate-indentation``, shipped as
``reduced/data/indentation_master.npz`` with its metadata: FE level, the discretisation error against a finer
level at check points, the command), h = 1 at y = 0, interpolated by natural cubic splines in ln(rho), then in
s = sqrt(y) and alpha (:class:`MasterTable`; the same sqrt rule as the plate table: h - 1 grows like sqrt(y)).
The shipped grid: rho = 0.05, 0.1, 0.2, 0.4, 1; alpha = 0, 0.5, 1.5; y = 0 ... 0.1 (x up to 0.0032 for R_p =
a0 / 20, 0.045 for R_p = a0; the fitted-edge FE of a stiffening ball under a small probe stops converging not far
beyond). Each node is the Richardson extrapolation of levels 1 and 2 (observed order 2.84 in the zone's element
count, measured over levels 1-3 at three geometries): against the extrapolation of levels 2 and 3 at 12 check
points (rho 0.05 and 0.2, alpha 0 and 1.5, y 0.025-0.1) it is within 6.6e-6 (level 2 alone: 6.4e-4 off at R_p =
a0 / 20). Off the nodes (R_p / a0 = 0.27, alpha = 0.75, x = 0.0102) the table is 5.1e-6 from the converged FE
(Richardson over levels 2-4, observed order 3.8; ``tests/data/indentation_reference.json``). Generation: 14 min
for level 2 with the level-3 check at rho = 0.2, 4 min for level 1 with the check at rho = 0.05 (2 processes on a
shared, heavily loaded 2-core machine).
Its range: rho and alpha inside the grid (:func:`master_table`: ``rho_range``, ``alpha_range``) and x up to
``x_max(rho)``. ``law="table"`` raises outside it (InputError naming the quantity and its range). ``law="auto"``
takes the table when radius and probe_radius are concrete numbers with R_p / a0, alpha and the largest approach
inside it, and the Hertz law otherwise: a half-space (``radius=math.inf``) or a probe outside the rho range
(silently: the Hertz law's own domain), an approach or alpha beyond the table (with a ``UserWarning``: the law is
then up to a few % soft, and a fit whose approaches cross x_max would see the two laws), several geometries in
one call, or a geometry traced under jit/grad (the table is sliced at one concrete rho; ``law="table"`` raises
there). Under jit with traced C / alpha / approaches the table's range is checked at run time by
``reduced.spheroid`` (its messages speak of the equivalent ball's x' = delta / (2 a'), a' = 8 R_s).

Viscoelasticity (the lumped convolution of :mod:`tissuemech.reduced.spheroid`)
----------------------------------------------------------------------------
    F(t) = F_eq(delta(t)) + sum_m beta_m int_0^t exp(-(t - s)/tau_m) dF_eq(delta(s))/ds ds

with energy factors beta_m (-) and relaxation times tau_m (s). reduced.spheroid's Hertz law for a ball of
radius a' between two plates is F = C a'^2 (32/3) (delta / (2 a'))^(3/2) = (32/3) C sqrt(a'/8) delta^(3/2):
the law above with a' = 8 R_s. :func:`force` therefore calls ``spheroid.force(..., radius=8 R_s,
equilibrium="hertz")`` (or the table's law at this rho, :meth:`MasterTable.law`; the check d_1 < R_1 keeps
delta < 16 R_s = 2 a', inside that law's range), so the
spheroid's quadrature (ramp and hold, exact kernel) and its diffrax path (any history) are reused, not copied.

Loading (``displacement``)
--------------------------
* a number (m) with ``ramp_time`` (s): a linear ramp to it, then held (quadrature, ~1e-9 accurate);
* a measured history ``(times, approaches)`` (s, m; 1-D, times strictly increasing from >= 0, approaches
  >= 0 and 0 at the first time, the first contact): piecewise linear between the samples and held after the
  last one (diffrax at ``rtol``/``atol``; an eager call makes every sample a jump time of the solver; under
  jit, where the samples are traced, give output times at the samples, as ``compare.afm.fit`` does, so the
  steps land on the kinks). Thin a long record first (a few hundred knots: the cost grows with their number).

Every function is jit / vmap / grad-able in float64 (parameters broadcast: output shape
``broadcast(params).shape + t.shape``); eager calls check their inputs (messages name the quantity and unit).
"""

from __future__ import annotations

import functools
import json
import warnings
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import jax.numpy as jnp
import numpy as np

import tissuemech.reduced  # noqa: F401  (float64 in JAX)
from tissuemech.reduced import spheroid
from tissuemech.reduced.interp import second_derivative_map, spline_weights
from tissuemech.reduced.material import probe_share
from tissuemech.reduced.validation import (
    InputError,
    is_traced,
    validate_finite,
    validate_material,
    validate_positive,
    validate_times,
)

__all__ = [
    "series_radius",
    "contact_depths",
    "equilibrium_force",
    "force",
    "history",
    "depth_ratio",
    "x_of_depth_ratio",
    "MasterTable",
    "master_table",
    "LAWS",
    "DATA_FILE",
]

HERTZ_PREFACTOR = 32.0 / 3.0  # F = (4/3) E* sqrt(R) d^1.5 with E* = 8 C: (32/3) C sqrt(R) d^1.5
DATA_FILE = Path(__file__).resolve().parent / "data" / "indentation_master.npz"
LAWS = ("auto", "table", "hertz")


def _check_radii(radius: Any, probe_radius: Any) -> None:
    """radius (ball) > 0 and may be inf (half-space); probe_radius > 0 and finite."""
    validate_positive("probe_radius (radius of the spherical AFM probe)", probe_radius, "m")
    if not is_traced(radius):
        r = np.asarray(radius, dtype=float) if not isinstance(radius, str) else None
        if r is None or r.size == 0 or np.any(np.isnan(r)) or np.any(r <= 0):
            raise InputError(
                f"radius (of the indented ball, in m) must be positive (math.inf for a half-space); got {radius!r}"
            )


def series_radius(radius: Any, probe_radius: Any) -> jnp.ndarray:
    """Series radius R_s = (R_1^(-1/3) + a0^(-1/3))^(-3) in m of the two Hertz contacts (module doc).

    radius        ball radius a0 (m); ``math.inf`` for a half-space (then R_s = probe_radius).
    probe_radius  probe radius R_p (m). R_1 = R_p a0 / (R_p + a0) is the probe-ball effective radius.
    """
    if not is_traced(radius, probe_radius):
        _check_radii(radius, probe_radius)
    a = jnp.asarray(radius, dtype=jnp.float64)
    rp = jnp.asarray(probe_radius, dtype=jnp.float64)
    r1 = rp / (1.0 + rp / a)  # = R_p a0 / (R_p + a0), finite for a0 = inf
    return (r1 ** (-1.0 / 3.0) + a ** (-1.0 / 3.0)) ** -3.0


def contact_depths(displacement: Any, *, radius: Any, probe_radius: Any) -> tuple[jnp.ndarray, jnp.ndarray]:
    """(d_1, d_2) in m: the approach ``displacement`` delta (m) split into the probe-ball depth d_1 and the
    ball-plate depth d_2 (d_1 + d_2 = delta; d_i proportional to R_i^(-1/3); d_2 = 0 for a half-space)."""
    if not is_traced(displacement, radius, probe_radius):
        _check_radii(radius, probe_radius)
        validate_finite("displacement (approach of the probe since contact)", displacement, "m")
    a = jnp.asarray(radius, dtype=jnp.float64)
    rp = jnp.asarray(probe_radius, dtype=jnp.float64)
    d = jnp.asarray(displacement, dtype=jnp.float64)
    d1 = d * probe_share(a, rp)
    return d1, d - d1


def _check_depth(dmax: Any, radius: Any, probe_radius: Any) -> None:
    """Eager: the small-strain law must at least be geometric sense (d_1 < R_1, d_2 < a0)."""
    d = np.max(np.asarray(dmax, dtype=float))
    a = np.asarray(radius, dtype=float)
    rp = np.asarray(probe_radius, dtype=float)
    d1, d2 = (np.asarray(v) for v in contact_depths(d, radius=a, probe_radius=rp))
    r1 = rp / (1.0 + rp / a)
    if np.any(d1 >= r1):
        raise InputError(
            f"displacement (approach of the probe, in m): {d:.4g} m puts the probe-ball contact {np.max(d1):.4g} m "
            f"deep, beyond its effective radius R_p a0/(R_p + a0) = {np.min(r1):.4g} m; the small-strain Hertz law "
            "holds only for depths well below it (check the units: m, not um)"
        )
    if np.any(d2 >= a):
        raise InputError(
            f"displacement (approach of the probe, in m): {d:.4g} m puts the ball-plate contact {np.max(d2):.4g} m "
            f"deep, beyond the ball's radius {np.min(a):.4g} m (check the units: m, not um)"
        )


def equilibrium_force(
    displacement: Any, *, radius: Any, probe_radius: Any, C: Any, alpha: Any = 0.0, law: str = "auto"
) -> jnp.ndarray:
    """Elastic (long-time) force F_eq in N: the two-Hertz-contacts law (32/3) C sqrt(R_s) delta^(3/2) times the
    FE-calibrated h(y, alpha, rho) (module doc).

    displacement  approach delta of the probe since first contact (m), >= 0 (negative: no contact, 0 N).
    radius        ball radius a0 (m), ``math.inf`` for a half-space.   probe_radius  R_p (m).
    C, alpha      Fung parameters (Pa, -); alpha enters through the table only.
    law           "auto" (default: the table where R_p / a0 is inside it, else Hertz), "table" or "hertz".
    """
    if not is_traced(displacement, radius, probe_radius, C, alpha):
        _check_radii(radius, probe_radius)
        validate_material(C, alpha)
        dv = validate_finite("displacement (approach of the probe since contact)", displacement, "m")
        _check_depth(dv, radius, probe_radius)
    tab = _geometry_law(law, radius, probe_radius, _concrete_max(displacement), alpha)
    if tab is not None:
        table, rho = tab
        a_equiv = 8.0 * series_radius(radius, probe_radius)
        d = jnp.maximum(jnp.asarray(displacement, dtype=jnp.float64), 0.0)
        return spheroid.equilibrium_force(d, radius=a_equiv, C=C, alpha=alpha, equilibrium=table.law(rho))
    d = jnp.maximum(jnp.asarray(displacement, dtype=jnp.float64), 0.0)
    rs = series_radius(radius, probe_radius)
    return HERTZ_PREFACTOR * jnp.asarray(C, dtype=jnp.float64) * jnp.sqrt(rs) * d * jnp.sqrt(d)


def history(times: Any, approaches: Any) -> tuple[jnp.ndarray, jnp.ndarray]:
    """A measured approach history, checked: ``times`` (s, 1-D, strictly increasing, >= 0) and ``approaches``
    (m, same length, finite, >= 0, 0 at the first sample: first contact). Returns both as float64 arrays;
    pass the pair as ``displacement=`` to :func:`force`."""
    if not is_traced(times, approaches):
        t = validate_times("times (of the measured approach history)", times, ascending=True, strictly=True, ndim1=True)
        d = validate_finite("approaches (of the measured approach history)", approaches, "m")
        if t is None or d is None:
            raise InputError("the measured history needs numbers: (times in s, approaches in m)")
        if d.shape != t.shape:
            raise InputError(f"approaches (m) need one value per time (s): got {d.size} approaches for {t.size} times")
        if t.size < 2:
            raise InputError(f"the measured history needs at least 2 samples (times in s); got {t.size}")
        if np.any(d < 0):
            raise InputError(
                f"approaches (of the measured history, m) must not be negative (no contact); got {np.min(d):.4g} m"
            )
        if d[0] != 0.0:
            raise InputError(
                f"approaches (m): the history starts at first contact, approach 0 m at the first time; got {d[0]:.4g} m"
            )
    return jnp.asarray(times, dtype=jnp.float64), jnp.asarray(approaches, dtype=jnp.float64)


# ---------------------------------------------------------------- the FE-calibrated table h(y, alpha, rho)


def depth_ratio(x: Any, rho: Any) -> np.ndarray:
    """y = d_1 / R_1 = 2 x share(rho) / r_1(rho): the probe contact's small-strain depth d_1 (``contact_depths``)
    over its effective radius R_1, at x = delta / (2 a0) and rho = R_p / a0 (r_1 = R_1 / a0; NumPy, eager)."""
    rho = np.asarray(rho, dtype=float)
    return 2.0 * np.asarray(x, dtype=float) * np.asarray(probe_share(1.0, rho)) / (rho / (1.0 + rho))


def x_of_depth_ratio(y: Any, rho: Any) -> np.ndarray:
    """x = delta / (2 a0) at the depth ratio y and rho = R_p / a0 (the inverse of :func:`depth_ratio`)."""
    rho = np.asarray(rho, dtype=float)
    return np.asarray(y, dtype=float) * (rho / (1.0 + rho)) / (2.0 * np.asarray(probe_share(1.0, rho)))


class MasterTable:
    """The FE-calibrated correction h(y, alpha, rho) = F_eq / F_Hertz,series (module doc, "FE-calibrated table").

    ``y`` (n_y,) depth ratios from 0 (:func:`depth_ratio`), ``alpha`` (n_a,), ``rho`` (n_r,) = R_p / a0, ``h``
    (n_r, n_a, n_y) with h = 1 at y = 0; ``metadata`` (the generator's JSON: levels, ``discretisation_error``...).
    h is interpolated by natural cubic splines in ln(rho) (:meth:`slice`), then in s = sqrt(y) and alpha (the
    plate table's ``spheroid.MasterCurve``, through which :func:`force` runs)."""

    def __init__(self, y: Any, alpha: Any, rho: Any, h: Any, metadata: dict | None = None):
        self.y, self.alpha, self.rho = (np.asarray(v, dtype=float) for v in (y, alpha, rho))
        self.h = np.asarray(h, dtype=float)
        if self.y.ndim != 1 or self.y.size < 3 or self.y[0] != 0 or np.any(np.diff(self.y) <= 0):
            raise ValueError("indentation table: y must be >= 3 increasing depth ratios from 0")
        if self.h.shape != (self.rho.size, self.alpha.size, self.y.size) or not np.all(np.isfinite(self.h)):
            raise ValueError(
                f"indentation table: h needs finite values of shape (n_rho, n_alpha, n_y) = "
                f"({self.rho.size}, {self.alpha.size}, {self.y.size}); got {self.h.shape}"
            )
        if self.rho.size < 2 or np.any(np.diff(self.rho) <= 0) or self.rho[0] <= 0:
            raise ValueError("indentation table: rho = R_p / a0 must be >= 2 increasing positive values")
        self.metadata = dict(metadata or {})
        self.y_max = float(self.y[-1])
        self.alpha_range = (float(self.alpha[0]), float(self.alpha[-1]))
        self.rho_range = (float(self.rho[0]), float(self.rho[-1]))
        self._L = second_derivative_map(np.log(self.rho), "natural")
        self._laws: dict[float, spheroid.FEMTable] = {}

    def covers(self, rho: float) -> bool:
        """Whether rho = R_p / a0 is inside the table's rho range."""
        lo, hi = self.rho_range
        return bool(lo * (1 - 1e-12) <= rho <= hi * (1 + 1e-12))

    def x_max(self, rho: float) -> float:
        """The largest x = delta / (2 a0) of the table at rho (its last depth ratio)."""
        return float(x_of_depth_ratio(self.y_max, rho))

    def slice(self, rho: float) -> np.ndarray:
        """h at the (alpha, y) nodes for this rho: (n_a, n_y), a natural cubic spline in ln(rho) of the slices."""
        w = np.asarray(spline_weights(np.log(self.rho), self._L, float(np.log(rho))))
        return np.tensordot(w, self.h, axes=1)

    def law(self, rho: float) -> spheroid.FEMTable:
        """The equilibrium law at rho as ``reduced.spheroid``'s table law for the equivalent ball of radius
        a' = 8 R_s (:func:`force`'s module doc): x' = delta / (2 a') = x / (8 r_s), f' = (32/3) x'^1.5 h."""
        key = float(rho)
        if key not in self._laws:
            if len(self._laws) > 64:
                self._laws.clear()
            rs = float(series_radius(1.0, key))
            xp = x_of_depth_ratio(self.y, key) / (8.0 * rs)
            H = self.slice(key)
            mc = spheroid.MasterCurve(
                xp, np.asarray(spheroid.hertz_f(xp)) * H, alpha=self.alpha, metadata=self.metadata, h=H
            )
            self._laws[key] = spheroid.FEMTable(mc)
        return self._laws[key]

    def __call__(self, x: Any, alpha: Any = 0.0, rho: float = 1.0) -> np.ndarray:
        """h at x = delta / (2 a0), alpha and one rho (eager, inside the table; NumPy)."""
        self.check(np.max(x), alpha, rho)
        xs = np.asarray(x, dtype=float) / (8.0 * float(series_radius(1.0, float(rho))))
        mc = self.law(rho).master
        return np.asarray(mc.f(xs, alpha)) / np.asarray(spheroid.hertz_f(xs))

    def check(self, x_max: Any, alpha: Any, rho: float) -> None:
        """Raise InputError where x up to ``x_max``, ``alpha`` (eager values) or ``rho`` is outside the table."""
        lo, hi = self.rho_range
        if not self.covers(rho):
            raise InputError(
                f"probe_radius / radius = {rho:.4g} is outside the calibrated indentation table (R_p / a0 in "
                f"[{lo:g}, {hi:g}]); use law='hertz' (the small-strain two-contact law)"
            )
        xm = self.x_max(rho)
        xv = None if is_traced(x_max) else float(np.max(np.asarray(x_max, dtype=float)))
        if xv is not None and xv > xm * (1 + 1e-9):
            raise InputError(
                f"displacement (approach of the probe): delta / (2 a0) = {xv:.4g} is beyond the calibrated indentation "
                f"table at R_p / a0 = {rho:.4g} (up to {xm:.4g}: the probe contact {self.y_max:g} of its effective "
                "radius deep); use law='hertz' (small strain) or a smaller approach (m)"
            )
        if not is_traced(alpha):
            av = np.asarray(alpha, dtype=float)
            a_lo, a_hi = self.alpha_range
            if av.size and (np.min(av) < a_lo - 1e-12 or np.max(av) > a_hi + 1e-12):
                raise InputError(
                    f"alpha (Fung exponent, -) = {np.max(av):g} is outside the calibrated indentation table (alpha in "
                    f"[{a_lo:g}, {a_hi:g}]); use law='hertz' (alpha does not enter it)"
                )


@functools.lru_cache(maxsize=4)
def master_table(path: str | None = None) -> MasterTable:
    """The FE-calibrated indentation table shipped with the package (``reduced/data/indentation_master.npz``, made
    by ``tissuemech calibrate-indentation``) or read from ``path``."""
    p = Path(path) if path is not None else DATA_FILE
    if not p.exists():
        raise FileNotFoundError(
            f"no calibrated indentation table at {p}. Generate it with `tissuemech calibrate-indentation "
            "--install`, or use law='hertz'."
        )
    with np.load(p, allow_pickle=False) as z:
        meta = json.loads(str(z["metadata"])) if "metadata" in z.files else {}
        return MasterTable(z["y"], z["alpha"], z["rho"], z["h"], metadata=meta)


def _concrete_max(v: Any) -> float | None:
    """max(v) as a float for concrete values, None for traced ones."""
    return None if is_traced(v) else float(np.max(np.asarray(v, dtype=float)))


def _geometry_law(
    law: str, radius: Any, probe_radius: Any, d_max: float | None = None, alpha: Any = 0.0
) -> tuple[MasterTable, float] | None:
    """(table, rho) when ``law`` resolves to the table at this geometry, None for the Hertz law (module doc).

    ``d_max``: the largest approach (m) when concrete. ``law="table"`` raises outside the table (InputError naming
    the quantity); ``law="auto"`` takes the Hertz law outside its rho range silently (the law's own domain: a
    half-space, a probe beyond the grid) and beyond its approach or alpha range with a ``UserWarning``."""
    if law not in LAWS:
        raise InputError(f"law must be one of {LAWS}, got {law!r}")
    if law == "hertz":
        return None
    if is_traced(radius, probe_radius):
        if law == "table":
            raise InputError(
                "law='table' needs concrete radius and probe_radius (m), not traced ones (the table is sliced at "
                "rho = R_p / a0 once); pass them as numbers, or use law='hertz'"
            )
        return None
    rho = np.unique(np.asarray(probe_radius, dtype=float) / np.asarray(radius, dtype=float))
    if rho.size != 1:
        if law == "auto":
            return None  # several geometries in one call: the Hertz law broadcasts over them
        raise InputError(
            f"law='table': one geometry per call (radius and probe_radius, m, as single values; got shapes "
            f"{np.shape(radius)} and {np.shape(probe_radius)}); loop over the geometries, or use law='hertz'"
        )
    r = float(rho.reshape(-1)[0])
    if law == "auto" and not DATA_FILE.exists():
        return None  # a checkout without the generated table: the small-strain law
    table = master_table()
    if law == "auto" and not table.covers(r):
        return None
    x_max = 0.0 if d_max is None else d_max / (2.0 * float(np.max(np.asarray(radius, dtype=float))))
    if law == "table":
        table.check(x_max, alpha, r)
        return table, r
    try:
        table.check(x_max, alpha, r)
    except InputError as err:
        warnings.warn(
            f"law='auto' uses the small-strain Hertz law here: {err.args[0].split('; use')[0]}",
            UserWarning,
            stacklevel=3,
        )
        return None
    return table, r


class _PiecewiseLinear:
    """delta(t) = interp(t; times, approaches), 0 before the first time, held after the last. Hashable by
    content (spheroid.force keys its compiled code on the history callable): equal records reuse it."""

    def __init__(self, times: Any, approaches: Any):
        self.t = jnp.asarray(times, dtype=jnp.float64)
        self.d = jnp.asarray(approaches, dtype=jnp.float64)
        traced = is_traced(self.t, self.d)
        self._key = None if traced else (np.asarray(self.t).tobytes(), np.asarray(self.d).tobytes())

    def __call__(self, t: Any) -> jnp.ndarray:
        return jnp.interp(t, self.t, self.d, left=0.0)

    def __hash__(self) -> int:
        return hash(self._key) if self._key is not None else id(self)

    def __eq__(self, other: object) -> bool:
        if self._key is None or not isinstance(other, _PiecewiseLinear):
            return self is other
        return self._key == other._key


def force(
    t: Any,
    *,
    radius: Any,
    probe_radius: Any,
    C: Any,
    alpha: Any = 0.0,
    branches: Sequence[tuple[Any, Any]] = (),
    displacement: Any,
    ramp_time: Any = None,
    rtol: float = 1e-10,
    atol: float = 1e-10,
    max_steps: int = 65536,
    solver: Any = None,
    adjoint: Any = "reverse",
    law: str = "auto",
) -> jnp.ndarray:
    r"""Probe force F(t) in N of the lumped generalized-Maxwell ball under a spherical probe (module doc).

    t             output times (s), any shape, >= 0 (t = 0 is first contact).
    radius        ball radius a0 (m), ``math.inf`` for a half-space.   probe_radius  R_p (m).
    C, alpha      Fung parameters (Pa, -); alpha unused by the small-strain law.
    branches      sequence of (beta, tau): energy factor (-) and relaxation time (s); () = elastic.
    displacement  approach of the probe (m) reached at ``ramp_time`` (s) by a linear ramp and then held; or a
                  measured history ``(times, approaches)`` (s, m), piecewise linear, held after its end.
    rtol, atol, max_steps, solver, adjoint   diffrax options of the measured-history path
                  (``adjoint="forward"`` for ``jax.jacfwd``).
    law           equilibrium law: "auto" (default: the FE-calibrated table where R_p / a0 is inside it and radius
                  and probe_radius are concrete; else the Hertz law), "table" (raises outside the table: R_p / a0,
                  alpha, delta / (2 a0)) or "hertz" (the small-strain two-contact law).
    Returns F (N), shape ``broadcast(params).shape + t.shape``. Raises ValueError (eager) for bad inputs.
    """
    measured = isinstance(displacement, tuple)
    if measured:
        if len(displacement) != 2:
            raise InputError("displacement as a measured history is a pair (times in s, approaches in m)")
        times, approaches = history(*displacement)
    eager = not is_traced(t, radius, probe_radius, C, alpha, *(v for b in branches for v in b))
    if eager:
        validate_times("t (output times, t = 0 is first contact)", t, unit="s")
        _check_radii(radius, probe_radius)
        validate_material(C, alpha)
        if measured:
            if not is_traced(approaches):
                _check_depth(np.max(np.asarray(approaches)), radius, probe_radius)
        else:
            validate_positive("displacement (approach of the probe at the end of the ramp)", displacement, "m")
            if ramp_time is None:
                raise InputError("ramp_time (s) is needed with a numeric displacement (linear ramp, then hold)")
            validate_positive("ramp_time (duration of the loading ramp)", ramp_time, "s")
            _check_depth(displacement, radius, probe_radius)
    tab = _geometry_law(law, radius, probe_radius, _concrete_max(approaches if measured else displacement), alpha)
    equilibrium: Any = "hertz"
    if tab is not None:
        table, rho = tab
        equilibrium = table.law(rho)
    rs = series_radius(radius, probe_radius)
    a_equiv = 8.0 * rs  # the spheroid's law with this radius and C' = C sqrt(8 R_s / a') = C (module doc)
    common = dict(radius=a_equiv, C=C, alpha=alpha, branches=branches, equilibrium=equilibrium)
    if measured:
        return spheroid.force(
            t,
            **common,
            displacement=_PiecewiseLinear(times, approaches),
            jump_times=None if is_traced(times) else tuple(float(v) for v in np.asarray(times)),
            rtol=rtol,
            atol=atol,
            max_steps=max_steps,
            solver=solver,
            adjoint=adjoint,
        )
    return spheroid.force(t, **common, displacement=displacement, ramp_time=ramp_time)
