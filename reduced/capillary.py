r"""The elastocapillary equilibrium law of the spheroid: a Fung ball with a surface tension between plates.

A ball of radius ``a0`` (m), Fung ``C`` (Pa) and ``alpha``, with a tissue surface tension ``gamma`` (N/m) on its
whole outer surface (non-wetting plates: contact angle 180 deg, ``fem.spheroid.compress(surface_tension=...)``),
squeezed by the total approach ``delta`` (m) carries the equilibrium plate force

    F_eq = C a0^2 f(x; alpha, Gamma),   x = delta / (2 a0),   Gamma = gamma / (C a0)  (elastocapillary number),
    f = R(x; alpha, Gamma) (f_plate(x; alpha) + Gamma d(x)),

``f_plate`` the shipped tension-free plate table (``reduced.spheroid``, the ``"fem"`` law), ``d(x) = F_drop /
(gamma a0)`` the exact liquid drop between the plates (``reduced.drop``) and R the FE-calibrated coupling ratio
(``reduced/data/capillary_master.npz``, made by ``tissuemech calibrate-capillary``; its metadata
holds the mesh, the command, the FE time and the discretisation error). R = 1 at Gamma = 0 exactly (the law IS the
plate table there) and R -> 1 as Gamma -> inf (the drop, C -> 0); an additive law (elastic + drop force) would have
R = 1 everywhere. R is interpolated by natural cubic splines in s = sqrt(x), alpha and Gamma (tensor product:
differentiable in all three, Gamma traced included).

Relaxation (``reduced.spheroid.force(..., surface_tension=gamma)``): the lumped Maxwell branches carry the
instantaneous excess over the equilibrium, dq_m/dt = -q_m / tau_m + beta_m C a0^2 d f_b(x(t)) / dt with
f_b = [R(x; alpha, Gamma / (1 + B)) ((1 + B) f_plate + Gamma d) - f] / B, B = sum_m beta_m (``Capillary.branch_curve``):
a ramp much faster than every tau_m gives the elastocapillary ball of modulus C (1 + B) with the same tension (its own
table point), the long-time force is f, and the tension itself does not relax. Against the FE (default mesh, Gamma
0.1-0.34, one or two branches; ``tests/test_reduced_capillary.py``, docs/tension.md): end of a fast ramp within the
mesh's own ~1e-4, plateau within 6e-5, 2-3 tau into the hold low by up to 1.1e-3 at Gamma 0.2, beta 1.5 (4.9e-4 at
Gamma 0.1, 5e-5 at beta 0.3: the shape's slow flow under the tension, which lumped branches do not carry).

Range: x up to the table's ``x_max``, alpha and Gamma inside the table's grids (eager calls raise ValueError naming
the quantity; under jit the check raises at run time).
"""

from __future__ import annotations

import functools
import json
from collections.abc import Callable
from pathlib import Path
from typing import Any

import jax.numpy as jnp
import numpy as np

from tissuemech.reduced import spheroid
from tissuemech.reduced.interp import second_derivative_map, spline_eval, spline_weights
from tissuemech.reduced.validation import (
    is_traced,
    traced_checks,
    traced_nonnegative,
    validate_nonnegative,
    validate_positive,
)

__all__ = [
    "CapillaryTable",
    "Capillary",
    "capillary_table",
    "equilibrium_force",
    "elastocapillary_number",
    "shipped_law",
    "DATA_FILE",
]

DATA_FILE = Path(__file__).resolve().parent / "data" / "capillary_master.npz"


def elastocapillary_number(surface_tension: Any, *, C: Any, radius: Any) -> Any:
    """Gamma = gamma / (C a0) (dimensionless) of a tension ``surface_tension`` (N/m), ``C`` (Pa), ``radius`` (m)."""
    return surface_tension / (C * radius)


class CapillaryTable:
    """The coupling ratio R(x; alpha, Gamma) on a grid: ``x`` (n_x,) from 0, ``alpha`` (n_a,), ``gamma`` (n_g,) the
    Gamma = gamma/(C a0) nodes from 0, ``ratio`` (n_g, n_a, n_x), ``drop`` d(x) = F_drop / (gamma a0) at ``drop_x``
    (a fine grid uniform in s = sqrt(x)). Splines: R in s from the first x > 0 (ends extrapolated), alpha and Gamma
    (natural); d in s (121 points: within 1.2e-6 of the exact drop from x = 5e-4 on; the first intervals hold the
    drop's non-analytic start)."""

    def __init__(
        self,
        x: Any,
        alpha: Any,
        gamma: Any,
        ratio: Any,
        drop_x: Any,
        drop: Any,
        metadata: dict | None = None,
    ):
        self.x = np.asarray(x, float)
        self.alpha = np.asarray(alpha, float)
        self.gamma = np.asarray(gamma, float)
        self.ratio = np.asarray(ratio, float)
        self.drop_x = np.asarray(drop_x, float)
        self.drop = np.asarray(drop, float)
        self.metadata = dict(metadata or {})
        if self.ratio.shape != (self.gamma.size, self.alpha.size, self.x.size) or self.drop.shape != self.drop_x.shape:
            raise ValueError(
                f"capillary table: ratio needs shape (n_gamma, n_alpha, n_x) = ({self.gamma.size}, {self.alpha.size}, "
                f"{self.x.size}) and drop the shape of drop_x; got {self.ratio.shape} and {self.drop.shape}"
            )
        if self.x[0] != 0 or np.any(np.diff(self.x) <= 0) or self.gamma[0] != 0 or np.any(np.diff(self.gamma) <= 0):
            raise ValueError("capillary table: x and Gamma must increase from 0")
        if not (np.all(np.isfinite(self.ratio)) and np.all(np.isfinite(self.drop))):
            raise ValueError("capillary table: ratio and drop values must be finite")
        self.s = np.sqrt(self.x)
        self.x_max = float(self.x[-1])
        self.gamma_max = float(self.gamma[-1])
        self.alpha_range = (float(self.alpha[0]), float(self.alpha[-1]))
        # R is splined from the first knot x > 0 on: R - 1 grows roughly like 1/sqrt(x) toward x = 0 (the coupling of a
        # small contact disc), so a value at x = 0 would only bend the first intervals; below the first knot the
        # spline continues linearly in s, and f -> 0 there with f_plate + Gamma d
        self._sR = self.s[1:]
        Ls = second_derivative_map(self._sR, "extrapolated")
        self._Ms = self.ratio[:, :, 1:] @ Ls.T  # (n_g, n_a, n_x - 1): second derivatives in s of every row
        self._La = second_derivative_map(self.alpha) if self.alpha.size > 1 else None
        self._Lg = second_derivative_map(self.gamma)
        self._sd = np.sqrt(self.drop_x)
        self._Md = second_derivative_map(self._sd, "extrapolated") @ self.drop

    def _weights(self, alpha: Any, Gamma: Any) -> tuple[jnp.ndarray, jnp.ndarray]:
        wg = spline_weights(self.gamma, self._Lg, Gamma)  # (n_g,)
        wa = jnp.ones(1) if self._La is None else spline_weights(self.alpha, self._La, alpha)
        y = jnp.einsum("g,a,gax->x", wg, wa, jnp.asarray(self.ratio[:, :, 1:]))
        M = jnp.einsum("g,a,gax->x", wg, wa, jnp.asarray(self._Ms))
        return y, M

    def ratio_curve(self, alpha: Any, Gamma: Any) -> Callable[[Any], jnp.ndarray]:
        """x -> R(x; alpha, Gamma) (the alpha and Gamma interpolation done once)."""
        y, M = self._weights(alpha, Gamma)
        return lambda x: spline_eval(self._sR, y, M, _sqrt_safe(x))

    def drop_f(self, x: Any) -> jnp.ndarray:
        """d(x) = F_drop / (gamma a0) of the liquid drop at x = delta / (2 a0) (spline of the exact solution)."""
        return spline_eval(self._sd, jnp.asarray(self.drop), jnp.asarray(self._Md), _sqrt_safe(x))

    def check_range(self, x_max: Any, alpha: Any, Gamma: Any) -> None:
        """Raise ValueError (eager values only) outside the tabulated x, alpha and Gamma."""
        for bad, message in self.range_checks(x_max, alpha, Gamma):
            if not is_traced(bad) and bool(np.any(np.asarray(bad))):
                raise ValueError(message)

    def range_checks(self, x_max: Any, alpha: Any, Gamma: Any) -> list[tuple[Any, str]]:
        """``(bad, message)`` pairs (the jit-safe twin of :meth:`check_range`)."""
        lo, hi = self.alpha_range
        a, G = jnp.asarray(alpha), jnp.asarray(Gamma)
        return [
            (
                jnp.asarray(x_max) > self.x_max * (1 + 1e-12),
                f"compression delta/(2 a0) is beyond the calibrated elastocapillary table (up to {self.x_max:.4g})",
            ),
            (
                (a < lo - 1e-12) | (a > hi + 1e-12),
                f"alpha is outside the calibrated elastocapillary table (alpha in [{lo:g}, {hi:g}])",
            ),
            (
                (G < 0) | (G > self.gamma_max * (1 + 1e-12)),
                "the elastocapillary number gamma/(C a0) (surface tension / (C radius)) is outside the calibrated table "
                f"([0, {self.gamma_max:g}]): the table was calibrated to gamma/(C a0) = {self.gamma_max:g} only "
                "(`tissuemech calibrate-capillary --gammas ...` extends it); a liquid-like aggregate is tissuemech.reduced.drop",
            ),
        ]


def _sqrt_safe(x: Any) -> jnp.ndarray:
    x = jnp.maximum(jnp.asarray(x, dtype=jnp.float64), 0.0)
    return jnp.sqrt(jnp.where(x > 0, x, 1.0)) * (x > 0)


@functools.lru_cache(maxsize=4)
def capillary_table(path: str | None = None) -> CapillaryTable:
    """The FE-calibrated elastocapillary table shipped with the package (or read from ``path``)."""
    p = Path(path) if path is not None else DATA_FILE
    if not p.exists():
        raise FileNotFoundError(f"no elastocapillary table at {p}. Generate it with `tissuemech calibrate-capillary`.")
    with np.load(p, allow_pickle=False) as z:
        meta = json.loads(str(z["metadata"])) if "metadata" in z.files else {}
        return CapillaryTable(z["x"], z["alpha"], z["gamma"], z["ratio"], z["drop_x"], z["drop"], metadata=meta)


class Capillary(spheroid.EquilibriumLaw):
    """The elastocapillary equilibrium law (module docstring) as a law object for ``reduced.spheroid``.

    ``Capillary(surface_tension=gamma)`` (N/m, a number: the law of that tension for any C and radius, usable as
    ``equilibrium=`` of :func:`~tissuemech.reduced.spheroid.force` and friends); ``Capillary()`` is the law that
    ``force(..., surface_tension=gamma)`` uses, the tension then given per call (traced, differentiable). ``table``:
    a :class:`CapillaryTable` (default the shipped one), ``plate``: the tension-free law (default the shipped FE
    plate table, ``spheroid.FEMTable()``)."""

    surface_tension: float | None
    capillary: CapillaryTable
    plate: spheroid.EquilibriumLaw

    def __init__(
        self,
        surface_tension: float | None = None,
        table: CapillaryTable | None = None,
        plate: spheroid.EquilibriumLaw | None = None,
    ):
        if surface_tension is not None:
            validate_nonnegative("surface_tension (gamma)", surface_tension, "N/m")
            surface_tension = float(surface_tension)
        self.surface_tension = surface_tension
        self.capillary = capillary_table() if table is None else table
        self.plate = spheroid.FEMTable() if plate is None else plate

    def _gamma(self, surface_tension: Any) -> Any:
        g = self.surface_tension if surface_tension is None else surface_tension
        if g is None:
            raise ValueError("Capillary() needs a surface tension: Capillary(surface_tension=gamma) (N/m)")
        return g

    def curve(self, *, alpha: Any, radius: Any, C: Any, surface_tension: Any = None) -> Callable[[Any], jnp.ndarray]:
        """x -> f(x) = R (f_plate + Gamma d) for one parameter set, Gamma = gamma / (C a0) (checked at run time
        when traced)."""
        G = elastocapillary_number(self._gamma(surface_tension), C=C, radius=radius)
        if is_traced(G):
            G = traced_checks(G, self.capillary.range_checks(0.0, alpha, G)[2:])
        else:
            self.capillary.check_range(0.0, alpha, G)
        fp = self.plate.curve(alpha=alpha, radius=radius, C=C)
        R = self.capillary.ratio_curve(alpha, G)
        d = self.capillary.drop_f
        return lambda x: R(x) * (fp(x) + G * d(x))

    def branch_curve(
        self, *, alpha: Any, radius: Any, C: Any, surface_tension: Any = None, total_beta: Any = None, **params: Any
    ) -> Callable[[Any], jnp.ndarray]:
        """x -> f_b(x), what drives the Maxwell branches (each beta_m f_b): the instantaneous excess over the
        equilibrium per unit B = sum_m beta_m,

            f_b = [R(x; alpha, Gamma / (1 + B)) ((1 + B) f_plate + Gamma d) - R(x; alpha, Gamma) (f_plate + Gamma d)] / B,

        so that a ramp much faster than every tau_m gives the elastocapillary ball of modulus C (1 + B) with the same
        tension (its own table point), and the long-time force the equilibrium f. The tension itself does not relax;
        at Gamma = 0, f_b = f_plate. Without ``total_beta`` (or B = 0): f_plate."""
        fp = self.plate.curve(alpha=alpha, radius=radius, C=C)
        if total_beta is None:
            return fp
        B = jnp.asarray(total_beta, dtype=jnp.float64)
        G = elastocapillary_number(self._gamma(surface_tension), C=C, radius=radius)
        Bs = jnp.where(B > 0, B, 1.0)
        R = self.capillary.ratio_curve(alpha, G)
        Ri = self.capillary.ratio_curve(alpha, G / (1.0 + Bs))
        d = self.capillary.drop_f

        def fb(x: Any) -> jnp.ndarray:
            fpx, gd = fp(x), G * d(x)
            excess = (Ri(x) * ((1.0 + Bs) * fpx + gd) - R(x) * (fpx + gd)) / Bs
            return jnp.where(B > 0, excess, fpx)

        return fb

    def branch_law(self) -> spheroid.EquilibriumLaw:
        """The tension-free plate law: it drives the branches (``coupling="auto"`` follows it)."""
        return self.plate

    def knots(self, displacement: Any, radius: Any) -> Any:
        """The x knots of both tables."""
        pk = self.plate.knots(displacement, radius)
        return np.unique(np.r_[self.capillary.x[1:], [] if pk is None else np.asarray(pk)])

    def check(self, x_max: Any, alpha: Any) -> None:
        """x and alpha inside both tables (Gamma is checked where C and the radius are known: :meth:`curve`)."""
        self.plate.check(x_max, alpha)
        self.capillary.check_range(x_max, alpha, 0.0)

    def traced_checks(self, x_max: Any, alpha: Any) -> list[tuple[Any, str]]:
        """The run-time twin of :meth:`check`."""
        return self.plate.traced_checks(x_max, alpha) + self.capillary.range_checks(x_max, alpha, 0.0)[:2]


def equilibrium_force(displacement: Any, *, radius: Any, C: Any, alpha: Any, surface_tension: Any) -> jnp.ndarray:
    """Elastocapillary equilibrium force F_eq = C a0^2 f(x; alpha, Gamma) in N at the total approach ``displacement``
    (m, any shape), ``radius`` a0 (m), ``C`` (Pa), ``alpha``, ``surface_tension`` gamma (N/m). Scalar parameters
    (traced or not); raises ValueError outside the table (eager), at run time under jit."""
    if not is_traced(radius, C, alpha, surface_tension):
        validate_positive("radius (of the ball)", radius, "m")
        validate_positive("C (Fung stiffness)", C, "Pa")
        validate_nonnegative("alpha (Fung exponent)", alpha)
        validate_nonnegative("surface_tension (gamma)", surface_tension, "N/m")
    law = Capillary()
    d = jnp.asarray(displacement, dtype=jnp.float64)
    x = d / (2.0 * radius)
    if not is_traced(x):
        xv = np.asarray(x)
        if np.any(xv < 0) or np.any(xv >= 1):
            raise ValueError(f"displacement must be in [0, 2 radius) m; got up to {float(np.max(d)):.4g} m")
        law.check(float(np.max(xv)), alpha)
        checks = []
    else:
        checks = law.traced_checks(jnp.max(x), alpha) + traced_nonnegative("displacement", d, "m")
    f = law.curve(alpha=alpha, radius=radius, C=C, surface_tension=surface_tension)(x)
    return traced_checks(f * C * radius**2, checks) if checks else f * C * radius**2


@functools.lru_cache(maxsize=1)
def shipped_law() -> Capillary:
    """``Capillary()`` on the shipped tables (one object: compiled code keyed on it is reused)."""
    return Capillary()
