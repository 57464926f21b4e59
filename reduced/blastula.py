r"""Exact inflation of a thick, incompressible, hyperelastic (Fung) hollow sphere.

Reference sphere: inner radius ``A`` and outer radius ``B`` (m); Fung law with stiffness ``C`` (Pa)
and exponent ``alpha`` (dimensionless, ``alpha = 0`` is neo-Hookean), see ``reduced.material``.
Internal pressure ``p`` (Pa, a follower load), outer surface free.

Kinematics (incompressible, spherically symmetric): a material sphere of reference radius ``R``
moves to ``r`` with ``r^3 - R^3 = a^3 - A^3``; hoop stretch ``l = r/R``, radial stretch ``l^-2``;

    lambda_b^3 = 1 + (lambda_a^3 - 1) k,        k = (A/B)^3,

with the inner stretch ``lambda_a = a/A`` and the outer stretch ``lambda_b = b/B``.
Equilibrium ``d sigma_r/dr = 2 (sigma_theta - sigma_r)/r`` with
``sigma_theta - sigma_r = 2 W'(I1) (l^2 - l^-4)``, ``I1 = 2 l^2 + l^-4``, ``sigma_r(b) = 0``,
``sigma_r(a) = -p``, integrates (``dr/r = -dl / (l (l^3 - 1))``) to

    p(lambda_a) = int_{lambda_b}^{lambda_a} g(l) dl,
    g(l) = 4 W'(I1(l)) (l^3 + 1) / l^5 = 4 C exp(alpha (2 l^2 + l^-4 - 3)) (l^3 + 1) / l^5.

Numerics (everything is computed for ``p / C`` as a function of ``(lambda_a, k, alpha)``):

* ``method="quadrature"``: the substitution ``l = exp(s)`` turns the integrand into
  ``G(s) = 4 exp(alpha (2 e^{2s} + e^{-4s} - 3)) (e^{3s} + 1) e^{-4s}``, an entire function of
  ``s`` (no pole at ``l = 0`` limits the convergence), integrated by a fixed ``N``-point
  Gauss-Legendre rule on ``[log lambda_b, log lambda_a]``. The interval length is formed without
  cancellation: ``log(lambda_a / lambda_b) = log1p(e (1 - k) / (1 + e k)) / 3`` with
  ``e = lambda_a^3 - 1 = expm1(3 log lambda_a)`` and ``1 - k = (B - A)(B^2 + AB + A^2)/B^3``, so ``p``
  keeps full relative accuracy at ``lambda_a = 1 + 1e-9`` (where ``p ~ 8 C (1 - k)(lambda_a - 1)``).
* ``method="ode"``: the radial equilibrium ODE integrated through the deformed wall with diffrax
  (Dopri8, PID control, ``rtol=`` argument of :func:`pressure`, default 1e-10), in the variable ``s = log l`` as well:
  ``d(sigma_r/C)/ds = -G(s)`` from ``s_b = log lambda_b`` (``sigma_r = 0``) to ``s_a = log lambda_a``;
  ``p = -sigma_r(a)``. The two paths agree to ~2e-13 relative (tested to 1e-10).

Stretch domain: ``lambda_a > 0``. ``lambda_a < 1`` is deflation (negative pressure, physical down to
the collapse ``lambda_a -> 0`` where ``p -> -infinity``). ``lambda_a <= 0``, non-finite or non-numeric
values raise ``ValueError`` in eager calls.

Under ``jax.jit`` / ``vmap`` / ``grad`` (traced inputs) every input an eager call refuses (a stretch outside
1e-30..1e30, zero, negative or non-finite; C <= 0; alpha < 0; radii not 0 < A < B; a non-finite pressure)
raises at run time instead (``equinox.error_if``: the compiled program stops with a ``JaxRuntimeError``
whose text names the quantity and its unit, as the eager message does, without the value); what an eager
call refuses for its result rather than its input (a pressure beyond float64, a pressure above the limit
point, no limit point) is the NaN flag. No extrapolated or sign-flipped number comes back.

Eager calls check their inputs with NumPy, then run one compiled program per public function (the
same core a user's ``jax.jit`` runs); one-point calls (Python numbers or size-1 arrays) take a fast
path (plain-float checks, the program on 0-d values), calls with 2 to 1024 points run padded to a
power-of-two size, so that every small shape shares one compiled program. Eager results are NumPy float64 arrays
(``limit_point``: Python floats for scalar input); traced calls return JAX arrays.

Error control of the quadrature
-------------------------------
One 20-point panel is exact to ~1e-13 in the seed's range, but the integrand grows like
``exp(2 alpha l^2)``: at alpha = 5-20 and stretch 2-10 a single panel is off by 10-20 %. An a-priori
indicator decides how many panels are needed: with ``D(s) = d log G/ds`` (closed form, increasing in
``s``, so its largest magnitude on an interval is at an end) a panel of width ``h`` has
``c = |h| (max |D| + 4) / 2``; the 20-point rule is accurate to < 1e-13 relative for ``c <= 12``
(measured over random shells, alpha in [0, 20]: worst 4e-14 for ``c <= 15``; 2e-10 at 25). Eager
calls split every interval into ``ceil(c / 12)`` equal panels (rounded up to a power of two; the seed's
cases need one, so the common case costs what it did), so the error stays below 1e-10 for every input;
a pressure beyond the float64 range (``log(p/C) > 705``, e.g. ``lambda_a = 100`` at alpha = 0.2) raises
``ValueError``. Inside ``jit``/``vmap``/``grad`` the number of panels cannot depend on the data: one
panel is used and entries whose indicator exceeds 12 are NaN (the documented flag), and
:func:`inner_stretch_solve` reports them as not converged (eager :func:`inner_stretch` polishes them).
"""

from __future__ import annotations

import functools
import math
from typing import Any, NamedTuple

import jax
import jax.numpy as jnp
import numpy as np

from tissuemech.reduced.material import dW_dI1
from tissuemech.reduced.programs import small_call
from tissuemech.reduced.validation import (
    is_traced,
    scalar_values,
    traced_checks,
    traced_finite,
    traced_material,
    traced_radii,
    validate_choice,
    validate_finite,
    validate_int,
    validate_material,
    validate_positive,
    validate_radii,
)

__all__ = [
    "pressure",
    "pressure_derivative",
    "inner_stretch",
    "inner_stretch_solve",
    "limit_point",
    "outer_stretch",
    "profiles",
    "Profiles",
    "LimitPoint",
]

Array = Any

# ---------------------------------------------------------------------------------------------
# Gauss-Legendre rule on [-1, 1] and its a-priori error control (see the module docstring)
# ---------------------------------------------------------------------------------------------
N_GAUSS = 20
_X, _W = np.polynomial.legendre.leggauss(N_GAUSS)
# A panel [s1, s2] of width h is integrated by the 20-point rule to < 1e-13 relative when its indicator
# c = |h| (max |d log G/ds| + 4) / 2 <= PANEL_INDICATOR (measured: max error 4e-14 for c <= 15 over
# random shells, alpha in [0, 20]; 2e-10 at c = 25, 1e-1 at c = 200). d log G/ds is increasing in s,
# so its largest magnitude on a panel is at an end. Wider intervals get ceil(c / PANEL_INDICATOR) equal panels.
PANEL_INDICATOR = 12.0
MAX_PANELS = 4096  # beyond this an eager call raises (never reached below the float64 overflow)
_LOG_FLOAT_MAX = 705.0  # log(p/C) above this would overflow float64 (max ~ 1.8e308)
_NODES_PER_CHUNK = 4_000_000  # eager composite rules are evaluated in chunks of this many nodes


STRETCH_DOMAIN = (1e-30, 1e30)  # inner stretches an eager call accepts: beyond, the integrand's powers leave float64


def _check_stretch(name: str, value: Any) -> np.ndarray | None:
    """Eager check: stretch finite and > 0 (``< 1`` is deflation and allowed) and within ``STRETCH_DOMAIN``; the
    float64 array (None for a traced value)."""
    v = validate_finite(name, value, "a/A, dimensionless")
    if v is not None and (v <= 0).any():
        raise ValueError(
            f"{name} must be positive (a/A > 0; values below 1 mean the cavity shrinks); got {np.min(v):g}"
        )
    if v is not None and ((v < STRETCH_DOMAIN[0]) | (v > STRETCH_DOMAIN[1])).any():
        bad = v[(v < STRETCH_DOMAIN[0]) | (v > STRETCH_DOMAIN[1])].ravel()[0]
        raise ValueError(
            f"{name} must lie within {STRETCH_DOMAIN[0]:g}..{STRETCH_DOMAIN[1]:g} (a/A, dimensionless; beyond, the "
            f"powers of the stretch in the pressure integral leave the float64 range); got {bad:g}"
        )
    return v


def _traced_stretch(name: str, value: Any) -> list[tuple[Any, str]]:
    """Twin of :func:`_check_stretch` for a traced stretch: the run-time check (for ``traced_checks``) that it lies
    in ``STRETCH_DOMAIN`` (zero, negative and non-finite values refused)."""
    if not is_traced(value):
        return []
    v = jnp.asarray(value)
    message = (
        f"{name} must be positive (a/A > 0, dimensionless; values below 1 mean the cavity shrinks) and lie within "
        f"{STRETCH_DOMAIN[0]:g}..{STRETCH_DOMAIN[1]:g}"
    )
    return [(~((v >= STRETCH_DOMAIN[0]) & (v <= STRETCH_DOMAIN[1])), message)]


def _traced_shell(A, B, C, alpha) -> list[tuple[Any, str]]:
    """The run-time checks of traced shell and material values (the twins of :func:`_validate`)."""
    return traced_radii(A, B) + traced_material(C, alpha)


def _validate(inner_radius, outer_radius, C, alpha) -> tuple[Any, Any, Any, Any]:
    """Check the shell and the material; (A, B, C, alpha) as float64 NumPy arrays where concrete,
    the traced values as they came otherwise (what the compiled cores take; :func:`_traced_shell` checks them)."""
    a, b = validate_radii(inner_radius, outer_radius)
    c, al = validate_material(C, alpha)
    return _concrete(a, inner_radius), _concrete(b, outer_radius), _concrete(c, C), _concrete(al, alpha)


def _geometry(inner_radius, outer_radius, xp=jnp):
    """k = (A/B)^3 and 1 - k, the latter without cancellation for thin walls (``xp``: jax.numpy or NumPy)."""
    A = xp.asarray(inner_radius, dtype=xp.float64)
    B = xp.asarray(outer_radius, dtype=xp.float64)
    r = A / B
    k = r**3
    one_minus_k = (B - A) / B * (1.0 + r + r * r)  # scale-free (B^3 under/overflows for radii beyond ~1e+-100 m)
    return k, one_minus_k


def _log_stretches(la, k, one_minus_k):
    """(log lambda_b, log(lambda_a / lambda_b)) without cancellation near lambda_a = 1 (log1p forms) nor in strong
    deflation (lambda_a^3 < 1/2: lambda_b^3 = 1 - k + k lambda_a^3 summed directly and the width as log a - log b,
    where 1 + e (1 - k)/(1 + e k) = (lambda_a / lambda_b)^3 -> 0 would lose digits: 2e-8 at lambda_a = 1e-3)."""
    xp = jnp if any(isinstance(v, jax.Array) for v in (la, k, one_minus_k)) else np
    sa = xp.log(la)
    e = xp.expm1(3.0 * sa)  # lambda_a^3 - 1
    deflated = e < -0.5
    ek = xp.where(deflated, 0.0, e * k)  # (the unused branch kept finite: no NaN in a gradient)
    sb = xp.where(deflated, xp.log(one_minus_k + k * xp.exp(3.0 * sa)) / 3.0, xp.log1p(ek) / 3.0)
    arg = xp.where(deflated, 0.0, e * one_minus_k / (1.0 + ek))
    width = xp.where(deflated, sa - sb, xp.log1p(arg) / 3.0)  # = sa - sb
    return sb, width


def _G(s, alpha):
    """Integrand in s = log l, divided by C: 4 W'(I1)/C (l^3 + 1) / l^4 (dimensionless)."""
    # one exponential per node, the powers by products; the barrier stops XLA folding them back into exponentials
    l1 = jax.lax.optimization_barrier(jnp.exp(s))
    l2 = l1 * l1
    lm4 = 1.0 / (l2 * l2)
    I1 = 2.0 * l2 + lm4
    return 4.0 * dW_dI1(I1, 1.0, alpha) * (l2 * l1 + 1.0) * lm4


def _g(l, alpha):
    """Integrand in l, divided by C: g(l)/C = 4 W'(I1)/C (l^3 + 1)/l^5 (dimensionless)."""
    l2 = l * l
    l4 = l2 * l2
    return 4.0 * dW_dI1(2.0 * l2 + 1.0 / l4, 1.0, alpha) * (l2 * l + 1.0) / (l4 * l)


def _log_G_and_slope(s, alpha, xp):
    """(log G(s), d log G/ds) in closed form (NumPy or jax.numpy ``xp``)."""
    e2, em4, e3 = xp.exp(2.0 * s), xp.exp(-4.0 * s), xp.exp(3.0 * s)
    logG = alpha * (2.0 * e2 + em4 - 3.0) + np.log(4.0) + xp.log1p(e3) - 4.0 * s
    slope = alpha * (4.0 * e2 - 4.0 * em4) + 3.0 * e3 / (1.0 + e3) - 4.0
    return logG, slope


def quadrature_indicator(la, k, omk, alpha):
    """(c, log_bound): the a-priori indicator c = |h| (max |d log G/ds| + 4)/2 of the interval
    [log lambda_b, log lambda_a] (one 20-point panel suffices for c <= PANEL_INDICATOR) and
    log(|h| max G), an upper bound of log |p/C| (overflow check). NumPy or JAX arrays."""
    xp = jnp if any(isinstance(v, jax.Array) for v in (la, k, omk, alpha)) else np
    sb, h = _log_stretches(la, k, omk)
    sa = sb + h
    lga, da = _log_G_and_slope(sa, alpha, xp)
    lgb, db = _log_G_and_slope(sb, alpha, xp)
    ah = xp.abs(h)
    c = 0.5 * ah * (xp.maximum(xp.abs(da), xp.abs(db)) + 4.0)
    log_bound = xp.maximum(lga, lgb) + xp.log(xp.maximum(ah, 1e-300))
    return c, log_bound


def _p_over_C_quad(la, k, one_minus_k, alpha):
    """p/C by one 20-point Gauss-Legendre panel in s = log l (accurate where the indicator allows)."""
    return _p_over_C_rule(la, k, one_minus_k, alpha, _X, _W)


_NODE_LOOP_MIN = 4096  # one-panel rules over at least this many points run node by node (see _p_over_C_rule)


def _p_over_C_rule(la, k, omk, alpha, x, w):
    """p/C with an arbitrary Gauss-Legendre rule (x, w) on [-1, 1] (log-l substitution).

    At least ``_NODE_LOOP_MIN`` points: one node at a time on arrays of the points' shape, which XLA fuses into one
    pass over the points; fewer: the nodes as a trailing axis, one (N, nodes) array between two fusions, which
    compiles up to ~3x faster (what a small eager call pays for most). At 1e6 random shells the exact pressure ran at
    1.0e7 points/s with the trailing axis and 1.4-1.9e7 node by node
    (``python -m tissuemech.compare.bench.reduced_blastula --workload-only``); the two sum in another order and
    agree to ~2e-15 relative."""
    sb, h = _log_stretches(la, k, omk)
    shape = jnp.broadcast_shapes(jnp.shape(sb), jnp.shape(h), jnp.shape(alpha))
    if math.prod(shape) < _NODE_LOOP_MIN:
        s = sb[..., None] + 0.5 * h[..., None] * (jnp.asarray(x) + 1.0)
        return 0.5 * h * jnp.sum(jnp.asarray(w) * _G(s, alpha[..., None]), axis=-1)
    total = jnp.zeros(shape, dtype=jnp.float64)
    for xj, wj in zip(np.asarray(x, dtype=float), np.asarray(w, dtype=float)):
        total = total + wj * _G(sb + (0.5 * (xj + 1.0)) * h, alpha)
    return 0.5 * h * total


@functools.cache
def _panel_rule(m: int) -> tuple[np.ndarray, np.ndarray]:
    """m equal panels of the 20-point rule on [0, 1]: nodes and weights (20 m each)."""
    j = np.arange(m)[:, None]
    t = ((j + 0.5 * (_X[None, :] + 1.0)) / m).ravel()
    w = np.tile(_W / (2.0 * m), m)
    return t, w


@functools.partial(jax.jit, static_argnums=(4,))
def _p_over_C_panels(la, k, omk, alpha, m):
    """p/C by m equal 20-point panels on [log lambda_b, log lambda_a] (1-D inputs of equal length)."""
    t, w = _panel_rule(m)
    sb, h = _log_stretches(la, k, omk)
    s = sb[:, None] + h[:, None] * jnp.asarray(t)[None, :]
    return h * jnp.sum(jnp.asarray(w) * _G(s, alpha[:, None]), axis=-1)


def _p_over_C_flagged(la, k, omk, alpha):
    """(p/C by one panel, NaN where the indicator exceeds PANEL_INDICATOR; flag) for broadcast inputs.

    ``flag`` marks the entries an eager call must redo with more panels (indicator above
    PANEL_INDICATOR, NaN indicator) or reject (log p/C beyond the float64 range)."""
    la, k, omk, alpha = jnp.broadcast_arrays(*(jnp.asarray(v, dtype=jnp.float64) for v in (la, k, omk, alpha)))
    c, log_bound = quadrature_indicator(la, k, omk, alpha)
    ok = c <= PANEL_INDICATOR
    pc = jnp.where(ok, _p_over_C_quad(la, k, omk, alpha), jnp.nan)
    return pc, ~ok | ~(log_bound <= _LOG_FLOAT_MAX)


_p_over_C_core = jax.jit(_p_over_C_flagged)


def _p_over_C(la, k, omk, alpha, what: str = "inner_stretch"):
    """p/C with the error kept below 1e-10 relative (the module docstring).

    Eager (concrete) input: one compiled call (one panel everywhere), then the entries whose indicator
    exceeds PANEL_INDICATOR get ceil(c / PANEL_INDICATOR) panels (rounded up to a power of 2, so few
    rules are compiled); a result beyond the float64 range raises ``ValueError``.
    Traced input (jit/vmap/grad): one panel; entries whose indicator exceeds PANEL_INDICATOR are NaN
    (the documented flag: the 20-point rule cannot be trusted there), overflow gives inf.
    """
    if is_traced(la, k, omk, alpha):
        return _p_over_C_flagged(la, k, omk, alpha)[0]
    pc, flag = _p_over_C_core(la, k, omk, alpha)
    if not np.asarray(flag).any():
        return pc
    return _fix_panels(pc, flag, la, k, omk, alpha, what)


def _fix_panels(pc, flag, la, k, omk, alpha, what: str):
    """Eager: redo the flagged entries of a one-panel p/C with the error-controlled composite rule."""
    flag = np.asarray(flag)
    L, K, O, Al = (np.broadcast_to(np.asarray(v, dtype=float), flag.shape)[flag] for v in (la, k, omk, alpha))
    out = np.array(pc)
    out[flag] = _p_over_C_panels_eager(L, K, O, Al, what)
    return jnp.asarray(out)


def _p_over_C_panels_eager(L, K, O, Al, what: str) -> np.ndarray:
    """p/C of 1-D NumPy inputs, ceil(c / PANEL_INDICATOR) panels each (raises on overflow)."""
    c, log_bound = quadrature_indicator(L, K, O, Al)
    with np.errstate(invalid="ignore"):
        over = log_bound > _LOG_FLOAT_MAX
    if np.any(over):
        i = int(np.flatnonzero(over)[0])
        raise ValueError(
            f"{what} {L[i]:g} with alpha = {Al[i]:g} needs a pressure beyond the float64 range "
            f"(p/C ~ 10^{log_bound[i] / np.log(10):.0f}): the Fung law stiffens as exp(2 alpha lambda^2); "
            "lower the stretch or alpha"
        )
    m = np.maximum(np.ceil(c / PANEL_INDICATOR), 1.0)
    if np.any(~np.isfinite(m)) or np.any(m > MAX_PANELS):
        i = int(np.flatnonzero(~(m <= MAX_PANELS))[0])
        raise ValueError(
            f"{what} {L[i]:g} with alpha = {Al[i]:g}: the pressure integral cannot be evaluated to 1e-10 "
            f"with {MAX_PANELS} panels (indicator {c[i]:.3g})"
        )
    buckets = 2 ** np.ceil(np.log2(m)).astype(int)
    out = np.empty(L.size)
    for b in np.unique(buckets):
        idx = np.flatnonzero(buckets == b)
        step = max(1, _NODES_PER_CHUNK // (20 * int(b)))
        for s0 in range(0, idx.size, step):
            sel = idx[s0 : s0 + step]
            out[sel] = np.asarray(_p_over_C_panels(L[sel], K[sel], O[sel], Al[sel], int(b)))
    return out


ODE_RTOL = 1e-10  # default relative tolerance of the radial-ODE path (agrees with the quadrature to ~2e-13)
_ODE_MAX_STEPS = 4096


def _p_over_C_ode(la, k, one_minus_k, alpha, rtol=ODE_RTOL):
    """p/C by the radial-equilibrium ODE (diffrax Dopri8, PID control at relative tolerance ``rtol``);
    NaN where the integration fails."""
    la, k, one_minus_k, alpha = jnp.broadcast_arrays(la, k, one_minus_k, alpha)
    sb, h = _log_stretches(la, k, one_minus_k)
    rtol = jnp.asarray(rtol, dtype=jnp.float64)

    def one(sb_i, h_i, alpha_i):
        import diffrax

        def rhs(t, y, args):
            return h_i * _G(sb_i + h_i * t, alpha_i)

        sol = diffrax.diffeqsolve(
            diffrax.ODETerm(rhs),
            diffrax.Dopri8(),
            t0=0.0,
            t1=1.0,
            dt0=None,
            y0=jnp.zeros((), dtype=jnp.float64),
            stepsize_controller=diffrax.PIDController(rtol=rtol, atol=1e-300),
            max_steps=_ODE_MAX_STEPS,
            saveat=diffrax.SaveAt(t1=True),
            throw=False,
        )
        return jnp.where(sol.result == diffrax.RESULTS.successful, sol.ys[-1], jnp.nan)

    flat = jax.vmap(one)(sb.ravel(), h.ravel(), alpha.ravel())
    return flat.reshape(la.shape)


def _concrete(checked, raw):
    """The validated NumPy array where the value was concrete, else the raw (traced) value."""
    return raw if checked is None else checked


def _pack(*values):
    """Concrete 0-d parameters as one float64 vector (one host-to-device transfer instead of one per
    argument; a compiled core unpacks it as it would a tuple), anything else as the tuple itself."""
    if all(type(v) is np.ndarray and v.ndim == 0 for v in values):
        return np.array(values, dtype=float)
    return values


_NO_X = object()  # marks a one-point call without per-point values (limit_point)


def _one_point(x, params, stretch: bool = True):
    """Fast path of a one-point eager call: ``(x, parameter vector, output shape)`` when ``x`` (or
    ``_NO_X``) and the shell and material ``params`` (A, B[, C, alpha]) are all Python numbers or size-1
    arrays that pass every input check (x > 0 for a stretch, else finite; 0 < A < B; C > 0;
    alpha >= 0, all finite); None otherwise, and then the full checks run (and raise their messages)."""
    got = scalar_values(*params) if x is _NO_X else scalar_values(x, *params)
    if got is None:
        return None
    vals, nd = got
    if not all(map(math.isfinite, vals)):
        return None
    if x is not _NO_X:
        xv = vals.pop(0)
        if stretch and not STRETCH_DOMAIN[0] <= xv <= STRETCH_DOMAIN[1]:
            return None
    A, B = vals[0], vals[1]
    if not (0.0 < A < B) or (len(vals) > 2 and not (vals[2] > 0.0 and vals[3] >= 0.0)):
        return None
    return (None if x is _NO_X else np.array(xv)), np.array(vals), (1,) * nd


_BUCKET_MAX = 1024  # concrete calls with at most this many points run padded to a power-of-two size


def _call(core, x, params, *static):
    """Run a compiled core on ``x`` (per-point values, or None) and ``params`` (A, B, C, alpha, ...).

    A concrete call with one point runs 0-d (one program per core for every size-1 shape). Concrete
    calls with 2 to ``_BUCKET_MAX`` points are flattened and padded (with their first
    entry, always a valid input) to a power-of-two size of at least 16, so that one compiled program
    serves every small shape (a command line that calls with scalars, 2, 11 and 600 points compiles
    each core once or twice, not once per shape); their outputs come back as NumPy arrays. Traced or
    larger calls run the core on the inputs as they are. Concrete calls get NumPy outputs (a view of
    the result buffer on CPU, no copy), traced calls the tracers.
    """
    values = tuple(params) if x is None else (x, *params)
    if not all(type(v) is np.ndarray for v in values):  # traced (or a JAX array passed through)
        return core(*(() if x is None else (x,)), _pack(*params), *static)
    shape = np.broadcast_shapes(*(v.shape for v in values))
    n = math.prod(shape)
    if n == 1:  # one point (Python floats or size-1 arrays): 0-d inputs, parameters in one vector
        ps = np.array([float(v.reshape(())) for v in params])
        args = (() if x is None else (x.reshape(()),)) + (ps,)
        out = small_call(core, tuple(range(len(args), len(args) + len(static))), one_point=True)(*args, *static)
        return jax.tree_util.tree_map(lambda o: _host(o).reshape(shape + o.shape), out)
    if n > _BUCKET_MAX:
        return jax.tree_util.tree_map(_host, core(*(() if x is None else (x,)), _pack(*params), *static))
    size = max(16, 1 << (n - 1).bit_length())

    def pad(v):
        f = np.broadcast_to(v, shape).ravel()
        return np.concatenate([f, np.full(size - n, f[0])])

    params = tuple(v.reshape(()) if v.size == 1 else v for v in params)  # (the output shape is known)
    scalar_params = all(v.ndim == 0 for v in params)
    ps = _pack(*params) if scalar_params else tuple(pad(v) for v in params)
    args = (() if x is None else (pad(x),)) + (ps,)
    out = small_call(core, tuple(range(len(args), len(args) + len(static))))(*args, *static)
    return jax.tree_util.tree_map(lambda o: _host(o)[:n].reshape(shape + o.shape[1:]), out)


def _host(o):
    """A compiled core's output as a NumPy array; a tracer stays one (concrete inputs inside a user's jit or vmap:
    the core was staged into the user's program, and the caller takes its traced branch)."""
    return o if isinstance(o, jax.core.Tracer) else np.asarray(o)


@jax.jit
def _pressure_core(la, params):
    """C p/C(lambda_a) by one panel; NaN where an eager call must take the composite rule (or raise)."""
    A, B, C, alpha = params
    k, omk = _geometry(A, B)
    pc, flag = _p_over_C_flagged(la, k, omk, alpha)
    return jnp.where(flag, jnp.nan, jnp.asarray(C, dtype=jnp.float64) * pc)


@jax.jit
def _pressure_ode_core(la, params, rtol):
    A, B, C, alpha = params
    k, omk = _geometry(A, B)
    la = jnp.asarray(la, dtype=jnp.float64)
    alpha = jnp.asarray(alpha, dtype=jnp.float64)
    return jnp.asarray(C, dtype=jnp.float64) * _p_over_C_ode(la, k, omk, alpha, rtol)


def pressure(
    inner_stretch: Array,
    *,
    inner_radius: Array,
    outer_radius: Array,
    C: Array,
    alpha: Array,
    method: str = "quadrature",
    rtol: float = ODE_RTOL,
) -> Array:
    r"""Internal pressure p (Pa) that holds the shell at inner stretch ``lambda_a = a/A``.

    p(lambda_a) = int_{lambda_b}^{lambda_a} 4 C exp(alpha (2 l^2 + l^-4 - 3)) (l^3 + 1)/l^5 dl,
    lambda_b^3 = 1 + (lambda_a^3 - 1)(A/B)^3.

    Parameters (all broadcast; jit/vmap/grad-able in every argument except ``method``):
    inner_stretch  lambda_a = a/A (dimensionless, > 0; < 1 is deflation, p < 0);
    inner_radius   A in m; outer_radius B in m (A < B); C in Pa (> 0); alpha >= 0.
    method         "quadrature" (20-point Gauss-Legendre in log l with a-priori error control, the
                   fast default) or "ode" (diffrax Dopri8 through the wall; an independent check,
                   ~40x slower; raises RuntimeError in eager calls if the integration fails, NaN inside jit).
    rtol           relative tolerance of the ODE integrator (dimensionless, > 0; default 1e-10, where
                   the two methods agree to ~2e-13); used by ``method="ode"`` only.
    Returns p in Pa, shape of the broadcast inputs.

    Accuracy: below 1e-10 relative for every input (module docstring, "Error control"). Eager calls
    raise ``ValueError`` for bad inputs and where p would overflow float64; inside jit/vmap/grad bad inputs
    raise at run time (``equinox.error_if``, the eager message without the value), the one-panel rule is used
    and entries it cannot resolve (large alpha lambda_a^2, overflow) are NaN.
    Eager calls run one compiled program (the same one a user's ``jax.jit`` runs), after the input checks.
    """
    if method == "quadrature":
        fast = _one_point(inner_stretch, (inner_radius, outer_radius, C, alpha))
        if fast is not None:
            p1 = _host(small_call(_pressure_core, one_point=True)(fast[0], fast[1]))
            if is_traced(p1) or not np.isnan(p1):
                return p1.reshape(fast[2])
    la = _concrete(_check_stretch("inner_stretch", inner_stretch), inner_stretch)
    A, B, C_, al = _validate(inner_radius, outer_radius, C, alpha)
    checks = _traced_stretch("inner_stretch", la) + _traced_shell(A, B, C_, al)  # run-time twins (traced values)
    validate_choice("method", method, ("quadrature", "ode"))
    if method == "ode":
        rt = validate_positive("rtol (relative tolerance of the ODE integrator)", rtol, "dimensionless")
        if rt is not None and rt.ndim != 0:
            raise ValueError(
                f"rtol (relative tolerance of the ODE integrator) must be one number; got shape {rt.shape}"
            )
        p = jnp.asarray(_pressure_ode_core(la, _pack(A, B, C_, al), _concrete(rt, rtol)))
        if not is_traced(p):
            bad = ~np.isfinite(np.asarray(p))
            if np.any(bad):
                stretch = np.broadcast_to(np.asarray(la, dtype=float), bad.shape)[bad]
                raise RuntimeError(
                    f"the radial-ODE integration failed at inner stretch {stretch.ravel()[0]:g} (diffrax did not "
                    f"reach the inner wall in {_ODE_MAX_STEPS} steps). Hint: use method='quadrature' (exact to 1e-13)."
                )
            return np.asarray(p)  # eager results are NumPy arrays, whichever method
        return traced_checks(p, checks)
    p = _call(_pressure_core, la, (A, B, C_, al))
    if is_traced(p):
        return traced_checks(p, checks)
    if not np.isnan(p).any():
        return p
    k, omk = _geometry(A, B)
    return np.asarray(jnp.asarray(C_, dtype=jnp.float64) * _p_over_C(la, k, omk, al))


def _dp_over_C(la, k, alpha):
    """d(p/C)/d lambda_a = g(lambda_a) - g(lambda_b) k lambda_a^2 / lambda_b^2 (Leibniz)."""
    lb = jnp.exp(jnp.log1p((la**3 - 1.0) * k) / 3.0)  # the cube root, 2x cheaper than jnp.cbrt on CPU
    return _g(la, alpha) - _g(lb, alpha) * k * la**2 / lb**2


@jax.jit
def _pressure_derivative_core(la, params):
    A, B, C, alpha = params
    k, _ = _geometry(A, B)
    la = jnp.asarray(la, dtype=jnp.float64)
    return jnp.asarray(C, dtype=jnp.float64) * _dp_over_C(la, k, jnp.asarray(alpha, dtype=jnp.float64))


def pressure_derivative(
    inner_stretch: Array, *, inner_radius: Array, outer_radius: Array, C: Array, alpha: Array
) -> Array:
    r"""dp/d lambda_a in Pa, closed form (Leibniz rule on the pressure integral):

    dp/d lambda_a = g(lambda_a) - g(lambda_b) d lambda_b/d lambda_a,
    d lambda_b/d lambda_a = (A/B)^3 lambda_a^2 / lambda_b^2,  g(l) = 4 W'(I1(l)) (l^3 + 1)/l^5.

    Arguments as :func:`pressure` (inner_stretch > 0; A < B in m; C > 0 in Pa; alpha >= 0), broadcast.
    Returns dp/d lambda_a in Pa (to ~1e-14 for walls thicker than ~1e-2 of A; the two terms cancel as A/B -> 1:
    ~5e-16 / (wall / A), 4.9e-10 at a wall of 1e-6 A). Raises ``ValueError`` for bad inputs and for a slope beyond
    the float64 range in eager calls; under jit/vmap/grad bad inputs raise at run time (``equinox.error_if``) and a
    slope beyond float64 is NaN.
    """
    fast = _one_point(inner_stretch, (inner_radius, outer_radius, C, alpha))
    if fast is not None:
        out = _host(small_call(_pressure_derivative_core, one_point=True)(fast[0], fast[1])).reshape(fast[2])
        if is_traced(out) or np.isfinite(out).all():
            return out
    la = _concrete(_check_stretch("inner_stretch", inner_stretch), inner_stretch)
    A, B, C_, al = _validate(inner_radius, outer_radius, C, alpha)
    out = _call(_pressure_derivative_core, la, (A, B, C_, al))
    if is_traced(out):  # the NaN flag where an eager call raises (a slope beyond the float64 range)
        checks = _traced_stretch("inner_stretch", la) + _traced_shell(A, B, C_, al)
        return traced_checks(jnp.where(jnp.isfinite(out), out, jnp.nan), checks)
    if np.isfinite(out).all():
        return out
    bad = ~np.isfinite(np.asarray(out))
    la_b, al_b = (np.broadcast_to(np.asarray(v, dtype=float), bad.shape)[bad][0] for v in (la, al))
    raise ValueError(
        f"dp/d lambda_a at inner_stretch {la_b:g} with alpha = {al_b:g} is beyond the float64 range: the Fung law "
        "stiffens as exp(2 alpha lambda^2) (and the slope grows as lambda^-5 towards collapse); lower the stretch or alpha"
    )


@jax.jit
def _outer_stretch_core(la, params):
    A, B = params
    k, omk = _geometry(A, B)
    sb, _ = _log_stretches(jnp.asarray(la, dtype=jnp.float64), k, omk)
    return jnp.exp(sb)


def _outer_stretch_numpy(la, A, B) -> np.ndarray:
    """Eager :func:`outer_stretch` of checked NumPy values: the same closed form in NumPy (a few operations: no
    program to compile, which a command's first call would pay for; equal to the compiled core to ~1 ulp)."""
    k, omk = _geometry(A, B, np)
    return np.asarray(np.exp(_log_stretches(np.asarray(la, dtype=float), k, omk)[0]))


def outer_stretch(inner_stretch: Array, *, inner_radius: Array, outer_radius: Array) -> Array:
    r"""Outer stretch lambda_b = b/B from incompressibility (dimensionless):

    lambda_b^3 = 1 + (lambda_a^3 - 1)(A/B)^3,  A = inner_radius, B = outer_radius (m).
    Raises ``ValueError`` for bad inputs in eager calls; under jit/vmap/grad at run time (``equinox.error_if``).
    """
    fast = _one_point(inner_stretch, (inner_radius, outer_radius))
    if fast is not None:
        return _outer_stretch_numpy(fast[0], *fast[1]).reshape(fast[2])
    la = _concrete(_check_stretch("inner_stretch", inner_stretch), inner_stretch)
    A, B = validate_radii(inner_radius, outer_radius)
    A, B = _concrete(A, inner_radius), _concrete(B, outer_radius)
    if not any(isinstance(v, jax.Array) for v in (la, A, B)):  # concrete (tracers are jax.Arrays)
        return _outer_stretch_numpy(la, A, B)
    return traced_checks(
        _call(_outer_stretch_core, la, (A, B)), _traced_stretch("inner_stretch", la) + traced_radii(A, B)
    )


# ---------------------------------------------------------------------------------------------
# Limit point (maximum of p(lambda_a)): closed-form dp/dlambda_a, grid scan + bisection
# ---------------------------------------------------------------------------------------------

LIMIT_SEARCH_MAX_STRETCH = 10.0  # a maximum is searched for on 1 < lambda_a <= 10
_LIMIT_NODES = 256
_LIMIT_GRID = np.geomspace(1.0, LIMIT_SEARCH_MAX_STRETCH, _LIMIT_NODES + 1)[1:]
_BISECTIONS = 12  # the grid cell (0.9 % wide) to ~2e-6, then Newton (quadratic) to round-off
_NEWTON_STEPS = 4


class LimitPoint(NamedTuple):
    """Maximum of the pressure-stretch curve: ``pressure`` (Pa) at ``inner_stretch`` (a/A).

    Beyond it the shell inflates without bound under a prescribed pressure ("bursts").
    Read the fields by name. Eager scalar calls hold Python floats; array or traced calls hold
    arrays, where NaN entries mean: no maximum for 1 < lambda_a <= 10.
    """

    pressure: Array
    inner_stretch: Array


_LIMIT_CHUNK = 2048  # lanes per block of the grid scan: memory stays flat in N (256 x 2048 doubles a temporary)


def _slope_sides(la, k, alpha):
    """The two sides of dp/dla >= 0 in a form with one exponential and no cube root:
    g(la) >= g(lb) k la^2/lb^2  <=>  exp(alpha (q(la) - q(lb))) (la^3 + 1) la^-7 >= k (lb^3 + 1) lb^-7,
    q(l) = 2 l^2 + l^-4, lb^3 = 1 + (la^3 - 1) k. Returns (left, right), both > 0; left/right - 1 is the
    relative slope (its sign is the sign of dp/dla)."""
    la2 = la * la
    la3 = la2 * la
    lb3 = 1.0 + (la3 - 1.0) * k
    inv_lb = jnp.exp(-jnp.log(lb3) / 3.0)
    ib2 = inv_lb * inv_lb
    ib4 = ib2 * ib2
    ila4 = 1.0 / (la2 * la2)
    dq = 2.0 * la2 + ila4 - 2.0 / ib2 - ib4
    return jnp.exp(alpha * dq) * (la3 + 1.0) * ila4 * ila4 * la, k * (lb3 + 1.0) * ib4 * ib2 * inv_lb


def _falling(la, k, alpha):
    """dp/dla <= 0 (past the maximum), see :func:`_slope_sides`."""
    left, right = _slope_sides(la, k, alpha)
    return left <= right


def _slope_ratio(la, k, alpha):
    """left/right of :func:`_slope_sides`: < 1 exactly where dp/dla < 0 (inf where the Fung term overflows)."""
    left, right = _slope_sides(la, k, alpha)
    return left / right


_GOLDEN_STEPS = 24  # golden-section steps of the dip search: the 2-cell interval (<= 1.8 %) to ~3e-7 in lambda_a,
# the minimum of the slope ratio r to ~r'' x 5e-14: only a dip whose relative slope stays above about -r'' x 5e-14
# (a maximum that p exceeds again by round-off only) can still be missed
_INV_PHI = (np.sqrt(5.0) - 1.0) / 2.0


def _argmin_positive(x):
    """argmin over the last axis (< 256 entries) of positive floats (inf allowed) as ONE integer min: the index
    replaces the 8 lowest mantissa bits (positive doubles order as their int64 bits), so the reduction fuses with
    the scan that makes ``x`` (``jnp.argmin`` does not on XLA CPU: +40 % on the scan). Ties within 256 ulp go to
    either index (the dip search needs only a node next to the minimum)."""
    n = x.shape[-1]
    assert n <= 256
    bits = jax.lax.bitcast_convert_type(x, jnp.int64)
    return jnp.min((bits & ~jnp.int64(255)) | jnp.arange(n, dtype=jnp.int64), axis=-1) & 255


def _dip(j, k, alpha):
    """Lanes whose grid shows no falling node: the minimum of the relative slope near the grid minimum
    (golden section on the two grid cells around it). A dip of dp/dla narrower than a grid cell can fall
    below zero between two rising nodes; then the refined minimum is past the maximum and the grid node
    before it is not: a bracket. ``j``: index of the grid minimum of the relative slope per lane (1-D, as k and
    alpha). Returns (lo, hi, found) of those brackets."""
    grid = jnp.asarray(_LIMIT_GRID)
    a = jnp.where(j > 0, jnp.take(grid, jnp.maximum(j - 1, 0)), 1.0)
    b = jnp.take(grid, jnp.minimum(j + 1, grid.size - 1))
    c = b - _INV_PHI * (b - a)
    d = a + _INV_PHI * (b - a)
    fc, fd = _slope_ratio(c, k, alpha), _slope_ratio(d, k, alpha)

    def golden(_, state):
        a, b, c, d, fc, fd = state
        left = fc < fd  # the minimum is in [a, d]
        a, b = jnp.where(left, a, c), jnp.where(left, d, b)
        x = jnp.where(left, b - _INV_PHI * (b - a), a + _INV_PHI * (b - a))
        fx = _slope_ratio(x, k, alpha)
        c, d = jnp.where(left, x, d), jnp.where(left, c, x)
        fc, fd = jnp.where(left, fx, fd), jnp.where(left, fc, fx)
        return a, b, c, d, fc, fd

    _, _, c, d, fc, fd = jax.lax.fori_loop(0, _GOLDEN_STEPS, golden, (a, b, c, d, fc, fd))
    x = jnp.where(fc < fd, c, d)
    found = jnp.minimum(fc, fd) < 1.0  # left < right there: dp/dla < 0, past the maximum
    node = jnp.take(grid, j)
    lo = jnp.where(x > node, node, a)  # a rising grid node (or lambda_a = 1) before the dip
    return lo, x, found


def _limit_bracket(k, alpha):
    """First root of dp/dla on (1, 10] (1-D k, alpha of one block; no gradient): scan of the
    ``_LIMIT_GRID`` nodes (lanes without a falling node: the dip search :func:`_dip` around the grid minimum
    of the slope), ``_BISECTIONS`` bisections, then safeguarded Newton steps on dp/dla.
    Returns (stretch, exists)."""
    grid = jnp.asarray(_LIMIT_GRID)
    left, right = _slope_sides(grid, k[:, None], alpha[:, None])
    falling = left <= right
    exists = jnp.any(falling, axis=-1)
    i = jnp.argmax(falling, axis=-1)  # first grid node past the maximum
    j = _argmin_positive(left / right)  # the grid minimum of the relative slope (for the dip search)
    hi = jnp.take(grid, i)
    lo = jnp.where(i > 0, jnp.take(grid, jnp.maximum(i - 1, 0)), 1.0)
    # no falling node: a narrow dip between two nodes (rare; blocks where every lane has one skip the search)
    dip_lo, dip_hi, dip = jax.lax.cond(
        jnp.all(exists),
        lambda: (lo, hi, jnp.zeros_like(exists)),
        lambda: _dip(j, k, alpha),
    )
    dip = dip & ~exists
    lo, hi, exists = jnp.where(dip, dip_lo, lo), jnp.where(dip, dip_hi, hi), exists | dip

    def bisect(_, bounds):
        lo, hi = bounds
        mid = 0.5 * (lo + hi)
        down = _falling(mid, k, alpha)
        return jnp.where(down, lo, mid), jnp.where(down, mid, hi)

    lo, hi = jax.lax.fori_loop(0, _BISECTIONS, bisect, (lo, hi))

    def newton(_, state):
        x, lo, hi = state
        d, dd = jax.jvp(lambda v: _dp_over_C(v, k, alpha), (x,), (jnp.ones_like(x),))
        down = d <= 0.0
        lo, hi = jnp.where(down, lo, x), jnp.where(down, x, hi)
        step = x - d / jnp.where(dd < 0.0, dd, -1.0)
        ok = (dd < 0.0) & (step >= lo) & (step <= hi)
        return jnp.where(ok, step, 0.5 * (lo + hi)), lo, hi

    x, _, _ = jax.lax.fori_loop(0, _NEWTON_STEPS, newton, (0.5 * (lo + hi), lo, hi))
    return x, exists


def _limit_stretch(k, alpha):
    """First root of dp/dla on (1, 10] (NaN if dp/dla > 0 on the whole search grid), broadcast inputs.

    The scan runs block by block (``_LIMIT_CHUNK`` lanes) so that memory does not grow with the
    256-node grid; the gradient comes from one Newton step with a frozen curvature (implicit function)."""
    k, alpha = jnp.broadcast_arrays(jnp.asarray(k, dtype=jnp.float64), jnp.asarray(alpha, dtype=jnp.float64))
    ks, als = (jax.lax.stop_gradient(v).ravel() for v in (k, alpha))
    n = ks.size
    if n <= _LIMIT_CHUNK:
        la, exists = _limit_bracket(ks, als)
    else:
        m = -(-n // _LIMIT_CHUNK)
        pad = m * _LIMIT_CHUNK - n
        blocks = tuple(
            jnp.concatenate([v, jnp.full((pad,), f)]).reshape(m, _LIMIT_CHUNK) for v, f in ((ks, 0.3), (als, 0.0))
        )
        la, exists = jax.lax.map(lambda kb: _limit_bracket(*kb), blocks)
        la, exists = la.ravel()[:n], exists.ravel()[:n]
    la, exists = la.reshape(k.shape), exists.reshape(k.shape)
    la = jax.lax.stop_gradient(la)
    # one Newton step with a frozen curvature: same value, exact implicit derivative in (k, alpha)
    h = 1e-6 * la
    curv = jax.lax.stop_gradient((_dp_over_C(la + h, k, alpha) - _dp_over_C(la - h, k, alpha)) / (2 * h))
    la = la - _dp_over_C(la, k, alpha) / curv
    return jnp.where(exists, la, jnp.nan)


@jax.jit
def _limit_core(params):
    """(p_max, stretch at the maximum); p_max NaN where there is no maximum or where an eager call
    must take the composite rule (then ``redo`` is True there)."""
    A, B, C, alpha = params
    k, omk = _geometry(A, B)
    alpha = jnp.asarray(alpha, dtype=jnp.float64)
    la = _limit_stretch(k, alpha)
    la_b, k_b, omk_b, alpha_b = jnp.broadcast_arrays(la, k, omk, alpha)
    none = jnp.isnan(la_b)
    pc, flag = _p_over_C_flagged(jnp.where(none, 1.0, la_b), k_b, omk_b, alpha_b)
    pmax = jnp.where(none | flag, jnp.nan, jnp.asarray(C, dtype=jnp.float64) * pc)
    return pmax, la_b, flag & ~none


def limit_point(*, inner_radius: Array, outer_radius: Array, C: Array, alpha: Array) -> LimitPoint | None:
    r"""Limit point of the inflation curve: ``(p_max [Pa], lambda_a at the maximum)``, or ``None``.

    The maximum is the first root of the closed-form slope (Leibniz rule)
    dp/dlambda_a = g(lambda_a) - g(lambda_b) (A/B)^3 lambda_a^2/lambda_b^2 on 1 < lambda_a <= 10
    (scan on a 256-node geometric grid; where no node has dp/dlambda_a <= 0, a golden-section search for the
    minimum of the slope around the grid minimum, so that a dip below zero narrower than a grid cell is not
    missed; 12 bisections, 4 safeguarded Newton steps; the stretch is exact
    to round-off, ~1e-14, for walls down to ~1e-3 of the inner radius; thinner walls lose digits as the slope's
    two terms cancel for A/B -> 1, ~3e-17 / (wall / A): 1.5e-11 at a wall of 1e-6 A, 3.4e-8 at 1e-9 A; p_max,
    stationary there, keeps ~1e-15).
    Arguments: inner_radius A and outer_radius B in m (A < B), C in Pa (> 0), alpha >= 0 (broadcast).
    Returns ``None`` for scalar eager inputs without a maximum up to lambda_a = 10 (e.g. Fung with
    alpha >= ~0.06 for A/B = 2/3 stiffens before it can go unstable), a ``LimitPoint`` of two floats
    for scalar eager inputs with one. For array or traced (jit/vmap/grad) inputs it returns a
    ``LimitPoint`` of arrays with NaN where there is no maximum.
    Gradients are exact (envelope theorem for p_max; implicit function theorem for the stretch).
    The scan runs in blocks of lanes: memory does not grow with the 256-node grid. Raises
    ``ValueError`` for bad inputs in eager calls; under jit/vmap/grad bad inputs (radii, C, alpha) raise at run
    time (``equinox.error_if``) and p_max is NaN where the one-panel rule cannot resolve it.
    """
    fast = _one_point(_NO_X, (inner_radius, outer_radius, C, alpha))
    if fast is not None:
        pm1, la1, redo1 = (_host(v) for v in small_call(_limit_core, one_point=True)(fast[1]))
        if is_traced(pm1):  # inside a user's jit/vmap: the traced convention (NaN where there is no maximum)
            return LimitPoint(pm1.reshape(fast[2]), la1.reshape(fast[2]))
        if not redo1:
            if not fast[2]:
                return None if np.isnan(pm1) else LimitPoint(float(pm1), float(la1))
            return LimitPoint(pm1.reshape(fast[2]), la1.reshape(fast[2]))
    A, B, C_, al = _validate(inner_radius, outer_radius, C, alpha)
    pmax, la, redo = _call(_limit_core, None, (A, B, C_, al))
    if is_traced(pmax):
        return LimitPoint(*traced_checks((pmax, la), _traced_shell(A, B, C_, al)))
    if np.asarray(redo).any():  # stiff states: the error-controlled quadrature (eager, rare)
        k, omk = _geometry(A, B)
        la_s = jnp.where(jnp.isnan(la), 1.0, la)
        la_b, k_b, omk_b, al_b = jnp.broadcast_arrays(la_s, k, omk, jnp.asarray(al, dtype=jnp.float64))
        pc = _p_over_C(la_b, k_b, omk_b, al_b, "limit stretch")
        pmax = jnp.where(jnp.isnan(la), jnp.nan, jnp.asarray(C_, dtype=jnp.float64) * pc)
    if np.ndim(pmax) == 0:
        if np.isnan(pmax):
            return None
        return LimitPoint(float(pmax), float(la))
    return LimitPoint(np.asarray(pmax), np.asarray(la))


# ---------------------------------------------------------------------------------------------
# Inverse: safeguarded Newton in x = log lambda_a
# ---------------------------------------------------------------------------------------------

INVERSE_STRETCH_RANGE = (0.5, LIMIT_SEARCH_MAX_STRETCH)
_COARSE_NODES = 6  # stage 1: Newton on a 6-point rule (cheap) to get close
_COARSE_ITER = 60
_FINE_ITER = 30  # stage 2: polish with the full 20-point rule (typically 2-3 steps)


def _rule_residual(x, k, omk, alpha, xr, wr, curvature=False):
    """(P, dP/dx[, d2P/dx2]): p/C at lambda_a = exp(x) by the Gauss rule (xr, wr) in s = log l and
    its exact x-derivatives (Leibniz in s): dP/dx = G(x) - G(s_b) q with q = d s_b/dx =
    k exp(3 (x - s_b)); d2P/dx2 = G(x) D(x) - G(s_b) q (D(s_b) q + 3 (1 - q)), D = d log G/ds."""
    e = jnp.expm1(3.0 * x)
    sb = jnp.log1p(e * k) / 3.0
    h = jnp.log1p(e * omk / (1.0 + e * k)) / 3.0
    # the nodes apart from the two ends and the weighted sum as a product with the weights: half the
    # time of one (.., 22) array of nodes on XLA CPU
    s = sb[..., None] + (0.5 * h)[..., None] * (jnp.asarray(xr) + 1.0)
    P = 0.5 * h * (_G(s, alpha[..., None]) @ jnp.asarray(wr))
    Ga, Gb = _G(x, alpha), _G(sb, alpha)
    q = k * jnp.exp(3.0 * (x - sb))
    d = Ga - Gb * q
    if not curvature:
        return P, d
    Da, Db = _log_G_and_slope(x, alpha, jnp)[1], _log_G_and_slope(sb, alpha, jnp)[1]
    return P, d, Ga * Da - Gb * q * (Db * q + 3.0 * (1.0 - q))


def _resolved(r, d, pt):
    """The convergence test of the inverse: positive slope and residual r = p/C - pt within 1e-11
    relative, or what a 2e-13 change of log(lambda_a) makes (near lambda_a = 1 only absolute
    resolution exists)."""
    return (d > 0.0) & (jnp.abs(r) <= 1e-11 * jnp.abs(pt) + 2e-13 * jnp.abs(d))


def _newton_update(x, lo, hi, pt, target, k, omk, alpha, xr, wr, tol, stop_when_resolved):
    """One safeguarded Newton step of :func:`_newton` (all lanes): (x, lo, hi after it, stop, r, d)."""
    if stop_when_resolved:
        P, d, d2 = _rule_residual(x, k, omk, alpha, xr, wr, curvature=True)
    else:
        P, d = _rule_residual(x, k, omk, alpha, xr, wr)
    r = P - pt
    past = (d <= 0.0) | (r > 0.0)
    lo_n = jnp.where(past, lo, x)
    hi_n = jnp.where(past, x, hi)
    dF = d / jnp.sqrt(1.0 + P * P)
    newton = x - (jnp.arcsinh(P) - target) / jnp.where(d > 0.0, dF, 1.0)
    # a Newton step below tol in x is the last one needed (quadratic convergence)
    small = (d > 0.0) & (jnp.abs(newton - x) <= tol)
    if stop_when_resolved:
        q2 = 1.0 + P * P
        d2F = (d2 - P * d * d / q2) / jnp.sqrt(q2)
        step = newton - x
        small = small | (_resolved(r, d, pt) & (jnp.abs(d2F) * step * step <= 2e-15 * dF))
    ok = small | ((d > 0.0) & (newton > lo_n) & (newton < hi_n))
    x_n = jnp.where(ok, newton, 0.5 * (lo_n + hi_n))
    x_n = jnp.where(r == 0.0, x, x_n)
    stop = small | (r == 0.0) | (hi_n - lo_n <= tol)
    return x_n, lo_n, hi_n, stop, r, d


def _newton(pt, k, omk, alpha, x0, lo, hi, rule, max_iter, tol, stop_when_resolved=False, done=None, full=False):
    """Safeguarded Newton for p/C(exp(x)) = pt on the rising branch, bracket [lo, hi] in x.

    Newton is applied to asinh(p/C): linear for |p| << C, logarithmic for the exponentially
    stiffening Fung branch, so that few steps are needed from far away. The bracket is kept by
    the rule "x is past the root if p(x) > pt or dp/dx <= 0 (beyond the limit point)"; a step that
    leaves the bracket, or a non-positive slope, is replaced by bisection. A lane stops after a
    Newton step below ``tol`` in x or, with ``stop_when_resolved``, after the step from a point that
    passes :func:`_resolved` where the error that step leaves, |F''/(2 F')| step^2 (quadratic
    convergence, F = asinh(p/C) and its closed-form derivatives in x), is below 1e-15.
    Returns (x, r, d): the final x and the residual p/C - pt and slope dP/dx at the last point
    evaluated (the one before the final Newton step), for the convergence check; with ``full``
    (x, lo, hi, done): the state to continue from (``done``: the lanes already stopped at entry).
    """
    target = jnp.arcsinh(pt)
    xr = jnp.asarray(rule[0])
    wr = jnp.asarray(rule[1])

    def cond(state):
        return (state[3] < max_iter) & ~jnp.all(state[4])

    def body(state):
        x, lo, hi, it, done, r_old, d_old = state
        x_n, lo_n, hi_n, stop, r, d = _newton_update(
            x, lo, hi, pt, target, k, omk, alpha, xr, wr, tol, stop_when_resolved
        )
        keep = done
        return (
            jnp.where(keep, x, x_n),
            jnp.where(keep, lo, lo_n),
            jnp.where(keep, hi, hi_n),
            it + 1,
            done | stop,
            jnp.where(keep, r_old, r),
            jnp.where(keep, d_old, d),
        )

    nan = jnp.full(pt.shape, jnp.nan)
    done0 = jnp.zeros(pt.shape, dtype=bool) if done is None else done
    state = (x0, lo, hi, jnp.asarray(0), done0, nan, nan)
    x, lo, hi, _, done, r, d = jax.lax.while_loop(cond, body, state)
    return (x, lo, hi, done) if full else (x, r, d)


_CHUNK = 1024  # large inputs are solved chunk by chunk: each chunk stops when its own lanes converge
_TABLE_NODES = 8192  # start table of one shell (scalar k, alpha): nodes in x = log lambda_a on [log 0.5, log 10]


def _start_table(k, omk, alpha):
    """Start table for the inverse of ONE shell (0-d k, 1 - k, alpha): F = asinh(p/C) and dF/dx at
    ``_TABLE_NODES`` equally spaced x = log lambda_a on the search range, by the 20-point rule.
    Nodes past the first one where the curve stops rising (limit point, overflow) get F = inf, so
    that a search finds only the rising branch. Costs ~1e5 integrand values (~1 ms): used for
    large calls only."""
    xs = jnp.linspace(np.log(INVERSE_STRETCH_RANGE[0]), np.log(INVERSE_STRETCH_RANGE[1]), _TABLE_NODES)
    shape = xs.shape
    P, d = _rule_residual(
        xs, jnp.broadcast_to(k, shape), jnp.broadcast_to(omk, shape), jnp.broadcast_to(alpha, shape), _X, _W
    )
    F = jnp.arcsinh(P)
    dF = d / jnp.sqrt(1.0 + P * P)
    good = (dF > 0.0) & jnp.isfinite(F) & jnp.isfinite(dF)
    rising = jnp.cumprod(good.astype(jnp.int32)) > 0
    rising = rising & jnp.concatenate([jnp.ones((1,), bool), F[1:] > F[:-1]])
    rising = jnp.cumprod(rising.astype(jnp.int32)) > 0
    return xs, jnp.where(rising, F, jnp.inf), jnp.where(rising, dF, 1.0)


def _table_start(pt, table, fallback):
    """x0 by cubic Hermite interpolation of the inverse x(F) between the two table nodes around
    F = asinh(pt) (``fallback`` where the target is outside the rising part of the table)."""
    xs, F, dF = table
    target = jnp.arcsinh(pt)
    j = jnp.clip(jnp.searchsorted(F, target, side="right", method="scan_unrolled") - 1, 0, F.size - 2)
    F0, F1 = F[j], F[j + 1]
    x0, x1 = xs[j], xs[j + 1]
    HF = F1 - F0
    t = (target - F0) / HF
    m0, m1 = HF / dF[j], HF / dF[j + 1]
    t2 = t * t
    t3 = t2 * t
    x = (2 * t3 - 3 * t2 + 1) * x0 + (t3 - 2 * t2 + t) * m0 + (-2 * t3 + 3 * t2) * x1 + (t3 - t2) * m1
    inside = (target >= F0) & (target <= F1) & jnp.isfinite(HF) & jnp.isfinite(x)
    return jnp.where(inside, x, fallback)


@jax.jit
def _solve_stretch(p_over_C, k, omk, alpha, max_stretch=INVERSE_STRETCH_RANGE[1]):
    """Inverse of p/C(lambda_a) on the rising branch by the one-panel rule, searching
    lambda_a <= ``max_stretch`` (per lane; e.g. the limit stretch, so that the far, re-stiffening
    branch of a Fung shell is never returned).

    Large calls (more than 2 chunks) for one shell (0-d k, 1 - k, alpha) start from a table of the
    curve (:func:`_start_table`), so that one or two 20-point Newton steps finish each lane; the
    blocks of other large calls run a 6-point Newton stage first; small calls (up to 2 chunks) run
    the 20-point Newton from the small-strain guess (one loop to compile: what they pay for most).

    Returns (lambda_a, converged, rule_ok): ``rule_ok`` is False where the 20-point rule cannot be
    trusted to 1e-10 at the solution (quadrature indicator above PANEL_INDICATOR)."""
    one_shell = all(jnp.ndim(v) == 0 for v in (k, omk, alpha))
    pt, k, omk, alpha, mx = jnp.broadcast_arrays(p_over_C, k, omk, alpha, jnp.asarray(max_stretch, jnp.float64))
    pt, k, omk, alpha, mx = (jax.lax.stop_gradient(v) for v in (pt, k, omk, alpha, mx))
    if pt.size <= 2 * _CHUNK:
        return _solve_block(pt, k, omk, alpha, mx, coarse_stage=False)
    table = _start_table(k.ravel()[0], omk.ravel()[0], alpha.ravel()[0]) if one_shell else None
    n = pt.size
    m = -(-n // _CHUNK)
    pad = m * _CHUNK - n
    # padding lanes: p = 0 in a valid shell (converge at once)
    fills = (0.0, 0.5, 0.5, 0.0, INVERSE_STRETCH_RANGE[1])
    blocks = tuple(
        jnp.concatenate([v.ravel(), jnp.full((pad,), f, dtype=v.dtype)]).reshape(m, _CHUNK)
        for v, f in zip((pt, k, omk, alpha, mx), fills)
    )
    if table is not None:
        outs = jax.lax.map(lambda b: _solve_block(*b, table=table), blocks)
    else:
        outs = _solve_regrouped(*(v.reshape(-1, _REGROUP_CHUNK) for v in blocks))
    return tuple(o.ravel()[:n].reshape(pt.shape) for o in outs)


_COARSE_FIRST = 7  # coarse Newton steps every lane takes before the unfinished lanes are regrouped
# lanes per block of the regrouped stages (divides _CHUNK): smaller blocks stop sooner, larger ones pay less per
# step; 256 measured fastest on random shells (`python -m tissuemech.compare.bench.reduced_blastula --workload-only`)
_REGROUP_CHUNK = 256


def _solve_regrouped(pt, k, omk, alpha, max_stretch):
    """The inverse on (blocks, lanes) arrays of many shells, each Newton stage in two phases.

    A block's Newton loop runs until its slowest lane stops: ~14 coarse steps per block of 1024 on
    random shells where the mean lane needs 5.9 (a few lanes of small alpha whose root lies where
    the curve is nearly flat converge linearly). So every lane takes at most ``_COARSE_FIRST``
    coarse steps, then the unfinished ones (~6 %) are gathered into the first blocks and continue
    there (a block with no unfinished lane stops at once), then go back to their places; the
    20-point polish likewise: one step for every lane (no loop), the lanes it does not finish
    regrouped for the rest. The same steps as the one-phase loops, lane by lane."""
    coarse = np.polynomial.legendre.leggauss(_COARSE_NODES)
    xr, wr = jnp.asarray(_X), jnp.asarray(_W)

    def first(b):
        pt_, k_, omk_, al_, mx_ = b
        x0, lo, hi = _start(pt_, omk_, mx_)
        return _newton(pt_, k_, omk_, al_, x0, lo, hi, coarse, _COARSE_FIRST, 1e-7, full=True)

    x, lo, hi, done = jax.lax.map(first, (pt, k, omk, alpha, max_stretch))

    def rest(b):
        pt_, k_, omk_, al_, x_, lo_, hi_, done_ = b
        left = _COARSE_ITER - _COARSE_FIRST
        return _newton(pt_, k_, omk_, al_, x_, lo_, hi_, coarse, left, 1e-7, done=done_, full=True)[0]

    x = _regrouped(rest, (pt, k, omk, alpha, x, lo, hi, done), done)

    def polish_first(b):  # one 20-point step from the coarse root, every lane
        pt_, k_, omk_, al_, mx_, x1 = b
        _, lo, hi = _start(pt_, omk_, mx_)
        return _newton_update(x1, lo, hi, pt_, jnp.arcsinh(pt_), k_, omk_, al_, xr, wr, 1e-13, True)

    x2, lo, hi, stop, r, d = jax.lax.map(polish_first, (pt, k, omk, alpha, max_stretch, x))

    def polish_rest(b):  # the lanes one step did not finish continue the loop where that step left them
        pt_, k_, omk_, al_, x2_, lo_, hi_, r_, d_, stop_ = b
        x, rr, dd = _newton(
            pt_, k_, omk_, al_, x2_, lo_, hi_, (_X, _W), _FINE_ITER - 1, 1e-13, stop_when_resolved=True, done=stop_
        )
        return x, jnp.where(stop_, r_, rr), jnp.where(stop_, d_, dd)

    x, r, d = _regrouped(polish_rest, (pt, k, omk, alpha, x2, lo, hi, r, d, stop), stop, outputs=3)
    return jax.lax.map(lambda b: _finish(*b), (x, r, d, pt, k, omk, alpha))


def _regrouped(fn, arrays, done, outputs=1):
    """``jax.lax.map(fn, arrays)`` over blocks (rows), with the lanes not ``done`` moved to the first
    blocks before (a stable partition by prefix sums, no sort) and back after: loops that stop when
    a block's lanes are done then run only where work is left."""
    shape = done.shape
    u = ~done.ravel()
    cu = jnp.cumsum(u)
    dest = jnp.where(u, cu - 1, cu[-1] + jnp.cumsum(~u) - 1)  # each lane's place in the regrouped order
    group = lambda v: jnp.zeros_like(v.ravel()).at[dest].set(v.ravel(), unique_indices=True).reshape(shape)
    out = jax.lax.map(fn, tuple(group(v) for v in arrays))
    outs = out if outputs > 1 else (out,)
    back = tuple(o.ravel()[dest].reshape(shape) for o in outs)
    return back if outputs > 1 else back[0]


def _start(pt, omk, max_stretch):
    """(x0, lo, hi): the small-strain start p/C ~ 8 (1 - k)(lambda_a - 1) in x = log lambda_a, inside the
    search bracket [lo, hi] (x >= 0 for p >= 0, x <= 0 for p < 0)."""
    xmin = np.log(INVERSE_STRETCH_RANGE[0])
    xmax = jnp.log(jnp.clip(max_stretch, 1.0, INVERSE_STRETCH_RANGE[1]))
    lo = jnp.where(pt >= 0.0, 0.0, xmin)
    hi = jnp.where(pt >= 0.0, xmax, 0.0)
    guess = jnp.log(jnp.maximum(1.0 + pt / (8.0 * omk), 1e-300))
    return jnp.where((guess >= lo) & (guess <= hi), guess, 0.5 * (lo + hi)), lo, hi


def _finish(x, r, d, pt, k, omk, alpha):
    """(lambda_a, converged, rule_ok) from the polished x and the residual and slope of its last evaluation."""
    la = jnp.exp(x)
    # r, d are taken one Newton step before the returned x (see _newton)
    converged = _resolved(r, d, pt) | (pt == 0.0)
    c, _ = quadrature_indicator(la, k, omk, alpha)
    return la, converged, c <= PANEL_INDICATOR


def _solve_block(pt, k, omk, alpha, max_stretch, table=None, coarse_stage=True):
    """Safeguarded Newton on one block of lanes (arrays of equal shape): from the table start when
    given (20-point rule only), else a 6-point stage first (``coarse_stage``; without it the 20-point
    Newton runs from the small-strain guess: a few more steps, but one loop less to compile, which is
    what a small call pays for most)."""
    x_small, lo, hi = _start(pt, omk, max_stretch)
    x0 = x_small
    if table is not None:
        guess = jnp.where(pt == 0.0, 0.0, _table_start(pt, table, x_small))
        x0 = jnp.where((guess >= lo) & (guess <= hi), guess, 0.5 * (lo + hi))

    def two_stage(x0):
        if not coarse_stage:
            return _newton(pt, k, omk, alpha, x0, lo, hi, (_X, _W), _COARSE_ITER, 1e-13, stop_when_resolved=True)
        coarse = np.polynomial.legendre.leggauss(_COARSE_NODES)
        x1 = _newton(pt, k, omk, alpha, x0, lo, hi, coarse, _COARSE_ITER, 1e-7)[0]
        return _newton(pt, k, omk, alpha, x1, lo, hi, (_X, _W), _FINE_ITER, 1e-13, stop_when_resolved=True)

    if table is None:
        x, r, d = two_stage(x0)
    else:
        # one Newton step from the table start finishes (nearly) every lane: run it without a loop
        x1, _, _, stop, r, d = _newton_update(x0, lo, hi, pt, jnp.arcsinh(pt), k, omk, alpha, _X, _W, 1e-13, True)
        x, r, d = jax.lax.cond(
            jnp.all(stop & (_resolved(r, d, pt) | (pt == 0.0))),
            lambda: (x1, r, d),
            lambda: _newton(pt, k, omk, alpha, x0, lo, hi, (_X, _W), _FINE_ITER, 1e-13, stop_when_resolved=True),
        )
        # lanes the table cannot start (no state on the first rising branch: above the limit point,
        # outside the stretch range) take the two-stage path from the small-strain guess, as without a
        # table (it may find the far, re-stiffening branch of a Fung shell); rare, so only blocks
        # that have such lanes pay for it
        failed = ~(_resolved(r, d, pt) | (pt == 0.0))
        x, r, d = jax.lax.cond(
            jnp.any(failed),
            lambda: tuple(jnp.where(failed, a, b) for a, b in zip(two_stage(x_small), (x, r, d))),
            lambda: (x, r, d),
        )
    return _finish(x, r, d, pt, k, omk, alpha)


def inner_stretch_solve(
    pressure: Array,
    *,
    inner_radius: Array,
    outer_radius: Array,
    C: Array,
    alpha: Array,
    max_inner_stretch: Array | None = None,
) -> tuple[Array, Array]:
    r"""Inverse of :func:`pressure` for jit/vmap use: ``(lambda_a, converged)``.

    Solves p(lambda_a) = pressure (Pa) on the stable (rising) branch by safeguarded Newton in
    x = log lambda_a (closed-form slope; bisection whenever a Newton step leaves the bracket or the
    slope is not positive), searching 0.5 <= lambda_a <= 10. Calls with more than 2048 pressures for
    one shell (scalar radii and alpha) start from a table of the curve (8192 nodes, cubic Hermite in
    asinh(p/C), start error ~1e-13 in log lambda_a), so that one 20-point Newton step finishes a point.
    ``converged`` is False where no stable state exists: pressure above the limit point (the shell bursts), or outside that stretch range,
    and where the one-panel quadrature cannot resolve the pressure integral at the solution to 1e-10
    (very stiff states, large alpha lambda_a^2: :func:`inner_stretch` solves those eagerly);
    ``lambda_a`` is NaN there. ``pressure = 0`` gives exactly 1. Negative pressures deflate
    (lambda_a < 1). No input check raises (use :func:`inner_stretch` for checked calls): a shell or material
    that :func:`inner_stretch` refuses (radii not 0 < A < B, C <= 0, alpha < 0, non-finite) gives NaN and
    ``converged`` False.
    Derivatives (jax.grad) follow the implicit function theorem: d lambda_a/dp = 1/(dp/dlambda_a).

    ``max_inner_stretch`` (optional, per entry) bounds the search: pass the limit stretch
    (``limit_point(...).inner_stretch``) to get the branch reached by inflating from rest. A Fung shell
    with a limit point re-stiffens beyond it (a second rising branch at large stretch); without the
    bound that far branch may be returned for pressures above the limit (where the shell has burst).
    """
    k, omk = _geometry(inner_radius, outer_radius)
    C = jnp.asarray(C, dtype=jnp.float64)
    alpha = jnp.asarray(alpha, dtype=jnp.float64)
    pt = jnp.asarray(pressure, dtype=jnp.float64) / C
    mx = INVERSE_STRETCH_RANGE[1] if max_inner_stretch is None else max_inner_stretch
    mx = jnp.where(jnp.isnan(jnp.asarray(mx, jnp.float64)), INVERSE_STRETCH_RANGE[1], mx)
    la = _inverse(pt, k, omk, alpha, mx)
    A, B = (jnp.asarray(v, dtype=jnp.float64) for v in (inner_radius, outer_radius))
    valid = (A > 0) & (B > A) & jnp.isfinite(B) & (C > 0) & jnp.isfinite(C) & (alpha >= 0) & jnp.isfinite(alpha)
    # a pressure of +-inf is no state either (the search would stop at its bracket's end, 0.5 or 10)
    valid = valid & jnp.isfinite(jnp.asarray(pressure, dtype=jnp.float64))
    la = jnp.where(valid, la, jnp.nan)  # input that eager calls refuse: NaN, not converged
    return la, ~jnp.isnan(la)


@jax.custom_jvp
def _inverse(pt, k, omk, alpha, max_stretch):
    """lambda_a(p/C; k, alpha) on the rising branch up to ``max_stretch``, NaN where there is none."""
    la, conv, rule_ok = _solve_stretch(pt, k, omk, alpha, max_stretch)
    return jnp.where(conv & rule_ok, la, jnp.nan)


@_inverse.defjvp
def _inverse_jvp(primals, tangents):
    """Implicit function theorem: d lambda_a = (d(p/C) - dP/d(k, 1-k, alpha) . d(k, 1-k, alpha)) / dP/dlambda_a.
    (The search bound ``max_stretch`` does not move the solution: no tangent.)"""
    pt, k, omk, alpha, mx = primals
    dpt, dk, domk, dalpha, _ = tangents
    la = _inverse(pt, k, omk, alpha, mx)
    f = lambda k_, o_, a_: _p_over_C_quad(*jnp.broadcast_arrays(la, k_, o_, a_))
    _, dP = jax.jvp(f, (k, omk, alpha), (dk, domk, dalpha))
    return la, (dpt - dP) / _dp_over_C(la, k, alpha)


def inner_stretch(pressure: Array, *, inner_radius: Array, outer_radius: Array, C: Array, alpha: Array) -> Array:
    r"""Inner stretch lambda_a = a/A at internal pressure ``pressure`` (Pa): the inverse of :func:`pressure`.

    The stable (rising) branch of p(lambda_a) is returned, found by safeguarded Newton (see
    :func:`inner_stretch_solve`). ``pressure = 0`` -> 1 exactly; negative pressure deflates the
    shell (lambda_a < 1, down to 0.5).

    Eager calls raise ``ValueError`` where no stable state exists: the pressure exceeds the limit
    point (the message gives the limit pressure), or the stretch would leave 0.5 <= lambda_a <= 10.
    Inside ``jit``/``vmap`` those entries are NaN (NaN convention; use :func:`inner_stretch_solve` for the
    explicit ``converged`` flag), while bad inputs (a non-finite pressure, radii, C, alpha) raise at run time
    (``equinox.error_if``, the eager message without the value).
    """
    fast = _one_point(pressure, (inner_radius, outer_radius, C, alpha), stretch=False)
    if fast is not None:
        la1, conv1, ok1 = (_host(v) for v in small_call(_inverse_core, one_point=True)(fast[0], fast[1]))
        if is_traced(la1):  # inside a user's jit/vmap: NaN where there is no stable state
            return jnp.where(conv1 & ok1, la1, jnp.nan).reshape(fast[2])
        if conv1 and ok1:
            return la1.reshape(fast[2])
    p = _concrete(validate_finite("pressure", pressure, "Pa"), pressure)
    A, B, C_, al = _validate(inner_radius, outer_radius, C, alpha)
    if is_traced(pressure, inner_radius, outer_radius, C, alpha):  # differentiable path (implicit function)
        la, _ = inner_stretch_solve(p, inner_radius=A, outer_radius=B, C=C_, alpha=al)
        return traced_checks(la, traced_finite("pressure", p, "Pa") + _traced_shell(A, B, C_, al))
    la, conv, rule_ok = _call(_inverse_core, p, (A, B, C_, al))
    if is_traced(la):  # concrete inputs inside a user's jit/vmap
        return jnp.where(conv & rule_ok, la, jnp.nan)
    conv = np.asarray(conv)
    rule_ok = np.asarray(rule_ok)
    if conv.all() and rule_ok.all():
        return la
    la, conv = np.array(la), conv.copy()
    fix = conv & ~rule_ok
    if np.any(fix):  # stiff states: polish with the error-controlled quadrature (Newton in log lambda_a)
        k, omk = _geometry(A, B)
        pt = np.asarray(p, dtype=float) / np.asarray(C_, dtype=float)
        b = np.broadcast_arrays(*(np.asarray(v, dtype=float) for v in (pt, k, omk, al)))
        la[fix], conv[fix] = _polish(la[fix], *(v[fix] for v in b))
    if not bool(np.all(conv)):
        _raise_no_solution(pressure, conv, inner_radius, outer_radius, C, alpha)
    return la


@jax.jit
def _inverse_core(p, params):
    """(lambda_a, converged, rule_ok) of the rising-branch inverse (no gradient: see ``_inverse``)."""
    A, B, C, alpha = params
    k, omk = _geometry(A, B)
    pt = jnp.asarray(p, dtype=jnp.float64) / jnp.asarray(C, dtype=jnp.float64)
    return _solve_stretch(pt, k, omk, jnp.asarray(alpha, dtype=jnp.float64))


def _polish(la, pt, k, omk, alpha, max_iter: int = 40):
    """Newton in x = log lambda_a on p/C(lambda_a) = pt with the error-controlled quadrature and the
    closed-form slope (eager, 1-D arrays). Returns (lambda_a, converged: |residual| <= 1e-11 |pt|)."""
    x = np.log(la)
    ok = np.zeros(la.shape, dtype=bool)
    for _ in range(max_iter):
        lam = np.exp(x)
        r = np.asarray(_p_over_C(lam, k, omk, alpha)) - pt
        ok = np.abs(r) <= 1e-11 * np.abs(pt)
        if np.all(ok):
            break
        d = lam * np.asarray(_dp_over_C(jnp.asarray(lam), jnp.asarray(k), jnp.asarray(alpha)))
        x = np.where(ok, x, x - r / np.where(d > 0, d, np.inf))
    return np.exp(x), ok


def _pressure_at(stretch, A, B, C, alpha) -> str:
    """p(stretch) in Pa as text for messages ("beyond 1e308" where it overflows)."""
    try:
        k, omk = _geometry(A, B)
        return f"{float(C * _p_over_C(stretch, k, omk, alpha)):g} Pa"
    except ValueError:
        return "a pressure beyond the float64 range (> 1e308 Pa)"


def _raise_no_solution(pressure, conv, inner_radius, outer_radius, C, alpha) -> None:
    p, A, B, C_, al, cv = np.broadcast_arrays(
        np.asarray(pressure, float),
        np.asarray(inner_radius, float),
        np.asarray(outer_radius, float),
        np.asarray(C, float),
        np.asarray(alpha, float),
        np.asarray(conv),
    )
    i = np.unravel_index(np.argmin(cv), cv.shape)
    pi, Ai, Bi, Ci, ai = (float(v[i]) for v in (p, A, B, C_, al))
    geo = f"(inner radius {Ai:g} m, outer radius {Bi:g} m, C = {Ci:g} Pa, alpha = {ai:g})"
    if pi < 0:
        pmin = _pressure_at(INVERSE_STRETCH_RANGE[0], Ai, Bi, Ci, ai)
        raise ValueError(
            f"pressure {pi:g} Pa deflates the shell {geo} below the smallest inner stretch this model "
            f"covers ({INVERSE_STRETCH_RANGE[0]:g}, reached at {pmin})"
        )
    lim = limit_point(inner_radius=Ai, outer_radius=Bi, C=Ci, alpha=ai)
    if lim is not None and pi > float(lim.pressure):
        raise ValueError(
            f"pressure {pi:g} Pa exceeds the limit pressure {float(lim.pressure):g} Pa of this shell {geo} "
            f"(reached at inner stretch {float(lim.inner_stretch):.6g}): above it there is no "
            "equilibrium and the shell inflates without bound (bursts)"
        )
    pmax = _pressure_at(INVERSE_STRETCH_RANGE[1], Ai, Bi, Ci, ai)
    raise ValueError(
        f"pressure {pi:g} Pa would inflate the shell {geo} beyond the largest inner stretch this model "
        f"covers ({INVERSE_STRETCH_RANGE[1]:g}, reached at {pmax})"
    )


# ---------------------------------------------------------------------------------------------
# Through-wall profiles
# ---------------------------------------------------------------------------------------------


class Profiles(NamedTuple):
    """Through-wall fields of the inflated shell (last axis: ``n`` points from inner to outer wall).

    R            reference radius (m)
    r            deformed radius (m)
    stretch      hoop stretch r/R (radial stretch is stretch^-2)
    sigma_r      radial Cauchy stress (Pa), = -p at the inner wall and 0 at the outer wall
    sigma_theta  hoop Cauchy stress (Pa)
    von_mises    |sigma_theta - sigma_r| (Pa)
    """

    R: Array
    r: Array
    stretch: Array
    sigma_r: Array
    sigma_theta: Array
    von_mises: Array


def profiles(
    inner_stretch: Array,
    *,
    inner_radius: Array,
    outer_radius: Array,
    C: Array,
    alpha: Array,
    n: int = 50,
) -> Profiles:
    r"""Radial profiles through the wall at inner stretch lambda_a (all SI).

    Point at reference radius R (A <= R <= B, ``n`` equally spaced): hoop stretch l with
    l^3 = 1 + (lambda_a^3 - 1)(A/R)^3, r = l R;
    sigma_r(R) = -int_{lambda_b}^{l} g(s) ds (the pressure integral of a shell with inner radius R),
    sigma_theta = sigma_r + 2 W'(I1)(l^2 - l^-4), I1 = 2 l^2 + l^-4; von Mises |sigma_theta - sigma_r|.
    Inputs broadcast; the profile axis is appended last. Eager calls raise ``ValueError`` for bad inputs; under
    jit/vmap/grad they raise at run time (``equinox.error_if``) and stresses the one-panel rule cannot resolve
    (large alpha l^2) are NaN.
    """
    fast = _one_point(inner_stretch, (inner_radius, outer_radius, C, alpha)) if type(n) is int and n >= 2 else None
    if fast is not None:
        fields, redo1 = small_call(_profiles_core, (2,), one_point=True)(fast[0], fast[1], n)
        if is_traced(fields):  # inside a user's jit/vmap: the one-panel fields
            return Profiles(*fields.reshape((6,) + fast[2] + (n,)))
        if not np.asarray(redo1).any():  # one transfer of the (6, n) block, then six views
            return Profiles(*np.asarray(fields).reshape((6,) + fast[2] + (n,)))
    la = _concrete(_check_stretch("inner_stretch", inner_stretch), inner_stretch)
    A, B, C_, al = _validate(inner_radius, outer_radius, C, alpha)
    n = validate_int("n (number of points through the wall)", n, minimum=2)
    fields, redo = _call(_profiles_core, la, (A, B, C_, al), n)
    out = Profiles(*(fields[..., i, :] for i in range(6)))
    if is_traced(redo):
        return Profiles(*traced_checks(tuple(out), _traced_stretch("inner_stretch", la) + _traced_shell(A, B, C_, al)))
    if not np.asarray(redo).any():
        return out
    # stiff states (large alpha l^2): sigma_r by the error-controlled composite rule (eager, rare)
    R, r, lam, _, _, _ = out
    A_, B_ = (jnp.asarray(v, dtype=jnp.float64)[..., None] for v in (A, B))
    kR, omkR, alpha_b, C_b = _wall_geometry(A_, B_, R, al, C_)
    lam_b, kR_b, omkR_b, alpha_b, C_b = jnp.broadcast_arrays(lam, kR, omkR, alpha_b, C_b)
    sigma_r = -C_b * _p_over_C(lam_b, kR_b, omkR_b, alpha_b, "hoop stretch in the wall")
    diff = _hoop_minus_radial(lam_b, C_b, alpha_b)
    return Profiles(*(np.asarray(v) for v in (R, r, lam, sigma_r, sigma_r + diff, jnp.abs(diff))))


def _wall_geometry(A, B, R, alpha, C):
    """(A/R)^3-type factors of the shell inside radius R: k_R = (R/B)^3, 1 - k_R; alpha, C with a profile axis."""
    kR, omkR = _geometry(R, B)
    return kR, omkR, jnp.asarray(alpha, dtype=jnp.float64)[..., None], jnp.asarray(C, dtype=jnp.float64)[..., None]


def _hoop_minus_radial(lam, C, alpha):
    """sigma_theta - sigma_r = 2 W'(I1)(l^2 - l^-4) in Pa."""
    I1 = 2.0 * lam**2 + lam**-4
    return 2.0 * dW_dI1(I1, C, alpha) * (lam**2 - lam**-4)


@functools.partial(jax.jit, static_argnums=(2,))
def _profiles_core(inner_stretch, params, n):
    """The six ``Profiles`` fields by the one-panel rule, stacked on axis -2 (shape (..., 6, n): one
    output buffer), and ``redo``: True where an eager call must take the composite rule."""
    inner_radius, outer_radius, C, alpha = params
    A = jnp.asarray(inner_radius, dtype=jnp.float64)[..., None]
    B = jnp.asarray(outer_radius, dtype=jnp.float64)[..., None]
    la = jnp.asarray(inner_stretch, dtype=jnp.float64)[..., None]
    t = jnp.linspace(0.0, 1.0, int(n))
    R = A + (B - A) * t
    e = jnp.expm1(3.0 * jnp.log(la))
    q, one_minus_q = _geometry(A, R)  # (A/R)^3 and 1 - (A/R)^3
    # l^3 = 1 + e q near lambda_a = 1 (log1p); in strong deflation 1 - q + q lambda_a^3 summed directly (1 + e q -> 0
    # there loses every digit: l was 0 at lambda_a = 1e-10)
    deflated = e < -0.5
    direct = jnp.log(jnp.where(deflated, one_minus_q + q * la**3, 1.0)) / 3.0
    lam = jnp.exp(jnp.where(deflated, direct, jnp.log1p(jnp.where(deflated, 0.0, e * q)) / 3.0))
    kR, omkR, alpha, C = _wall_geometry(A, B, R, alpha, C)
    lam_b, kR_b, omkR_b, alpha_b, C_b, R_b = jnp.broadcast_arrays(lam, kR, omkR, alpha, C, R)
    pc, redo = _p_over_C_flagged(lam_b, kR_b, omkR_b, alpha_b)
    sigma_r = -C_b * pc
    diff = _hoop_minus_radial(lam_b, C_b, alpha_b)
    fields = (R_b, lam_b * R_b, lam_b, sigma_r, sigma_r + diff, jnp.abs(diff))
    return jnp.stack(fields, axis=-2), redo
