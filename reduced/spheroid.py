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

Loading
-------
``displacement`` a number (m) and ``ramp_time`` (s): the approach grows linearly to ``displacement``
over ``ramp_time`` and is then held. The kink is handled exactly: the ramp and the hold are separate
pieces, and during the hold the branches decay in closed form, q_m(t) = q_m(t_r) e^{-(t-t_r)/tau_m}.
Over the ramp, two paths that agree to ~1e-13 (``method=``):

* ``"quadrature"`` (default): q_m is the convolution beta_m int e^{-(t-s)/tau_m} dF_eq/ds ds, summed
  between consecutive output times with the kernel absorbed exactly by z = e^{-(t-s)/tau} and the
  sqrt(t) of first contact removed by a square substitution, 16-point Gauss-Legendre per interval: no
  time stepping, exact for any stiffness tau << t_r, ~1e-15 with Hertz (~1e-8 with the spline table);
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
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any, NamedTuple, Union, cast

import diffrax
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
]

DATA_FILE = Path(__file__).resolve().parent / "data" / "spheroid_master.npz"
Equilibrium = Union[str, Callable, tuple, "MasterCurve"]


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
                raise ValueError(
                    f"alpha = {np.min(av):g}..{np.max(av):g} is outside the calibrated table "
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


# ---------------------------------------------------------------- equilibrium laws (dimensionless)


def _equilibrium_law(equilibrium: Any, radius, C, alpha) -> tuple[Callable, Any]:
    """(f(x) dimensionless F_eq/(C a0^2), table-or-None) for a spec; x = delta/(2 a0)."""
    if isinstance(equilibrium, str):
        if equilibrium == "hertz":
            return hertz_f, None
        if equilibrium == "fem":
            mc = master_curve()
            return mc.f_curve(alpha), mc
        raise ValueError(f"equilibrium must be 'hertz', 'fem', an (x, f) table or a callable; got {equilibrium!r}")
    if isinstance(equilibrium, MasterCurve):
        return equilibrium.f_curve(alpha), equilibrium
    if isinstance(equilibrium, tuple) and len(equilibrium) == 2:
        mc = _table_object(equilibrium, "f")
        return (lambda x: mc.f(x)), mc
    if callable(equilibrium):
        return (lambda x: equilibrium(2.0 * radius * x, radius=radius, C=C, alpha=alpha) / (C * radius**2)), None
    raise ValueError(f"equilibrium must be 'hertz', 'fem', an (x, f) table or a callable; got {equilibrium!r}")


def _midplane_law(midplane: Any, equilibrium: Any, radius, alpha) -> tuple[Callable, Any]:
    """(g(x) = r_mid / a0, table-or-None)."""
    if midplane is None:
        midplane = "fem" if (isinstance(equilibrium, str) and equilibrium == "fem") else "incompressible"
    if isinstance(midplane, str):
        if midplane == "incompressible":
            return (lambda x: 1.0 / jnp.sqrt(1.0 - jnp.minimum(x, 0.999))), None
        if midplane == "fem":
            mc = master_curve()
            return mc.g_curve(alpha), mc
        raise ValueError(f"midplane must be 'incompressible', 'fem', an (x, g) table or a callable; got {midplane!r}")
    if isinstance(midplane, MasterCurve):
        return midplane.g_curve(alpha), midplane
    if isinstance(midplane, Spline1D):
        return midplane, None
    if isinstance(midplane, tuple) and len(midplane) == 2:
        s = _table_object(midplane, "g")
        return s, None
    if callable(midplane):
        return (lambda x: midplane(2.0 * radius * x, radius=radius, alpha=alpha) / radius), None
    raise ValueError(f"midplane must be 'incompressible', 'fem', an (x, g) table or a callable; got {midplane!r}")


# ---------------------------------------------------------------- the lumped ODE


class _Opts(NamedTuple):
    rtol: float
    atol: float
    max_steps: int
    solver: Any
    adjoint: Any
    method: str = "quadrature"
    n_ramp: int | None = None  # output times inside the ramp, when known at trace time


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


class _Midplane1D(Spline1D):
    """A user (x, g) midplane table (a hashable spline object, so compiled code is reused)."""


def _content_key(table: tuple) -> tuple:
    arrs = [np.ascontiguousarray(np.asarray(a, dtype=float)) for a in table]
    return tuple((a.shape, a.tobytes()) for a in arrs)


@functools.lru_cache(maxsize=32)
def _cached_table(kind: str, key: tuple):
    arrays = [np.frombuffer(b, dtype=float).reshape(shape) for shape, b in key]
    return MasterCurve(*cast(list[Any], arrays)) if kind == "f" else _Midplane1D(*arrays)


def _table_object(table: tuple, kind: str):
    """One spline object per table content: a user's (x, f) or (x, g) arrays passed again in a later call
    reuse the compiled code instead of re-tracing (the object is a static argument of the jitted core)."""
    return _cached_table(kind, _content_key(table))


@functools.partial(jax.jit, static_argnums=(4,))
def _run(flat_t, params, betas, taus, static):
    law, mid, history, jumps, o, stress, shape = static
    disp = history if history is not None else None

    def one(p, bs, ts):
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
        )

    if shape == ():
        out, ok = one(params, betas, taus)
    else:
        bc = lambda v: jnp.broadcast_to(v, shape).reshape(-1)
        out, ok = jax.vmap(one)(
            {k: bc(v) for k, v in params.items()}, tuple(bc(b) for b in betas), tuple(bc(tau) for tau in taus)
        )
    return out.reshape(shape + flat_t.shape[:0] + (-1,)) if shape else out, ok


_GL_NODES, _GL_WEIGHTS = np.polynomial.legendre.leggauss(16)
_ETA = (_GL_NODES + 1.0) / 2.0  # Gauss-Legendre on [0, 1]
_W_ETA = _GL_WEIGHTS / 2.0


def _ramp_hold_quadrature(t, f, X, tr, betas, taus, n_ramp=None, knots=None):
    """Dimensionless F/(C a0^2) at times t for x(t) = X min(t/tr, 1), by exact-kernel quadrature.

    In ramp units s = t/tr (k_m = tr/tau_m), q_m(s) = beta_m int_0^s e^{-k_m (s-u)} phi(u) du with
    phi(u) = d f(X u)/du. Between consecutive output points s_{j-1} < s_j:
        q(s_j) = e^{-k D} q(s_{j-1}) + beta int_{s_{j-1}}^{s_j} e^{-k (s_j - u)} phi(u) du,  D = s_j - s_{j-1},
    and the interval integral, after z = e^{-k (s_j - u)} (which absorbs the kernel exactly, for any
    stiffness k D) and z = z0 + (1 - z0) eta^2 (which removes the sqrt(u) of first contact), is
        (1 - z0)/k int_0^1 phi(s_j + log(z)/k) 2 eta d eta,   1 - z0 = -expm1(-k D),
    evaluated with 16-point Gauss-Legendre. No time stepping: every output point at once.
    ``n_ramp`` (static, when the times and ramp time are known at trace time): how many of the
    sorted output times lie in the ramp; the others need no integral (closed-form hold).
    ``knots``: x-values where the equilibrium law is only piecewise smooth (a spline table's knots);
    they become interval ends too, so every Gauss rule sees a smooth integrand (callables: 16 even
    points; Hertz: none needed)."""
    n = betas.shape[0]
    s = jnp.clip(t / tr, 0.0, 1.0)
    feq = f(X * s)
    if n == 0:
        return feq, jnp.asarray(True)
    order = jnp.argsort(s)
    if n_ramp is None:
        n_ramp = t.shape[0]
    order = order[:n_ramp]
    extra = jnp.zeros(0) if knots is None else jnp.clip(jnp.asarray(knots, dtype=jnp.float64) / X, 0.0, 1.0)
    pts = jnp.concatenate([s[order], extra])
    order2 = jnp.argsort(pts)
    inv = jnp.argsort(order2)
    grid = jnp.concatenate([jnp.zeros(1), pts[order2], jnp.ones(1)])  # 0, sorted ramp outputs and knots, 1
    s1, s0 = grid[1:], grid[:-1]
    D = s1 - s0  # (m,)
    k = (tr / taus)[:, None]  # (n, 1)
    one_minus_z0 = -jnp.expm1(-k * D)  # (n, m)
    eta = jnp.asarray(_ETA)
    # u at the nodes: (n, m, G); log z = log1p(-(1 - z0)(1 - eta^2))
    u = s1[None, :, None] + jnp.log1p(-one_minus_z0[..., None] * (1.0 - eta**2)) / k[..., None]
    u = jnp.clip(u, s0[None, :, None], s1[None, :, None])
    _, dfx = jax.jvp(f, (X * u,), (jnp.full(u.shape, X),))  # phi(u) = X f'(X u)
    # weight (1 - z0)/k, safe as k D -> 0 (then -> D)
    wk = jnp.where(k * D > 1e-300, one_minus_z0 / k, D)
    I = wk * jnp.sum(dfx * (2.0 * eta * jnp.asarray(_W_ETA)), axis=-1)  # (n, m)
    decay = jnp.exp(-k * D)  # (n, m)

    def step(q, inputs):
        dec, inc = inputs
        q = dec * q + inc
        return q, q

    _, qs = jax.lax.scan(step, jnp.zeros(n), (decay.T, (betas[:, None] * I).T))  # (m, n)
    q_sorted, q_end = qs[inv[:n_ramp]], qs[-1]
    q_ramp = jnp.zeros((t.shape[0], n)).at[order].set(q_sorted)
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


def _curve(t, radius, C, alpha, betas, taus, displacement, ramp_time, equilibrium, midplane, jumps, o, stress: bool):
    """Force (N) or nominal stress (Pa) at flat times t for scalar parameters."""
    f, table = _equilibrium_law(equilibrium, radius, C, alpha)
    if table is not None:
        knots = table.x[1:]  # x = 0 is the grid start already
    elif isinstance(equilibrium, str) and equilibrium == "hertz":
        knots = None
    else:  # a user callable: smoothness unknown, 16 even sub-intervals of the ramp
        knots = None if callable(displacement) else np.linspace(0.0, 1.0, 17)[1:-1] * displacement / (2.0 * radius)
    if callable(displacement):

        def x_of_t(tt):
            return displacement(tt) / (2.0 * radius)

        fhat, ok = _history(t, f, x_of_t, betas, taus, jumps, o)
        x_t = x_of_t(t)
    else:
        X = displacement / (2.0 * radius)
        if o.method == "quadrature":
            fhat, ok = _ramp_hold_quadrature(t, f, X, ramp_time, betas, taus, o.n_ramp, knots)
        else:
            fhat, ok = _ramp_hold(t, f, X, ramp_time, betas, taus, o)
        x_t = X * jnp.clip(t / ramp_time, 0.0, 1.0)
    out = fhat * C * radius**2
    if stress:
        g, _ = _midplane_law(midplane, equilibrium, radius, alpha)
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
    t_arr = jnp.asarray(t, dtype=jnp.float64)
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
        _check_inputs(t, radius, C, alpha, displacement, ramp_time, equilibrium, midplane, jump_times)
    _check_solver_options(rtol, atol, max_steps)
    betas = tuple(jnp.asarray(b, dtype=jnp.float64) for b, _ in br)
    taus = tuple(jnp.asarray(tau, dtype=jnp.float64) for _, tau in br)
    params = dict(radius=radius, C=C, alpha=alpha)
    if not callable(displacement):
        params.update(displacement=displacement, ramp_time=ramp_time)
    params = {k: jnp.asarray(v, dtype=jnp.float64) for k, v in params.items()}
    shape = jnp.broadcast_shapes(
        *(v.shape for v in params.values()), *(b.shape for b in betas), *(tau.shape for tau in taus)
    )
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
    n_ramp = None
    if not callable(displacement):
        tv, rv = _concrete(t), _concrete(ramp_time)
        if tv is not None and rv is not None:
            n_ramp = int(np.sum(tv.ravel() <= np.max(rv)))
    o = _Opts(float(rtol), float(atol), int(max_steps), solver, _adjoint(adjoint), method, n_ramp)
    law = _table_object(equilibrium, "f") if isinstance(equilibrium, tuple) else equilibrium
    mid = _table_object(midplane, "g") if isinstance(midplane, tuple) else midplane
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


def _table_of(law):
    if isinstance(law, MasterCurve):
        return law
    if isinstance(law, str) and law == "fem":
        return master_curve()
    if isinstance(law, tuple) and len(law) == 2:
        return _table_object(law, "f")
    return None


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
    midplane: Any = None,
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
    """Elastic equilibrium force F_eq(delta) in N for the total approach ``displacement`` (m)."""
    if not is_traced(displacement, radius, C, alpha):
        r = validate_positive("radius (of the ball)", radius, "m")
        validate_material(C, alpha)
        d = validate_finite("displacement (the total approach of the plates)", displacement, "m")
        _check_approach("displacement", d / (2.0 * r))
        mc = _table_of(equilibrium)
        if mc is not None:
            mc.check_range(np.asarray(displacement, dtype=float) / (2 * np.asarray(radius, dtype=float)), alpha)
    f, _ = _equilibrium_law(equilibrium, radius, C, alpha)
    x = jnp.asarray(displacement, dtype=jnp.float64) / (2.0 * jnp.asarray(radius, dtype=jnp.float64))
    return f(x) * C * jnp.asarray(radius) ** 2


def midplane_radius(
    displacement: Any, *, radius: Any, alpha: Any = 0.0, midplane: Any = "incompressible"
) -> jnp.ndarray:
    """Deformed equator radius r_mid (m) at total approach ``displacement`` (m)."""
    if not is_traced(displacement, radius, alpha):
        r = validate_positive("radius (of the ball)", radius, "m")
        validate_nonnegative("alpha (the Fung stiffening exponent)", alpha, "dimensionless")
        d = validate_finite("displacement (the total approach of the plates)", displacement, "m")
        _check_approach("displacement", d / (2.0 * r))
        mc = _table_of_safe(midplane)
        if mc is not None:
            mc.check_range(d / (2.0 * r), alpha)
    g, _ = _midplane_law(midplane, None, radius, alpha)
    x = jnp.asarray(displacement, dtype=jnp.float64) / (2.0 * jnp.asarray(radius, dtype=jnp.float64))
    return jnp.asarray(radius) * g(x)


# ---------------------------------------------------------------- input checks of the public entry points


def _check_solver_options(rtol: Any, atol: Any, max_steps: Any) -> None:
    validate_positive("rtol (relative tolerance of the ODE solver)", rtol, "dimensionless")
    validate_positive("atol (absolute tolerance of the ODE solver)", atol, "dimensionless")
    validate_int("max_steps (of the ODE solver)", max_steps, minimum=1)


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


def _check_inputs(t, radius, C, alpha, displacement, ramp_time, equilibrium, midplane, jump_times) -> None:
    """Eager checks of force / nominal_stress (every message names the quantity and its unit)."""
    validate_times("t (output times, t = 0 is first contact)", t, unit="s")
    r = validate_positive("radius (of the ball)", radius, "m")
    validate_material(C, alpha)
    if jump_times is not None:
        validate_times("jump_times (kinks of the displacement history)", jump_times, unit="s")
    laws = [law for law in (equilibrium, midplane) if _table_of_safe(law) is not None]
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
        for law in laws:
            _table_of_safe(law).check_range(np.max(x), alpha)
        return
    validate_positive("displacement (the total approach of the plates)", displacement, "m")
    if ramp_time is None:
        raise ValueError("ramp_time (s) is needed with a numeric displacement (linear ramp, then hold)")
    validate_positive("ramp_time (duration of the loading ramp)", ramp_time, "s")
    if np.any(np.asarray(displacement, dtype=float) >= 2 * np.asarray(radius, dtype=float)):
        raise ValueError("displacement (total approach) must be smaller than the ball's diameter 2 * radius")
    x_max = np.asarray(displacement, dtype=float) / (2 * np.asarray(radius, dtype=float))
    for law in laws:
        _table_of_safe(law).check_range(x_max, alpha)


def _table_of_safe(law):
    """The table behind an equilibrium/midplane spec, or None (also for specs rejected later)."""
    try:
        return _table_of(law)
    except (TypeError, ValueError):
        return None
