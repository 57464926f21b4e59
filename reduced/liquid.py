r"""The lumped viscoelastic LIQUID with a surface tension between plates: a relaxation curve in microseconds.

A Maxwell liquid (no long-time modulus, C_inf = 0) of radius ``a0`` (m), Fung exponent ``alpha``, Maxwell branches
given by their own Fung stiffnesses ``(C_m [Pa], tau_m [s])`` (the FE's spelling ``fem.viscoelastic.Branch(modulus=C_m,
tau=tau_m)`` is accepted as is: it is that pair) and a tissue surface tension ``gamma`` (N/m, non-wetting plates) is
squeezed by the total approach delta(t) (m), x = delta / (2 a0). Its plate force is

    F(t) = gamma a0 d(x(t)) + C_ref a0^2 sum_m q_m(t),
    dq_m/dt = -q_m / tau_m + beta_m d f_b(x(t)) / dt,    beta_m = C_m / C_ref,  C_ref = sum_m C_m,
    f_b(x) = R(x; alpha, Gamma) (f_plate(x; alpha) + Gamma d(x)) - Gamma d(x),   Gamma = gamma / (C_ref a0),

* long time (the branches relaxed, q_m -> 0): the exact drop d(x) = F_drop / (gamma a0) (``reduced.drop``,
  tabulated once in s = sqrt(x) by ``tissuemech calibrate-drop`` into ``data/drop_master.npz``:
  481 knots, spline error <= 1.9e-9 from x = 1e-3 on, 6e-5 at x = 1e-5; in its metadata), which the FE liquid meets
  to 1e-4;
* instantaneous (a ramp much faster than every tau_m: q_m = beta_m f_b): C_ref a0^2 R (f_plate + Gamma d), the
  elastocapillary law of ``reduced.capillary`` for the ball of modulus C_ref with the same tension. That is how the FE
  scales a liquid (``fem.viscoelastic.relative_branches``: reference modulus C_ref = sum_m C_m, branch factors
  beta_m = C_m / C_ref summing to 1, no long-time term), so Gamma = gamma / (C_ref a0) must lie in the capillary
  table (<= its ``gamma_max``).

The branches are the lumped ones of ``reduced.spheroid`` (the same quadrature / ODE, ``coupling`` as there), run
through ``spheroid.force(..., equilibrium=Liquid(), surface_tension=gamma)`` with C = C_ref: jit, vmap and grad (in
gamma, the moduli, the times, a0, alpha) work as for ``spheroid.force``. What the lumped model leaves out is the
flow: under held plates the FE aggregate creeps toward the drop shape while its branch stresses relax; the lumped
branches relax at the held approach (measured against the FE: ``python -m tissuemech.compare.bench.liquid_relaxation``).

Range: x up to the capillary table's ``x_max`` (0.3), alpha and Gamma inside its grids (ValueError naming the
quantity for eager calls, at run time under jit).
"""

from __future__ import annotations

import functools
import json
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any

import jax.numpy as jnp
import numpy as np

from tissuemech.reduced import capillary, spheroid
from tissuemech.reduced.interp import second_derivative_map, spline_eval
from tissuemech.reduced.validation import (
    InputTypeError,
    is_traced,
    validate_nonnegative,
    validate_positive,
)

__all__ = ["DropTable", "Liquid", "drop_table", "drop_force", "liquid_law", "force", "nominal_stress", "DATA_FILE"]

DATA_FILE = Path(__file__).resolve().parent / "data" / "drop_master.npz"
X_MAX = 0.36  # the drop table's range in x = delta / (2 a0) (the plate table's)


def _sqrt_safe(x: Any) -> jnp.ndarray:
    x = jnp.maximum(jnp.asarray(x, dtype=jnp.float64), 0.0)
    return jnp.sqrt(jnp.where(x > 0, x, 1.0)) * (x > 0)


class DropTable:
    """d(x) = F_drop / (gamma a0) of the Young-Laplace drop between non-wetting plates at x = delta / (2 a0): a cubic
    spline in s = sqrt(x) through ``d`` at the knots ``x`` (from 0; ends extrapolated). Callable, jit-safe, C^2 in s."""

    def __init__(self, x: Any, d: Any, metadata: dict | None = None):
        self.x = np.asarray(x, float)
        self.d = np.asarray(d, float)
        self.metadata = dict(metadata or {})
        if self.x.ndim != 1 or self.x.shape != self.d.shape or self.x.size < 4:
            raise ValueError("drop table: x and d need the same 1-D shape, >= 4 knots")
        if self.x[0] != 0 or np.any(np.diff(self.x) <= 0) or not np.all(np.isfinite(self.d)):
            raise ValueError("drop table: x must increase from 0 and d be finite")
        self.s = np.sqrt(self.x)
        self.x_max = float(self.x[-1])
        self._M = second_derivative_map(self.s, "extrapolated") @ self.d

    def __call__(self, x: Any) -> jnp.ndarray:
        return spline_eval(self.s, jnp.asarray(self.d), jnp.asarray(self._M), _sqrt_safe(x))


@functools.lru_cache(maxsize=4)
def drop_table(path: str | None = None) -> DropTable:
    """The shipped drop table (or the one at ``path``)."""
    p = Path(path) if path is not None else DATA_FILE
    if not p.exists():
        raise FileNotFoundError(f"no drop table at {p}. Generate it with `tissuemech calibrate-drop`.")
    with np.load(p, allow_pickle=False) as z:
        meta = json.loads(str(z["metadata"])) if "metadata" in z.files else {}
        return DropTable(z["x"], z["drop"], metadata=meta)


def drop_force(displacement: Any, *, radius: Any, surface_tension: Any) -> jnp.ndarray:
    """The exact drop's plate force gamma a0 d(x) (N) at the approach ``displacement`` (m, any shape, 0 <= delta <=
    2 X_MAX a0) of a drop of radius ``radius`` (m) and tension ``surface_tension`` (N/m), from the shipped table
    (jit/grad-safe; the liquid's long-time law)."""
    table = drop_table()
    if not is_traced(displacement, radius, surface_tension):
        validate_positive("radius (of the drop)", radius, "m")
        validate_nonnegative("surface_tension (gamma)", surface_tension, "N/m")
        x = np.asarray(displacement, float) / (2.0 * np.asarray(radius, float))
        if np.any(x < 0) or np.any(x > table.x_max * (1 + 1e-12)):
            raise ValueError(
                f"displacement (the total approach, m) must be in [0, {2 * table.x_max:g} radius] for the drop table; "
                f"got delta / (2 a0) up to {float(np.max(x)):.4g}"
            )
    return surface_tension * radius * table(jnp.asarray(displacement, dtype=jnp.float64) / (2.0 * radius))


class Liquid(capillary.Capillary):
    """The liquid's law object for ``reduced.spheroid`` with C = C_ref (module docstring): ``curve`` = Gamma d (the
    part that does not relax), ``branch_curve`` = R (f_plate + Gamma d) - Gamma d (what the branches carry at first).
    ``drop``: a :class:`DropTable` (default the shipped one); ``table``, ``plate`` as :class:`Capillary`."""

    drop: DropTable

    def __init__(
        self,
        table: capillary.CapillaryTable | None = None,
        plate: spheroid.EquilibriumLaw | None = None,
        drop: DropTable | None = None,
    ):
        super().__init__(None, table=table, plate=plate)
        self.drop = drop_table() if drop is None else drop

    def curve(self, *, alpha: Any, radius: Any, C: Any, surface_tension: Any = None) -> Callable[[Any], jnp.ndarray]:
        """x -> Gamma d(x), Gamma = gamma / (C a0) (C the reference modulus C_ref)."""
        G = capillary.elastocapillary_number(self._gamma(surface_tension), C=C, radius=radius)
        d = self.drop
        return lambda x: G * d(x)

    def branch_curve(self, *, alpha: Any, radius: Any, C: Any, **params: Any) -> Callable[[Any], jnp.ndarray]:
        """x -> R (f_plate + Gamma d) - Gamma d: the instantaneous elastocapillary excess over the drop."""
        gamma = self._gamma(params.get("surface_tension"))
        full = super().curve(alpha=alpha, radius=radius, C=C, surface_tension=gamma)
        G = capillary.elastocapillary_number(gamma, C=C, radius=radius)
        d = self.drop
        return lambda x: full(x) - G * d(x)


@functools.lru_cache(maxsize=1)
def liquid_law() -> Liquid:
    """``Liquid()`` on the shipped tables (one object: compiled code keyed on it is reused)."""
    return Liquid()


def _branches(branches: Any) -> tuple[Any, list[tuple[Any, Any]]]:
    """(C_ref, [(beta_m, tau_m)]) from the liquid's branches (C_m [Pa], tau_m [s]) or objects with .modulus, .tau."""
    if branches is None or isinstance(branches, (str, bytes, dict)):
        raise InputTypeError(
            "branches of a liquid: a sequence of (modulus C_m [Pa], tau_m [s]) pairs or fem.viscoelastic.Branch "
            f"objects, at least one; got {branches!r}"
        )
    pairs = []
    for k, b in enumerate(branches):
        if hasattr(b, "modulus") and hasattr(b, "tau"):
            m, tau = b.modulus, b.tau
        else:
            try:
                m, tau = b
            except (TypeError, ValueError):
                raise InputTypeError(
                    f"branch {k} of a liquid: a pair (modulus C_m [Pa], tau_m [s]) or a Branch; got {b!r}"
                ) from None
        if not is_traced(m, tau):
            validate_positive(f"modulus (the Fung stiffness C_m of branch {k})", m, "Pa")
            validate_positive(f"tau (relaxation time of branch {k})", tau, "s")
        pairs.append((m, tau))
    if not pairs:
        raise ValueError(
            "a liquid (no long-time modulus) needs at least one Maxwell branch (modulus C_m [Pa], tau_m [s]): a "
            "material with no modulus at all has no elastic response"
        )
    ref = pairs[0][0]
    for m, _ in pairs[1:]:
        ref = ref + m
    return ref, [(m / ref, tau) for m, tau in pairs]


def _evaluate(t: Any, *, stress: bool, branches: Any, **kw: Any) -> jnp.ndarray:
    fixed = sorted({"C", "equilibrium"} & set(kw))
    if fixed:
        raise InputTypeError(
            f"reduced.liquid sets {', '.join(fixed)} itself (C = sum of the branch moduli, the liquid's law); "
            "a solid with tension is reduced.spheroid.force(..., surface_tension=gamma)"
        )
    ref, rel = _branches(branches)
    fn = spheroid.nominal_stress if stress else spheroid.force
    return fn(t, C=ref, branches=rel, equilibrium=liquid_law(), **kw)


def force(
    t: Any,
    *,
    radius: Any,
    alpha: Any,
    branches: Sequence[Any],
    surface_tension: Any,
    displacement: Any,
    ramp_time: Any = None,
    **options: Any,
) -> jnp.ndarray:
    r"""Plate force F(t) in N of the lumped Maxwell liquid with surface tension (module docstring).

    t                output times (s), any shape, >= 0 (t = 0 is first contact).
    radius           ball radius a0 (m).      alpha   Fung exponent (-) of the branches.
    branches         the Maxwell branches: (modulus C_m [Pa], tau_m [s]) pairs or ``fem.viscoelastic.Branch``; >= 1.
    surface_tension  gamma (N/m, > 0 for a finite long-time force; Gamma = gamma / (sum C_m a0) in the capillary table).
    displacement     total approach delta (m) reached at ``ramp_time`` (s) and held; or a callable / a measured
                     history ``(times, approaches)`` as in :func:`tissuemech.reduced.spheroid.force`.
    options          ``method``, ``coupling``, ``jump_times``, ``rtol``... of :func:`tissuemech.reduced.spheroid.force`.
    Parameters broadcast (result ``broadcast(params).shape + t.shape``); jit/vmap/grad like ``spheroid.force``; eager
    calls raise ValueError naming a bad input and its unit.
    """
    return _evaluate(
        t,
        stress=False,
        branches=branches,
        radius=radius,
        alpha=alpha,
        surface_tension=surface_tension,
        displacement=displacement,
        ramp_time=ramp_time,
        **options,
    )


def nominal_stress(
    t: Any,
    *,
    radius: Any,
    alpha: Any,
    branches: Sequence[Any],
    surface_tension: Any,
    displacement: Any,
    ramp_time: Any = None,
    **options: Any,
) -> jnp.ndarray:
    """Nominal stress F(t) / (pi r_mid^2) in Pa (r_mid the calibrated midplane of the tension-free ball unless
    ``midplane=`` says otherwise: at x = 0.1 it is 1.0133 a0, the drop's 1.0224 a0, the incompressible estimate
    a0 / sqrt(1 - x) 1.0541 a0); arguments as :func:`force`."""
    return _evaluate(
        t,
        stress=True,
        branches=branches,
        radius=radius,
        alpha=alpha,
        surface_tension=surface_tension,
        displacement=displacement,
        ramp_time=ramp_time,
        **options,
    )
