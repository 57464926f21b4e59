r"""Spheroid compression-relaxation, the lumped generalized-Maxwell model (JAX + diffrax, SI units).

A ball of radius ``a0`` (m) of Fung material (``C`` Pa, ``alpha``) is squeezed between two rigid
frictionless plates; ``delta(t)`` is the total approach (m). The plate force (N) is

    F(t) = F_eq(delta(t)) + sum_m q_m(t),   dq_m/dt = -q_m / tau_m + beta_m d F_eq(delta(t)) / dt,

(physics.md; beta_m energy factors, tau_m relaxation times in s), q_m(0) = 0. The equilibrium law
F_eq is pluggable (``equilibrium=``):

* ``"fem"`` (default): the master curves f(x; alpha) tabulated by the FE (``python -m tissuemech.compare.calibrate``,
  shipped as ``reduced/data/spheroid_master.npz``; x = delta/(2 a0) in [0, 0.36], alpha in [0, 1.5]),
  interpolated by C^2 splines of f / f_Hertz in sqrt(x) and alpha (differentiable in both);
* ``"hertz"``: small-strain Hertz for two plates, F = (4/3) E* sqrt(a0) (delta/2)^(3/2) with
  E* = 8 C (incompressible), i.e. F_eq = C a0^2 f(x), f(x) = (32/3) x^(3/2), x = delta / (2 a0)
  (independent of alpha; 4 % soft at x = 0.05, 30 % at x = 0.3 against the FE);
* a table: ``(x, f)`` arrays (x = delta/(2 a0) from 0, f = F_eq / (C a0^2)), or a :class:`MasterCurve`;
* a callable ``F_eq(delta, *, radius, C, alpha) -> N`` (JAX-traceable; its delta-derivative is taken
  by ``jax.jvp``).

The nominal stress (Pa) divides by the deformed midplane area, sigma~ = F / (pi r_mid^2), with r_mid
pluggable the same way (``midplane=``): ``"incompressible"`` (the volume-preserving oblate estimate
r_mid = a0 / sqrt(1 - x): a spheroid keeping its volume when its height shrinks by delta), ``"fem"``
(the calibrated g(x; alpha) = r_mid / a0), a table ``(x, g)``, or a callable
``r_mid(delta, *, radius, alpha) -> m``. ``midplane=None`` picks ``"fem"`` with ``equilibrium="fem"``,
else ``"incompressible"``.

Each spelling names a small law object (an ``equinox.Module``, immutable, compared by value), which may
also be passed directly: equilibrium :class:`Hertz`, :class:`FEMTable` (``FEMTable()`` is ``"fem"``;
``FEMTable(curve)`` a MasterCurve), :class:`Tabulated` ``(x, f)``, :class:`UserLaw` ``(fn)``; midplane
:class:`Incompressible`, :class:`FEMMidplane`, :class:`TabulatedMidplane` ``(x, g)``, :class:`UserMidplane`
``(fn)``. :func:`as_equilibrium_law` / :func:`as_midplane_law` map the spellings to them. A law's
``curve(alpha=, radius=, ...)`` gives x -> f(x) (or g(x)), calling it evaluates the law, ``check`` its x
range. Equal laws (equal table arrays included) reuse the compiled code.

Loading
-------
``displacement`` a number (m) and ``ramp_time`` (s): the approach grows linearly to ``displacement``
over ``ramp_time`` and is then held. The kink is handled exactly: the ramp and the hold are separate
pieces, and during the hold the branches decay in closed form, q_m(t) = q_m(t_r) e^{-(t-t_r)/tau_m}.
Over the ramp, two paths that agree to ~1e-13 (``method=``):

* ``"quadrature"`` (default): q_m is the convolution beta_m int e^{-(t-s)/tau_m} dF_eq/ds ds, summed
  between consecutive output times with the kernel absorbed exactly by z = e^{-(t-s)/tau} and the
  sqrt(t) of first contact removed by a square substitution, 16-point Gauss-Legendre per interval
  (graded into a stiff interval's boundary layer): no time stepping, any stiffness tau << t_r; with Hertz
  against the closed form at most 4.7e-9 for tau / t_r in [1e-4, 1e3] (at tau ~ 0.026 t_r; 1e-10 for
  tau in [0.1, 1] t_r, ~1e-15 for tau >= t_r: ``python notes/stiff_kernel_scan.py``; ~1e-8 with the
  spline table);
* ``"ode"``: diffrax integrates the ODE in v = sqrt(t / t_r) with steps landing on the output times;
  a PID controller at ``rtol``/``atol`` (1e-10). ``solver=None`` picks the explicit ``Tsit5`` when the
  parameters are concrete and ramp_time/tau <= 10, else the L-stable ESDIRK ``Kvaerno5``.

``displacement`` a callable delta(t) (m, JAX-traceable) instead: one diffrax solve (``method`` ignored)
over the output times, ``jump_times`` (s) naming any kinks of the history.

Every public function broadcasts over array parameters (one call = a grid of curves; output shape
``param_shape + t.shape``) and works under jit / vmap / grad / jacfwd. Eager calls validate inputs
and raise on solver failure; inside jit a failed solve gives NaN (check with ``jnp.isnan``).
"""

from __future__ import annotations

import functools
import json
import math
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any, NamedTuple, Union, cast

import diffrax
import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np

from tissuemech.reduced.interp import Spline1D, Spline2D
from tissuemech.reduced.validation import (
    is_traced,
    validate_branches,
    validate_finite,
    validate_int,
    validate_material,
    validate_nonnegative,
    validate_positive,
    validate_times,
)

__all__ = [
    "force",
    "nominal_stress",
    "midplane_radius",
    "equilibrium_force",
    "hertz_f",
    "MasterCurve",
    "master_curve",
    "DATA_FILE",
    "EquilibriumLaw",
    "Hertz",
    "FEMTable",
    "Tabulated",
    "UserLaw",
    "MidplaneLaw",
    "Incompressible",
    "FEMMidplane",
    "TabulatedMidplane",
    "UserMidplane",
    "as_equilibrium_law",
    "as_midplane_law",
]

DATA_FILE = Path(__file__).resolve().parent / "data" / "spheroid_master.npz"
Equilibrium = Union[str, Callable, tuple, "MasterCurve", "EquilibriumLaw"]
Midplane = Union[str, Callable, tuple, "MasterCurve", "MidplaneLaw", None]


def hertz_f(x: Any) -> jnp.ndarray:
    """Hertz master curve f(x) = F / (C a0^2) = (32/3) x^(3/2), x = delta / (2 a0) (E* = 8 C)."""
    x = jnp.maximum(jnp.asarray(x, dtype=jnp.float64), 0.0)
    return (32.0 / 3.0) * x * _sqrt_safe(x)  # derivative 16 sqrt(x): finite (0) at first contact


def _sqrt_safe(x):
    # sqrt with a finite derivative at 0 (gradient of x^1.5 at 0 is 0, and must not be NaN)
    return jnp.sqrt(jnp.where(x > 0, x, 1.0)) * (x > 0)


class MasterCurve:
    """Tabulated equilibrium master curves f(x; alpha) = F_eq/(C a0^2), g(x; alpha) = r_mid/a0.

    ``x`` (n_x,) from 0 (x = delta / (2 a0)), ``alpha`` (n_a,) or None for a single curve,
    ``f``/``g`` shaped (n_a, n_x) or (n_x,). Interpolated as f = f_Hertz(x) * h(sqrt(x), alpha) with h a
    C^2 spline in s = sqrt(x) (h -> 1 at x = 0 for a ball, h - 1 ~ sqrt(x)), and g directly in x. ``h``
    (optional, same shape as f) gives h = f / f_Hertz at the knots (its x = 0 value included), else it is
    computed from f (x = 0: extrapolated in s). ``x_max``/``alpha_range`` bound the table.
    """

    def __init__(
        self,
        x: np.ndarray,
        f: np.ndarray,
        g: np.ndarray | None = None,
        alpha: np.ndarray | None = None,
        metadata: dict | None = None,
        h: np.ndarray | None = None,
    ):
        x = np.asarray(x, dtype=float)
        f = np.asarray(f, dtype=float)
        if x.ndim != 1 or x.size < 3 or x[0] < 0 or np.any(np.diff(x) <= 0):
            raise ValueError("master curve: x = delta/(2 a0) must be >= 3 increasing values from 0")
        if np.any(~np.isfinite(f)):
            raise ValueError("master curve: f values must be finite")
        self.x, self.metadata = x, dict(metadata or {})
        self.x_max = float(x[-1])
        pos = x > 0
        hz = (32.0 / 3.0) * x[pos] ** 1.5
        # h = f / f_Hertz is splined in s = sqrt(x): for a ball between plates h - 1 grows like sqrt(x),
        # smooth in s (a spline in x would miss that; compare.calibrate)
        self.s = np.sqrt(x)

        def ratio(fr):
            r = np.empty_like(x)
            r[pos] = fr[pos] / hz
            if not pos.all():  # x = 0: extrapolate the ratio (quadratic in s) from the next points
                s1, s2, s3 = self.s[1:4] if x.size > 3 else (self.s[1], self.s[2], None)
                if s3 is None:
                    r[0] = r[1] - (r[2] - r[1]) * s1 / (s2 - s1)
                else:
                    l1, l2, l3 = (
                        s2 * s3 / ((s1 - s2) * (s1 - s3)),
                        s1 * s3 / ((s2 - s1) * (s2 - s3)),
                        s1 * s2 / ((s3 - s1) * (s3 - s2)),
                    )
                    r[0] = l1 * r[1] + l2 * r[2] + l3 * r[3]
            return r

        if alpha is None:
            if f.shape != x.shape:
                raise ValueError(f"master curve: f needs shape {x.shape}; got {f.shape}")
            self.alpha = None
            self._h = Spline1D(self.s, ratio(f) if h is None else np.asarray(h, float), ends="extrapolated")
            self._g = None if g is None else Spline1D(x, np.asarray(g, dtype=float))
            self.alpha_range = (0.0, np.inf)
        else:
            alpha = np.atleast_1d(np.asarray(alpha, dtype=float))
            if f.shape != (alpha.size, x.size):
                raise ValueError(
                    f"master curve: f needs shape (n_alpha, n_x) = ({alpha.size}, {x.size}); got {f.shape}"
                )
            self.alpha = alpha
            hv = np.stack([ratio(fr) for fr in f]) if h is None else np.asarray(h, float)
            self._h = Spline2D(self.s, alpha, hv, ends="extrapolated")
            self._g = None if g is None else Spline2D(x, alpha, np.asarray(g, dtype=float))
            self.alpha_range = (float(alpha[0]), float(alpha[-1]))

    def f(self, x: Any, alpha: Any = 0.0) -> jnp.ndarray:
        """F_eq / (C a0^2) at x = delta/(2 a0)."""
        s = _sqrt_safe(jnp.maximum(jnp.asarray(x, dtype=jnp.float64), 0.0))
        h = self._h(s) if self.alpha is None else self._h(s, alpha)
        return hertz_f(x) * h

    def f_curve(self, alpha: Any = 0.0) -> Callable:
        """x -> F_eq/(C a0^2) at one alpha (alpha interpolation done once: fast inside ODEs)."""
        h = self._h if self.alpha is None else self._h.curve(alpha)
        return lambda x: hertz_f(x) * h(_sqrt_safe(jnp.maximum(jnp.asarray(x, dtype=jnp.float64), 0.0)))

    def g_curve(self, alpha: Any = 0.0) -> Callable:
        """x -> r_mid / a0 at one alpha."""
        if self._g is None:
            raise ValueError("this master curve has no midplane-radius table g; use midplane='incompressible'")
        return self._g if self.alpha is None else self._g.curve(alpha)

    def g(self, x: Any, alpha: Any = 0.0) -> jnp.ndarray:
        """r_mid / a0 at x = delta/(2 a0)."""
        if self._g is None:
            raise ValueError("this master curve has no midplane-radius table g; use midplane='incompressible'")
        return self._g(x) if self.alpha is None else self._g(x, alpha)

    def check_range(self, x_max: Any, alpha: Any) -> None:
        """Raise ValueError (eager values only) outside the tabulated x and alpha."""
        if type(x_max) is float and type(alpha) is float:  # one point (the eager fast paths): no NumPy
            lo, hi = self.alpha_range if self.alpha is not None else (-math.inf, math.inf)
            if x_max <= self.x_max * (1 + 1e-12) and lo - 1e-12 <= alpha <= hi + 1e-12:
                return
        xv, av = _concrete(x_max), _concrete(alpha)
        if xv is not None and np.max(xv) > self.x_max * (1 + 1e-12):
            raise ValueError(
                f"compression delta/(2 a0) = {np.max(xv):.4g} is beyond the calibrated table (up to "
                f"{self.x_max:.4g}, i.e. {100 * self.x_max:.3g} % of the diameter). Use equilibrium='hertz' "
                "or a callable, or extend the table with `python -m tissuemech.compare.calibrate --x-max ...`."
            )
        if av is not None and self.alpha is not None:
            lo, hi = self.alpha_range
            if np.min(av) < lo - 1e-12 or np.max(av) > hi + 1e-12:
                span = f"{np.min(av):g}" if np.min(av) == np.max(av) else f"{np.min(av):g}..{np.max(av):g}"
                raise ValueError(
                    f"alpha = {span} is outside the calibrated table "
                    f"(alpha in [{lo:g}, {hi:g}]); use equilibrium='hertz' or extend the table."
                )


def _concrete(v):
    if is_traced(v):
        return None
    try:
        return np.asarray(v, dtype=float)
    except (TypeError, ValueError):
        return None


@functools.lru_cache(maxsize=4)
def master_curve(path: str | None = None) -> MasterCurve:
    """The FE-calibrated master curves shipped with the package (or read from ``path``)."""
    p = Path(path) if path is not None else DATA_FILE
    if not p.exists():
        raise FileNotFoundError(
            f"no calibrated spheroid table at {p}. Generate it with `python -m tissuemech.compare.calibrate`, "
            "or use equilibrium='hertz'."
        )
    with np.load(p, allow_pickle=False) as z:
        meta = json.loads(str(z["metadata"])) if "metadata" in z.files else {}
        h = z["f_over_hertz"] if "f_over_hertz" in z.files else None
        if h is not None and not np.all(np.isfinite(h)):
            h = None
        return MasterCurve(z["x"], z["f"], z["g"] if "g" in z.files else None, alpha=z["alpha"], metadata=meta, h=h)


# ---------------------------------------------------------------- equilibrium and midplane laws (dimensionless)
#
# A law is a small immutable object (an ``equinox.Module``): hashable and compared by value, so it is a
# static argument of the compiled cores (equal laws -> the compiled code is reused). Tables built from a
# user's arrays are cached by content (``_cached_table``): passing equal arrays again gives an equal law.


class EquilibriumLaw(eqx.Module):
    """An equilibrium law: the dimensionless master curve f(x) = F_eq / (C a0^2) at x = delta / (2 a0).

    Subclasses implement :meth:`curve`; :meth:`check` raises in eager calls outside the law's x range
    (every law: 0 <= x < 1, checked by the public functions; tables: x <= their last knot, alpha inside
    their alpha grid). ``knots`` are the x where the law is only piecewise smooth (the quadrature puts
    interval ends there)."""

    def curve(self, *, alpha: Any, radius: Any, C: Any) -> Callable[[Any], jnp.ndarray]:
        """x -> f(x) = F_eq / (C a0^2) for one parameter set (any work in alpha done once)."""
        raise NotImplementedError

    def __call__(self, x: Any, *, alpha: Any = 0.0, radius: Any = 1.0, C: Any = 1.0) -> jnp.ndarray:
        """f(x) = F_eq / (C a0^2) at x = delta / (2 a0) (dimensionless), for ``alpha``, ``radius`` (m),
        ``C`` (Pa) (only a user callable depends on radius and C)."""
        return self.curve(alpha=alpha, radius=radius, C=C)(jnp.asarray(x, dtype=jnp.float64))

    def knots(self, displacement: Any, radius: Any) -> Any:
        """x-values (dimensionless) of the law's kinks in smoothness over [0, X] (None: smooth)."""
        return None

    def check(self, x_max: Any, alpha: Any) -> None:
        """Raise ValueError (eager values only) where x up to ``x_max`` or ``alpha`` is outside the law."""

    @property
    def table(self) -> MasterCurve | None:
        """The master-curve table behind the law (None for closed forms and callables)."""
        return None


class Hertz(EquilibriumLaw):
    """Small-strain Hertz contact between two rigid plates: F = (4/3) E* sqrt(a0) (delta/2)^(3/2) with
    E* = 8 C (incompressible), i.e. f(x) = F_eq / (C a0^2) = (32/3) x^(3/2), x = delta / (2 a0).

    Independent of alpha; valid for any 0 <= x < 1 (no table range; 4 % soft against the FE at x = 0.05,
    30 % at x = 0.3)."""

    def curve(self, *, alpha: Any, radius: Any, C: Any) -> Callable[[Any], jnp.ndarray]:
        """x -> (32/3) x^(3/2) (its derivative 16 sqrt(x) is finite, 0, at first contact)."""
        return hertz_f


class FEMTable(EquilibriumLaw):
    """A tabulated master curve f(x; alpha) = F_eq / (C a0^2) (:class:`MasterCurve`): the FE-calibrated
    table shipped with the package (``FEMTable()``, the ``"fem"`` law) or any other MasterCurve.

    f = f_Hertz(x) h(sqrt(x), alpha), h a C^2 spline in sqrt(x) and alpha (h -> 1 at x = 0). Valid for
    0 <= x <= ``table.x_max`` and alpha in ``table.alpha_range`` (eager calls raise outside)."""

    master: MasterCurve

    def __init__(self, master: MasterCurve | None = None):
        self.master = master_curve() if master is None else master
        if not isinstance(self.master, MasterCurve):
            raise ValueError(f"FEMTable needs a MasterCurve table; got {type(self.master).__name__}")

    def curve(self, *, alpha: Any, radius: Any, C: Any) -> Callable[[Any], jnp.ndarray]:
        """x -> f_Hertz(x) h(sqrt(x), alpha) (the alpha interpolation done once)."""
        return self.master.f_curve(alpha)

    def knots(self, displacement: Any, radius: Any) -> Any:
        """The table's x knots (x = 0 excluded): the spline is C^2 but piecewise cubic."""
        return self.master.x[1:]

    def check(self, x_max: Any, alpha: Any) -> None:
        """x <= the table's last knot and alpha inside its grid (eager values only)."""
        self.master.check_range(x_max, alpha)

    @property
    def table(self) -> MasterCurve:
        """The MasterCurve."""
        return self.master


class Tabulated(FEMTable):
    """A user's single equilibrium curve: arrays ``x`` (from 0, increasing, >= 3 values; x = delta / (2 a0))
    and ``f`` = F_eq / (C a0^2) at those x (independent of alpha), interpolated as f_Hertz(x) h(sqrt(x))
    like the FE table. Valid for 0 <= x <= x[-1] (eager calls raise beyond). Equal arrays give an equal
    law (the table is cached by content), so compiled code is reused."""

    def __init__(self, x: Any, f: Any):
        self.master = cast(MasterCurve, _cached_table("f", _content_key((x, f))))

    def curve(self, *, alpha: Any, radius: Any, C: Any) -> Callable[[Any], jnp.ndarray]:
        """x -> f_Hertz(x) h(sqrt(x)) of the single tabulated curve."""
        return self.master.f_curve(alpha)


class UserLaw(EquilibriumLaw):
    """A user callable ``fn(delta, *, radius, C, alpha) -> F_eq`` (N; delta the total approach in m, radius
    in m, C in Pa), JAX-traceable; f(x) = fn(2 a0 x, ...) / (C a0^2). Its delta-derivative is taken by
    ``jax.jvp``. Valid wherever ``fn`` is, within 0 <= x < 1 (no table range); its smoothness is unknown,
    so the quadrature splits the ramp into 16 even intervals."""

    fn: Callable

    def curve(self, *, alpha: Any, radius: Any, C: Any) -> Callable[[Any], jnp.ndarray]:
        """x -> fn(2 a0 x, radius=a0, C=C, alpha=alpha) / (C a0^2)."""
        fn = self.fn
        return lambda x: fn(2.0 * radius * x, radius=radius, C=C, alpha=alpha) / (C * radius**2)

    def knots(self, displacement: Any, radius: Any) -> Any:
        """15 even interior points of [0, X]."""
        return np.linspace(0.0, 1.0, 17)[1:-1] * displacement / (2.0 * radius)


class MidplaneLaw(eqx.Module):
    """A midplane law: the deformed equator radius g(x) = r_mid / a0 at x = delta / (2 a0).

    Subclasses implement :meth:`curve`; :meth:`check` raises in eager calls outside the law's x range."""

    def curve(self, *, alpha: Any, radius: Any) -> Callable[[Any], jnp.ndarray]:
        """x -> g(x) = r_mid / a0 for one parameter set."""
        raise NotImplementedError

    def __call__(self, x: Any, *, alpha: Any = 0.0, radius: Any = 1.0) -> jnp.ndarray:
        """g(x) = r_mid / a0 at x = delta / (2 a0) (dimensionless), for ``alpha`` and ``radius`` (m)."""
        return self.curve(alpha=alpha, radius=radius)(jnp.asarray(x, dtype=jnp.float64))

    def check(self, x_max: Any, alpha: Any) -> None:
        """Raise ValueError (eager values only) where x up to ``x_max`` or ``alpha`` is outside the law."""

    @property
    def table(self) -> MasterCurve | None:
        """The master-curve table behind the law (None otherwise)."""
        return None


class Incompressible(MidplaneLaw):
    """The volume-preserving oblate estimate: a spheroid keeping the ball's volume when its height
    2 a0 shrinks by delta has g(x) = r_mid / a0 = 1 / sqrt(1 - x) (= 1 + x/2 + ... at small x).

    Valid for 0 <= x <= X_MAX = 0.999 (r_mid up to 31.6 a0): eager calls beyond it raise; traced calls are capped
    there, so they stay finite."""

    X_MAX = 0.999

    def curve(self, *, alpha: Any, radius: Any) -> Callable[[Any], jnp.ndarray]:
        """x -> 1 / sqrt(1 - min(x, X_MAX))."""
        return lambda x: 1.0 / jnp.sqrt(1.0 - jnp.minimum(x, self.X_MAX))

    def check(self, x_max: Any, alpha: Any) -> None:
        """x <= X_MAX (eager values only): beyond it the estimate 1/sqrt(1 - x) runs to infinity."""
        xv = _concrete(x_max)
        if xv is not None and np.max(xv) > self.X_MAX * (1 + 1e-12):
            raise ValueError(
                f"compression delta/(2 a0) = {np.max(xv):.6g} is beyond the incompressible midplane law's range "
                f"(up to {self.X_MAX}, where r_mid = {1 / np.sqrt(1 - self.X_MAX):.3g} a0): the plates nearly touch"
            )


class FEMMidplane(MidplaneLaw):
    """The calibrated midplane radius g(x; alpha) = r_mid / a0 of a :class:`MasterCurve` (``FEMMidplane()``:
    the shipped FE table, the ``"fem"`` midplane), a C^2 spline in x and alpha (g = 1 at x = 0).

    Valid for 0 <= x <= ``table.x_max`` and alpha in ``table.alpha_range``; the table must carry g."""

    master: MasterCurve

    def __init__(self, master: MasterCurve | None = None):
        self.master = master_curve() if master is None else master
        if not isinstance(self.master, MasterCurve):
            raise ValueError(f"FEMMidplane needs a MasterCurve table; got {type(self.master).__name__}")

    def curve(self, *, alpha: Any, radius: Any) -> Callable[[Any], jnp.ndarray]:
        """x -> g(x; alpha) (the alpha interpolation done once)."""
        return self.master.g_curve(alpha)

    def check(self, x_max: Any, alpha: Any) -> None:
        """x <= the table's last knot and alpha inside its grid (eager values only)."""
        self.master.check_range(x_max, alpha)

    @property
    def table(self) -> MasterCurve:
        """The MasterCurve."""
        return self.master


class TabulatedMidplane(MidplaneLaw):
    """A user's midplane table: arrays ``x`` (increasing; x = delta / (2 a0)) and ``g`` = r_mid / a0 at
    those x, a natural cubic spline in x (or an existing :class:`~tissuemech.reduced.interp.Spline1D` as
    ``TabulatedMidplane(spline=...)``). Valid for x <= x[-1] (eager calls raise beyond; not checked for a
    given spline). Equal arrays give an equal law (cached by content)."""

    spline: Spline1D
    x_max: float | None

    def __init__(self, x: Any = None, g: Any = None, *, spline: Spline1D | None = None):
        if spline is not None:
            self.spline, self.x_max = spline, None
            return
        if x is None or g is None:
            raise ValueError("TabulatedMidplane needs the arrays x (= delta/(2 a0)) and g (= r_mid/a0), or a spline")
        self.spline = cast(Spline1D, _cached_table("g", _content_key((x, g))))
        self.x_max = float(self.spline.knots[-1])

    def curve(self, *, alpha: Any, radius: Any) -> Callable[[Any], jnp.ndarray]:
        """x -> the spline through (x, g)."""
        return self.spline

    def check(self, x_max: Any, alpha: Any) -> None:
        """x <= the table's last knot (eager values only)."""
        xv = _concrete(x_max)
        if self.x_max is not None and xv is not None and np.max(xv) > self.x_max * (1 + 1e-12):
            raise ValueError(
                f"compression delta/(2 a0) = {np.max(xv):.4g} is beyond the midplane table (up to {self.x_max:.4g}, "
                f"i.e. {100 * self.x_max:.3g} % of the diameter); extend the table or use midplane='incompressible'."
            )


class UserMidplane(MidplaneLaw):
    """A user callable ``fn(delta, *, radius, alpha) -> r_mid`` (m; delta the total approach in m, radius in
    m), JAX-traceable; g(x) = fn(2 a0 x, ...) / a0. Valid wherever ``fn`` is, within 0 <= x < 1."""

    fn: Callable

    def curve(self, *, alpha: Any, radius: Any) -> Callable[[Any], jnp.ndarray]:
        """x -> fn(2 a0 x, radius=a0, alpha=alpha) / a0."""
        fn = self.fn
        return lambda x: fn(2.0 * radius * x, radius=radius, alpha=alpha) / radius


def as_equilibrium_law(spec: Any) -> EquilibriumLaw:
    """The law object for an ``equilibrium=`` value: ``"hertz"`` -> :class:`Hertz`, ``"fem"`` ->
    :class:`FEMTable` (the shipped table), a :class:`MasterCurve` -> ``FEMTable(curve)``, an ``(x, f)``
    tuple -> :class:`Tabulated`, a callable ``F_eq(delta, *, radius, C, alpha)`` -> :class:`UserLaw`;
    a law object is returned as it is.

    Raises ValueError for anything else (FileNotFoundError for ``"fem"`` without the shipped table)."""
    if isinstance(spec, EquilibriumLaw):
        return spec
    if isinstance(spec, str):
        if spec in ("hertz", "fem"):
            return _law_of(spec)
    elif isinstance(spec, tuple) and len(spec) == 2:
        return _law_of(Tabulated, _content_key(spec))
    elif isinstance(spec, MasterCurve) or (callable(spec) and not isinstance(spec, (MidplaneLaw, Spline1D))):
        try:
            return _law_of(spec)
        except TypeError:  # an unhashable callable: a fresh object (compiled per call)
            return FEMTable(spec) if isinstance(spec, MasterCurve) else UserLaw(spec)
    raise ValueError(f"equilibrium must be 'hertz', 'fem', an (x, f) table or a callable; got {spec!r}")


def as_midplane_law(spec: Any, equilibrium: Any = None) -> MidplaneLaw:
    """The law object for a ``midplane=`` value: ``"incompressible"`` -> :class:`Incompressible`, ``"fem"`` ->
    :class:`FEMMidplane` (the shipped table), a :class:`MasterCurve` -> ``FEMMidplane(curve)``, an
    ``(x, g)`` tuple or a Spline1D -> :class:`TabulatedMidplane`, a callable ``r_mid(delta, *, radius,
    alpha)`` -> :class:`UserMidplane`; a law object is returned as it is. ``None`` picks ``"fem"`` when
    ``equilibrium`` is the shipped table (``"fem"`` or ``FEMTable()``), else ``"incompressible"``.

    Raises ValueError for anything else."""
    if spec is None:
        shipped = isinstance(equilibrium, str) and equilibrium == "fem"
        if type(equilibrium) is FEMTable and DATA_FILE.exists():
            shipped = equilibrium.master is master_curve()
        spec = "fem" if shipped else "incompressible"
    if isinstance(spec, MidplaneLaw):
        return spec
    if isinstance(spec, str):
        if spec in ("incompressible", "fem"):
            return _midplane_of(spec)
    elif isinstance(spec, tuple) and len(spec) == 2:
        return _midplane_of(TabulatedMidplane, _content_key(spec))
    elif isinstance(spec, (MasterCurve, Spline1D)) or (callable(spec) and not isinstance(spec, EquilibriumLaw)):
        try:
            return _midplane_of(spec)
        except TypeError:  # an unhashable callable: a fresh object (compiled per call)
            return UserMidplane(cast(Callable, spec))
    raise ValueError(f"midplane must be 'incompressible', 'fem', an (x, g) table or a callable; got {spec!r}")


@functools.lru_cache(maxsize=64)
def _law_of(spec: Any, key: tuple | None = None) -> EquilibriumLaw:
    """One law object per public spelling (constructing and comparing equinox modules costs ~10 us: an
    eager call should find its law, and the compiled code keyed on it, by identity)."""
    if spec == "hertz":
        return Hertz()
    if spec == "fem":
        return FEMTable()
    if spec is Tabulated:
        x, f = (np.frombuffer(b, dtype=float).reshape(shape) for shape, b in cast(tuple, key))
        return Tabulated(x, f)
    if isinstance(spec, MasterCurve):
        return FEMTable(spec)
    return UserLaw(spec)


@functools.lru_cache(maxsize=64)
def _midplane_of(spec: Any, key: tuple | None = None) -> MidplaneLaw:
    """One midplane object per public spelling (see :func:`_law_of`)."""
    if spec == "incompressible":
        return Incompressible()
    if spec == "fem":
        return FEMMidplane()
    if spec is TabulatedMidplane:
        x, g = (np.frombuffer(b, dtype=float).reshape(shape) for shape, b in cast(tuple, key))
        return TabulatedMidplane(x, g)
    if isinstance(spec, MasterCurve):
        return FEMMidplane(spec)
    if isinstance(spec, Spline1D):
        return TabulatedMidplane(spline=spec)
    return UserMidplane(spec)


class _Midplane1D(Spline1D):
    """A user (x, g) midplane table (a hashable spline object, so compiled code is reused)."""


def _content_key(table: tuple) -> tuple:
    arrs = [np.ascontiguousarray(np.asarray(a, dtype=float)) for a in table]
    return tuple((a.shape, a.tobytes()) for a in arrs)


@functools.lru_cache(maxsize=32)
def _cached_table(kind: str, key: tuple):
    """One table object per content: a user's (x, f) or (x, g) arrays passed again in a later call give
    the same object, hence an equal law and reused compiled code (laws are static arguments)."""
    arrays = [np.frombuffer(b, dtype=float).reshape(shape) for shape, b in key]
    return MasterCurve(*cast(list[Any], arrays)) if kind == "f" else _Midplane1D(*arrays)


# ---------------------------------------------------------------- the lumped ODE


class _Opts(NamedTuple):
    rtol: float
    atol: float
    max_steps: int
    solver: Any
    adjoint: Any
    method: str = "quadrature"


def _adjoint(kind: Any):
    if kind == "reverse":
        return diffrax.RecursiveCheckpointAdjoint()
    if kind == "forward":
        return diffrax.ForwardMode()
    if isinstance(kind, diffrax.AbstractAdjoint):
        return kind
    raise ValueError(
        f"adjoint must be 'reverse' (jax.grad/jacrev), 'forward' (jax.jacfwd/jvp) or a diffrax adjoint; got {kind!r}"
    )


@functools.partial(jax.jit, static_argnums=(4,))
def _run(flat_t, params, betas, taus, static):
    law, mid, history, jumps, o, stress, shape = static
    disp = history if history is not None else None

    def one(p, bs, ts, batch_axis=None):
        b = jnp.stack(bs) if bs else jnp.zeros(0)
        tau = jnp.stack(ts) if ts else jnp.ones(0)
        return _curve(
            flat_t,
            p["radius"],
            p["C"],
            p["alpha"],
            b,
            tau,
            disp if disp is not None else p["displacement"],
            p.get("ramp_time"),
            law,
            mid,
            jumps,
            o,
            stress,
            batch_axis,
        )

    if shape == ():
        out, ok = one(params, betas, taus)
    else:
        bc = lambda v: jnp.broadcast_to(v, shape).reshape(-1)
        out, ok = jax.vmap(lambda p, bs, ts: one(p, bs, ts, "params"), axis_name="params")(
            {k: bc(v) for k, v in params.items()}, tuple(bc(b) for b in betas), tuple(bc(tau) for tau in taus)
        )
    return out.reshape(shape + flat_t.shape[:0] + (-1,)) if shape else out, ok


_GL_NODES, _GL_WEIGHTS = np.polynomial.legendre.leggauss(16)
_ZETA = (_GL_NODES + 1.0) / 2.0  # Gauss-Legendre on [0, 1] in zeta, eta = zeta^2
_ETA = _ZETA**2
_W_ETA = _ZETA * _GL_WEIGHTS  # d eta = 2 zeta d zeta, times the [0, 1] weights w / 2
_CHUNK = 8  # ramp intervals integrated per step of the chunk loop (the rest of a chunk loop is skipped)


def _ramp_hold_quadrature(t, f, X, tr, betas, taus, knots=None, batch_axis=None):
    """Dimensionless F/(C a0^2) at times t for x(t) = X min(t/tr, 1), by exact-kernel quadrature.

    In ramp units s = t/tr (k_m = tr/tau_m), q_m(s) = beta_m int_0^s e^{-k_m (s-u)} phi(u) du with
    phi(u) = d f(X u)/du. Between consecutive output points s_{j-1} < s_j:
        q(s_j) = e^{-k D} q(s_{j-1}) + beta int_{s_{j-1}}^{s_j} e^{-k (s_j - u)} phi(u) du,  D = s_j - s_{j-1},
    and the interval integral, after z = e^{-k (s_j - u)} (which absorbs the kernel exactly, for any
    stiffness k D) and z = z0 + (1 - z0) eta^2 (which removes the sqrt(u) of first contact), is
        (1 - z0)/k int_0^1 phi(s_j + log(z)/k) 2 eta d eta,   1 - z0 = -expm1(-k D),
    evaluated with 16-point Gauss-Legendre in zeta = sqrt(eta). A stiff interval (z0 = e^{-k D} small) has
    a boundary layer of width sqrt(z0) in eta (its integrand is singular at eta = +-i sqrt(z0 / (1 - z0)));
    in zeta that distance is z0^(1/4), so the same 16 nodes resolve it: against the closed form (Hertz,
    Dawson's integral) the largest error over tau / t_r in [1e-4, 1e3] drops from 5.9e-7 (Gauss in eta,
    at tau ~ 0.023 t_r) to 4.7e-9 (``python notes/stiff_kernel_scan.py [--eta]``). No time stepping: every output
    point at once.

    The sorted points (output times clipped to the ramp, and ``knots``) are walked in chunks of
    ``_CHUNK`` intervals; a chunk that starts at the end of the ramp (s = 1: hold outputs and knots
    beyond X, whose intervals are empty) is skipped by ``lax.cond``. The cost follows the number of
    ramp points at run time, also under jit with traced times (their count is not known when
    tracing). ``batch_axis``: the vmap axis over parameter sets, whose largest count is used, so the
    skip stays a branch (not a select) under vmap.
    ``knots``: x-values where the equilibrium law is only piecewise smooth (a spline table's knots);
    they become interval ends too, so every Gauss rule sees a smooth integrand (callables: 16 even
    points; Hertz: none needed)."""
    n = betas.shape[0]
    s = jnp.clip(t / tr, 0.0, 1.0)
    feq = f(X * s)
    if n == 0:
        return feq, jnp.asarray(True)
    extra = jnp.zeros(0) if knots is None else jnp.clip(jnp.asarray(knots, dtype=jnp.float64) / X, 0.0, 1.0)
    pts = jnp.concatenate([s, extra])
    order2 = jnp.argsort(pts)
    inv = jnp.argsort(order2)
    n_int = pts.shape[0] + 1  # intervals 0 -> sorted points -> 1
    n_chunks = -(-n_int // _CHUNK)
    pad = n_chunks * _CHUNK - n_int
    # 0, sorted ramp outputs and knots, 1 (and empty intervals at 1 up to a whole number of chunks)
    grid = jnp.concatenate([jnp.zeros(1), pts[order2], jnp.ones(1 + pad)])
    active = jnp.sum(pts < 1.0) + 1  # intervals that start inside the ramp
    if batch_axis is not None:
        active = jax.lax.pmax(active, batch_axis)
    k = (tr / taus)[:, None]  # (n, 1)
    eta = jnp.asarray(_ETA)
    w_eta = 2.0 * eta * jnp.asarray(_W_ETA)
    bcol = betas[:, None]

    def integrate(q, s0, s1):
        D = s1 - s0  # (K,)
        one_minus_z0 = -jnp.expm1(-k * D)  # (n, K)
        # u at the nodes: (n, K, G); log z = log1p(-(1 - z0)(1 - eta^2))
        u = s1[None, :, None] + jnp.log1p(-one_minus_z0[..., None] * (1.0 - eta**2)) / k[..., None]
        u = jnp.clip(u, s0[None, :, None], s1[None, :, None])
        _, dfx = jax.jvp(f, (X * u,), (jnp.full(u.shape, X),))  # phi(u) = X f'(X u)
        # weight (1 - z0)/k, safe as k D -> 0 (then -> D)
        wk = jnp.where(k * D > 1e-300, one_minus_z0 / k, D)
        I = wk * jnp.sum(dfx * w_eta, axis=-1)  # (n, K)
        decay = jnp.exp(-k * D)  # (n, K)

        def step(q, inputs):
            dec, inc = inputs
            q = dec * q + inc
            return q, q

        return jax.lax.scan(step, q, (decay.T, (bcol * I).T))  # (n,), (K, n)

    def chunk(q, inputs):
        c, s0, s1 = inputs
        return jax.lax.cond(
            c * _CHUNK < active,
            integrate,
            lambda q, s0, s1: (q, jnp.broadcast_to(q, (_CHUNK, n))),  # the ramp is over: q stays q(1)
            q,
            s0,
            s1,
        )

    chunks = (jnp.arange(n_chunks), grid[:-1].reshape(n_chunks, _CHUNK), grid[1:].reshape(n_chunks, _CHUNK))
    q_end, qs = jax.lax.scan(chunk, jnp.zeros(n), chunks)
    q_ramp = qs.reshape(-1, n)[inv[: t.shape[0]]]  # q at each output's point (interval j ends at point j)
    hold = q_end * jnp.exp(-jnp.maximum(t - tr, 0.0)[:, None] / taus)
    q = jnp.where((t <= tr)[:, None], q_ramp, hold)
    ok = jnp.all(jnp.isfinite(q))
    return feq + jnp.sum(q, axis=-1), ok


def _ramp_hold(t, f, X, tr, betas, taus, o: _Opts):
    """Dimensionless F/(C a0^2) at times t (1-D, any order) for x(t) = X min(t/tr, 1)."""
    n = betas.shape[0]
    fX = f(X)
    scale = jnp.where(fX > 0, fX, 1.0)
    s = jnp.clip(t / tr, 0.0, 1.0)
    x_t = X * s
    feq = f(x_t)
    if n == 0:
        return feq, jnp.asarray(True)
    k = tr / taus  # ramp time over relaxation times

    def rhs(v, q, args):
        # s = v^2, ds = 2 v dv; dq/ds = -k q + beta X f'(X s) / f(X)
        _, df = jax.jvp(f, (X * v * v,), (X * 2.0 * v,))
        return -k * q * 2.0 * v + betas * df / scale

    vs = jnp.sqrt(s)
    order = jnp.argsort(vs)
    sol = diffrax.diffeqsolve(
        diffrax.ODETerm(rhs),
        o.solver,
        t0=0.0,
        t1=1.0,
        dt0=1e-3,
        y0=jnp.zeros(n),
        saveat=diffrax.SaveAt(ts=vs[order], t1=True),
        # steps land on the output times: saved values are step values, not the (lower-order) interpolant
        stepsize_controller=diffrax.ClipStepSizeController(
            diffrax.PIDController(rtol=o.rtol, atol=o.atol), step_ts=vs[order]
        ),
        max_steps=o.max_steps,
        adjoint=o.adjoint,
        throw=False,
    )
    q_ramp = jnp.zeros((t.shape[0], n)).at[order].set(sol.ys[:-1])
    q_end = sol.ys[-1]
    hold = q_end * jnp.exp(-jnp.maximum(t - tr, 0.0)[:, None] / taus)
    q = jnp.where((t <= tr)[:, None], q_ramp, hold) * scale
    return feq + jnp.sum(q, axis=-1), sol.result == diffrax.RESULTS.successful


def _history(t, f, x_of_t, betas, taus, jumps, o: _Opts):
    """Dimensionless force for a general approach history x(t) (t sorted ascending inside)."""
    n = betas.shape[0]
    feq = f(x_of_t(t))
    if n == 0:
        return feq, jnp.asarray(True)
    T = jnp.max(t)
    scale = jnp.maximum(jnp.max(jnp.abs(feq)), 1e-300)

    def rhs(tt, q, args):
        _, df = jax.jvp(lambda s: f(x_of_t(s)), (tt,), (jnp.ones_like(tt),))
        return -q / taus + betas * df / scale

    order = jnp.argsort(t)
    controller = diffrax.ClipStepSizeController(
        diffrax.PIDController(rtol=o.rtol, atol=o.atol),
        step_ts=t[order],
        jump_ts=None if jumps is None else jnp.asarray(jumps, dtype=jnp.float64),
    )
    sol = diffrax.diffeqsolve(
        diffrax.ODETerm(rhs),
        o.solver,
        t0=0.0,
        t1=T,
        dt0=T * 1e-4,
        y0=jnp.zeros(n),
        saveat=diffrax.SaveAt(ts=t[order]),
        stepsize_controller=controller,
        max_steps=o.max_steps,
        adjoint=o.adjoint,
        throw=False,
    )
    q = jnp.zeros((t.shape[0], n)).at[order].set(sol.ys) * scale
    return feq + jnp.sum(q, axis=-1), sol.result == diffrax.RESULTS.successful


def _curve(
    t, radius, C, alpha, betas, taus, displacement, ramp_time, law, mid, jumps, o, stress: bool, batch_axis=None
):
    """Force (N) or nominal stress (Pa) at flat times t for scalar parameters (``law``/``mid``: law objects)."""
    f = law.curve(alpha=alpha, radius=radius, C=C)
    if callable(displacement):

        def x_of_t(tt):
            return displacement(tt) / (2.0 * radius)

        fhat, ok = _history(t, f, x_of_t, betas, taus, jumps, o)
        x_t = x_of_t(t)
    else:
        X = displacement / (2.0 * radius)
        if o.method == "quadrature":
            knots = law.knots(displacement, radius)
            fhat, ok = _ramp_hold_quadrature(t, f, X, ramp_time, betas, taus, knots, batch_axis)
        else:
            fhat, ok = _ramp_hold(t, f, X, ramp_time, betas, taus, o)
        x_t = X * jnp.clip(t / ramp_time, 0.0, 1.0)
    out = fhat * C * radius**2
    if stress:
        g = mid.curve(alpha=alpha, radius=radius)
        out = out / (jnp.pi * (radius * g(x_t)) ** 2)
    return jnp.where(ok, out, jnp.nan), ok


def _evaluate(
    t,
    *,
    radius,
    C,
    alpha,
    branches,
    displacement,
    ramp_time,
    equilibrium,
    midplane,
    jump_times,
    rtol,
    atol,
    max_steps,
    solver,
    adjoint,
    method,
    stress,
):
    br = validate_branches(branches)
    eager = not is_traced(
        t,
        radius,
        C,
        alpha,
        ramp_time,
        *(v for b in br for v in b),
        *(() if callable(displacement) else (displacement,)),
    )
    if eager:
        _check_inputs(t, radius, C, alpha, displacement, ramp_time, equilibrium, midplane, jump_times, stress)
    _check_solver_options(rtol, atol, max_steps)
    t_arr = jnp.asarray(t, dtype=jnp.float64)  # after the checks: their messages name t, numpy's would not
    betas = tuple(jnp.asarray(b, dtype=jnp.float64) for b, _ in br)
    taus = tuple(jnp.asarray(tau, dtype=jnp.float64) for _, tau in br)
    params = dict(radius=radius, C=C, alpha=alpha)
    if not callable(displacement):
        params.update(displacement=displacement, ramp_time=ramp_time)
    params = {k: jnp.asarray(v, dtype=jnp.float64) for k, v in params.items()}
    shapes = {
        **{k: v.shape for k, v in params.items()},
        **{f"beta of branch {m}": b.shape for m, b in enumerate(betas)},
    }
    shapes.update({f"tau of branch {m}": tau.shape for m, tau in enumerate(taus)})
    try:
        shape = jnp.broadcast_shapes(*shapes.values())
    except ValueError:
        given = ", ".join(f"{k} {v}" for k, v in shapes.items() if v != ())
        raise ValueError(
            f"the parameter arrays do not broadcast together ({given}): give them shapes that broadcast, e.g. "
            "(2, 1) and (3,) for a 2 x 3 grid"
        ) from None
    if solver is None:
        solver = diffrax.Kvaerno5()  # L-stable: safe for any tau / ramp ratio
        if eager and br and not callable(displacement):
            stiff = np.max(
                np.asarray(ramp_time, dtype=float) / np.min([np.min(np.asarray(tau, dtype=float)) for _, tau in br])
            )
            if stiff <= 10.0:
                solver = diffrax.Tsit5()  # non-stiff: the explicit solver is ~4x faster
    if method not in ("quadrature", "ode"):
        raise ValueError(
            f"method must be 'quadrature' (fast default for a ramp-and-hold) or 'ode' (diffrax); got {method!r}"
        )
    o = _Opts(float(rtol), float(atol), int(max_steps), solver, _adjoint(adjoint), method)
    law = as_equilibrium_law(equilibrium)
    mid = as_midplane_law(midplane, equilibrium) if stress else None
    static = (
        law,
        mid,
        displacement if callable(displacement) else None,
        None if jump_times is None else tuple(float(j) for j in jump_times),
        o,
        stress,
        shape,
    )
    out, ok = _run(t_arr.reshape(-1), params, betas, taus, static)
    if eager and not bool(np.all(np.asarray(ok))):
        raise RuntimeError(
            f"the lumped viscoelastic ODE failed for {int(np.size(ok) - np.sum(np.asarray(ok)))} of "
            f"{int(np.size(ok))} parameter sets. Hint: raise max_steps (now {max_steps}), loosen rtol/atol, "
            "or check that the relaxation times are not absurdly short compared with the ramp."
        )
    out = out.reshape(shape + t_arr.shape)
    if eager and callable(displacement) and bool(np.any(np.asarray(out) < 0)):
        raise ValueError(
            "displacement history: the plate force turns negative (the plates would lose contact: the "
            "approach decreases faster than the ball relaxes); the lumped model holds only while the "
            "plates push (force >= 0 N). Shorten the history or unload more slowly"
        )
    return out


def force(
    t: Any,
    *,
    radius: Any,
    C: Any,
    alpha: Any,
    branches: Sequence[tuple[Any, Any]] = (),
    displacement: Any,
    ramp_time: Any = None,
    equilibrium: Equilibrium = "fem",
    jump_times: Sequence[float] | None = None,
    rtol: float = 1e-10,
    atol: float = 1e-10,
    max_steps: int = 16384,
    solver: Any = None,
    adjoint: Any = "reverse",
    method: str = "quadrature",
) -> jnp.ndarray:
    r"""Plate force F(t) in N of the lumped generalized-Maxwell spheroid.

    F = F_eq(delta) + sum_m q_m,  dq_m/dt = -q_m/tau_m + beta_m dF_eq/dt,  q_m(0) = 0.

    t            output times (s), any shape, >= 0 (t = 0 is first contact).
    radius       ball radius a0 (m).       C, alpha   Fung parameters (Pa, -).
    branches     sequence of (beta, tau): energy factor (-) and relaxation time (s); () = elastic.
    displacement total approach delta of the plates (m) reached at ``ramp_time`` (s) and then held;
                 or a callable delta(t) (m) for any history (``jump_times``: its kinks, s).
    equilibrium  "hertz", "fem" (FE-calibrated table), an (x, f) table or a callable (module doc).
    Parameters broadcast: the result has shape ``broadcast(params).shape + t.shape``.
    """
    return _evaluate(
        t,
        radius=radius,
        C=C,
        alpha=alpha,
        branches=branches,
        displacement=displacement,
        ramp_time=ramp_time,
        equilibrium=equilibrium,
        midplane=None,
        jump_times=jump_times,
        rtol=rtol,
        atol=atol,
        max_steps=max_steps,
        solver=solver,
        adjoint=adjoint,
        method=method,
        stress=False,
    )


def nominal_stress(
    t: Any,
    *,
    radius: Any,
    C: Any,
    alpha: Any,
    branches: Sequence[tuple[Any, Any]] = (),
    displacement: Any,
    ramp_time: Any = None,
    equilibrium: Equilibrium = "fem",
    midplane: Midplane = None,
    jump_times: Sequence[float] | None = None,
    rtol: float = 1e-10,
    atol: float = 1e-10,
    max_steps: int = 16384,
    solver: Any = None,
    adjoint: Any = "reverse",
    method: str = "quadrature",
) -> jnp.ndarray:
    r"""Nominal stress sigma~(t) = F(t) / (pi r_mid(delta(t))^2) in Pa (the seed's observable).

    Same arguments as :func:`force`; ``midplane`` chooses r_mid: "incompressible" (a0/sqrt(1 - x)),
    "fem" (calibrated), an (x, g) table, a callable r_mid(delta, *, radius, alpha) (m), or None (auto).
    """
    return _evaluate(
        t,
        radius=radius,
        C=C,
        alpha=alpha,
        branches=branches,
        displacement=displacement,
        ramp_time=ramp_time,
        equilibrium=equilibrium,
        midplane=midplane,
        jump_times=jump_times,
        rtol=rtol,
        atol=atol,
        max_steps=max_steps,
        solver=solver,
        adjoint=adjoint,
        method=method,
        stress=True,
    )


def equilibrium_force(
    displacement: Any, *, radius: Any, C: Any, alpha: Any, equilibrium: Equilibrium = "fem"
) -> jnp.ndarray:
    """Elastic equilibrium force F_eq(delta) = C a0^2 f(delta / (2 a0)) in N.

    displacement  total approach delta of the plates (m), any shape, 0 <= delta < 2 radius.
    radius        ball radius a0 (m).       C, alpha   Fung parameters (Pa, -).
    equilibrium   "hertz", "fem" (FE-calibrated table), a MasterCurve, an (x, f) table, a callable
                  F_eq(delta, *, radius, C, alpha) (N), or a law object (:class:`Hertz`, :class:`FEMTable`...).
    Returns F_eq (N), shape broadcast(displacement, radius, C).
    Raises ValueError (eager calls) for a bad value (naming it and its unit), an unknown law, or an
    approach beyond the law's table. Eager calls validate here and run one compiled kernel.
    """
    fast = _plain_numbers(displacement, radius, C, alpha)
    if fast is not None:  # one point given as plain numbers: the checks in scalar arithmetic (~1 us)
        d, r, c, a = fast
        if r > 0 and c > 0 and a >= 0 and 0 <= d < 2.0 * r:
            law = as_equilibrium_law(equilibrium)
            type(law).check(law, d / (2.0 * r), a)
            return _equilibrium_core(law, d, r, c, a)
    elif fast_params := _plain_numbers(radius, C, alpha) if _float_array(displacement) else None:
        # an array of approaches: its range checked in one NumPy pass, then one compiled kernel
        r, c, a = fast_params
        if r > 0 and c > 0 and a >= 0:
            law = as_equilibrium_law(equilibrium)
            hi = _array_max_below(displacement, 2.0 * r)
            if hi is not None:
                type(law).check(law, hi / (2.0 * r), a)
                return _equilibrium_core(law, displacement, r, c, a)
    if not is_traced(displacement, radius, C, alpha):
        r = validate_positive("radius (of the ball)", radius, "m")
        validate_material(C, alpha)
        d = validate_finite("displacement (the total approach of the plates)", displacement, "m")
        x_hi = _approach_max("displacement", d, r)
        law = as_equilibrium_law(equilibrium)
        type(law).check(law, x_hi, alpha)
        return _equilibrium_core(law, d, r, np.asarray(C, dtype=float), np.asarray(alpha, dtype=float))
    return _equilibrium_core(as_equilibrium_law(equilibrium), displacement, radius, C, alpha)


@functools.partial(jax.jit, static_argnums=(0,))
def _equilibrium_core(law: EquilibriumLaw, displacement, radius, C, alpha):
    x = jnp.asarray(displacement, dtype=jnp.float64) / (2.0 * jnp.asarray(radius, dtype=jnp.float64))
    if jnp.ndim(alpha) == 0:  # one alpha: the law's curve is made once (its alpha interpolation done once)
        return law.curve(alpha=alpha, radius=radius, C=C)(x) * C * jnp.asarray(radius) ** 2
    # an array of alphas: one curve per point (a law's curve is made for ONE alpha)
    return _pointwise(lambda xi, ai, ri, ci: law.curve(alpha=ai, radius=ri, C=ci)(xi) * ci * ri**2, x, alpha, radius, C)


def _pointwise(fn: Callable, *args):
    """fn over the broadcast arguments, point by point (vmap over the flattened broadcast), in their shape."""
    arrs = [jnp.asarray(a, dtype=jnp.float64) for a in args]
    shape = jnp.broadcast_shapes(*(a.shape for a in arrs))
    flat = [jnp.broadcast_to(a, shape).reshape(-1) for a in arrs]
    return jax.vmap(fn)(*flat).reshape(shape)


def midplane_radius(
    displacement: Any, *, radius: Any, alpha: Any = 0.0, midplane: Midplane = "incompressible"
) -> jnp.ndarray:
    """Deformed equator radius r_mid = a0 g(delta / (2 a0)) in m at total approach ``displacement`` (m).

    displacement  total approach delta of the plates (m), any shape, 0 <= delta < 2 radius.
    radius        ball radius a0 (m).       alpha   Fung exponent (-), used by the "fem" table.
    midplane      "incompressible" (a0 / sqrt(1 - x)), "fem" (calibrated), a MasterCurve, an (x, g) table,
                  a callable r_mid(delta, *, radius, alpha) (m), or a law object (:class:`Incompressible`...).
    Returns r_mid (m), shape broadcast(displacement, radius).
    Raises ValueError (eager calls) for a bad value (naming it and its unit), an unknown law, or an
    approach beyond the law's table. Eager calls validate here and run one compiled kernel.
    """
    fast = _plain_numbers(displacement, radius, alpha)
    if fast is not None:  # one point given as plain numbers: the checks in scalar arithmetic (~1 us)
        d, r, a = fast
        if r > 0 and a >= 0 and 0 <= d < 2.0 * r:
            law = as_midplane_law(midplane)
            type(law).check(law, d / (2.0 * r), a)
            return _midplane_core(law, d, r, a)
    elif fast_params := _plain_numbers(radius, alpha) if _float_array(displacement) else None:
        # an array of approaches: its range checked in one NumPy pass, then one compiled kernel
        r, a = fast_params
        if r > 0 and a >= 0:
            law = as_midplane_law(midplane)
            hi = _array_max_below(displacement, 2.0 * r)
            if hi is not None:
                type(law).check(law, hi / (2.0 * r), a)
                return _midplane_core(law, displacement, r, a)
    if not is_traced(displacement, radius, alpha):
        r = validate_positive("radius (of the ball)", radius, "m")
        validate_nonnegative("alpha (the Fung stiffening exponent)", alpha, "dimensionless")
        d = validate_finite("displacement (the total approach of the plates)", displacement, "m")
        x_hi = _approach_max("displacement", d, r)
        law = as_midplane_law(midplane)
        type(law).check(law, x_hi, alpha)
        return _midplane_core(law, d, r, np.asarray(alpha, dtype=float))
    return _midplane_core(as_midplane_law(midplane), displacement, radius, alpha)


@functools.partial(jax.jit, static_argnums=(0,))
def _midplane_core(law: MidplaneLaw, displacement, radius, alpha):
    x = jnp.asarray(displacement, dtype=jnp.float64) / (2.0 * jnp.asarray(radius, dtype=jnp.float64))
    if jnp.ndim(alpha) == 0:
        return jnp.asarray(radius) * law.curve(alpha=alpha, radius=radius)(x)
    return _pointwise(lambda xi, ai, ri: ri * law.curve(alpha=ai, radius=ri)(xi), x, alpha, radius)


# ---------------------------------------------------------------- input checks of the public entry points


_NUMBER_TYPES = (float, int, np.floating, np.integer)


def _float_array(v: Any) -> bool:
    """A concrete (not traced) NumPy or JAX array of floats."""
    return isinstance(v, (np.ndarray, jax.Array)) and not is_traced(v) and v.dtype.kind == "f"


def _array_max_below(d: Any, upper: float) -> float | None:
    """The largest entry of a concrete float array when every entry lies in [0, upper) (upper > 0), else None
    (the caller then runs the full validators, which name the offending value; so does an empty array).

    One NumPy pass, before the compiled kernel (which uses both cores: run alongside it, the pass slowed it more
    than it cost). For float64 it is the maximum of the bit patterns read as unsigned integers, which order like
    the values for +0 and positive finite floats and put every negative value (sign bit) and NaN / inf above any
    finite ``upper`` (-0.0 too: it goes to the validators, which accept it); min and max for other float types."""
    v = np.asarray(d)
    if v.size == 0 or not upper > 0.0:
        return None
    if v.dtype == np.float64:
        bits = int(np.max(v.view(np.uint64)))
        if bits < int(np.float64(upper).view(np.uint64)):
            return float(np.uint64(bits).view(np.float64))
        return None
    lo, hi = float(np.min(v)), float(np.max(v))
    return hi if 0.0 <= lo and hi < upper else None


def _plain_numbers(*values: Any) -> tuple[float, ...] | None:
    """The values as Python floats when every one is a single finite real number (Python or NumPy
    scalar, not a bool), else None: the eager entry points then take the full validators (the same
    checks, a one-line error naming the quantity; ~50 us more). A validator of this module, not of
    ``reduced.validation``: it only decides which path checks, never what is accepted."""
    out = []
    for v in values:
        if not isinstance(v, _NUMBER_TYPES) or isinstance(v, (bool, np.bool_)):
            return None
        fv = float(v)
        if not math.isfinite(fv):
            return None
        out.append(fv)
    return tuple(out)


def _check_solver_options(rtol: Any, atol: Any, max_steps: Any) -> None:
    validate_positive("rtol (relative tolerance of the ODE solver)", rtol, "dimensionless")
    validate_positive("atol (absolute tolerance of the ODE solver)", atol, "dimensionless")
    validate_int("max_steps (of the ODE solver)", max_steps, minimum=1)


def _approach_max(name: str, d: Any, r: Any) -> float:
    """max of x = d / (2 r) after :func:`_check_approach` (two passes over d when r is one number; the
    full check, with its message, only when something is wrong)."""
    d, r = np.asarray(d), np.asarray(r)
    if r.size == 1:
        lo, hi = float(np.min(d)) / (2.0 * float(r.reshape(-1)[0])), float(np.max(d)) / (2.0 * float(r.reshape(-1)[0]))
        if math.isfinite(lo) and math.isfinite(hi) and lo >= 0 and hi < 1:
            return hi
    x = d / (2.0 * r)
    _check_approach(name, x)
    return float(np.max(x))


def _check_approach(name: str, x_over_diameter: np.ndarray, where: str = "") -> None:
    """An approach delta/(2 a0) must be finite, >= 0 and below 1 (the plates cannot pass each other)."""
    if not np.all(np.isfinite(x_over_diameter)):
        raise ValueError(f"{name} (the total approach of the plates, in m) must be finite{where}")
    if np.any(x_over_diameter < 0):
        raise ValueError(
            f"{name} (the total approach of the plates, in m) must not be negative{where}: "
            f"got delta/(2 radius) = {np.min(x_over_diameter):.4g}"
        )
    if np.any(x_over_diameter >= 1):
        raise ValueError(
            f"{name} (the total approach of the plates, in m) must be smaller than the ball's diameter "
            f"2 * radius{where}: got delta/(2 radius) = {np.max(x_over_diameter):.4g}"
        )


def _check_inputs(
    t, radius, C, alpha, displacement, ramp_time, equilibrium, midplane, jump_times, stress: bool = False
) -> None:
    """Eager checks of force / nominal_stress (every message names the quantity and its unit); the laws
    (converted last, so a bad value is named before a bad law) check their own ranges."""
    validate_times("t (output times, t = 0 is first contact)", t, unit="s")
    r = validate_positive("radius (of the ball)", radius, "m")
    validate_material(C, alpha)
    if jump_times is not None:
        validate_times("jump_times (kinks of the displacement history)", jump_times, unit="s")

    def laws() -> list[EquilibriumLaw | MidplaneLaw]:
        eq = as_equilibrium_law(equilibrium)
        return [eq, as_midplane_law(midplane, equilibrium)] if stress else [eq]

    if callable(displacement):
        tn = np.asarray(t, dtype=float).ravel()
        probe = np.union1d(tn, np.linspace(0.0, float(np.max(tn)), 257))
        try:
            d = np.asarray(jax.vmap(displacement)(jnp.asarray(probe)), dtype=float)
        except Exception as exc:
            raise ValueError(
                f"displacement (a callable delta(t) in m) failed when called on the output times: {exc}"
            ) from None
        if d.shape != probe.shape:
            raise ValueError(
                f"displacement (a callable delta(t) in m) must return one number per time; got shape {d.shape}"
            )
        x = d / (2.0 * float(np.min(r)))
        _check_approach("displacement history", x, " at every time")
        if abs(float(x[0])) > 1e-12:
            raise ValueError(
                f"displacement history: delta(0) = {d[0]:g} m, but the model starts at first contact "
                "(delta(0) = 0 m, branches at rest); start the history at 0"
            )
        for law in laws():
            cast(Any, type(law)).check(law, np.max(x), alpha)
        return
    validate_positive("displacement (the total approach of the plates)", displacement, "m")
    if ramp_time is None:
        raise ValueError("ramp_time (s) is needed with a numeric displacement (linear ramp, then hold)")
    validate_positive("ramp_time (duration of the loading ramp)", ramp_time, "s")
    if np.any(np.asarray(displacement, dtype=float) >= 2 * np.asarray(radius, dtype=float)):
        raise ValueError("displacement (total approach) must be smaller than the ball's diameter 2 * radius")
    x_max = np.asarray(displacement, dtype=float) / (2 * np.asarray(radius, dtype=float))
    for law in laws():
        cast(Any, type(law)).check(law, x_max, alpha)
