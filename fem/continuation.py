r"""Path following: adaptive load control and Riks arc-length (through limit points).

``load_control(solve, loads, x0, *, lam0=0.0, monitor=None, max_cuts=12, tangent=None)``
    ``solve(lam, x_guess) -> NewtonResult`` (raises ``NewtonError``). Reaches every requested
    load; a failed step is halved (up to ``max_cuts`` times), after one retry from the last converged state
    where the predicted guess is inadmissible (Newton could not start from it). The predictor, first that applies: with a
    ``monitor`` (a scalar response m(x), e.g. the inner stretch) and three converged states, the curve through
    them quadratic in m (lam(m) solved for the target load, x(m) interpolated: smooth where x(lam) bends
    sharply, e.g. a shell that inflates fast before the Fung law stiffens it); Euler's, x_c + (dx/dlam) dlam,
    where ``tangent(lam, x) -> dx/dlam or None`` is given and has a slope at the converged state, for a step
    no longer than the last converged one; else the secant of the last two converged states (none of the
    first two after a cut; ``scale``/``unit`` only format messages). Returns a list
    of ``LoadStep`` = ``fem.stepping.Step(load, x, newton_iterations, wall_time)`` (``.solution``: the
    ``NewtonResult`` of release 0.1), one per requested load. If it fails where the
    load-response curve flattens (monitor slope below 2 % of the initial one or falling), raises
    ``LimitPointError`` naming the last converged load.

``arc_length(fun, x0, lam0, ds, *, stop, ...)``
    Riks: unknowns (x, lam), ``fun(x, lam) -> (r, K, r_lam)`` with r_lam = dr/dlam; hyperplane
    constraint t . (x - x_pred, lam - lam_pred) = 0 in the metric |x|^2 / c^2 + lam^2 (c from the
    first tangent), bordered sparse system solved directly (regular at limit points). Step length
    adapted to the Newton iteration count; ``stop(x, lam)`` ends the trace. Returns a list of
    ``ArcStep`` = ``fem.stepping.Step(load, x, newton_iterations, wall_time)``.
"""

from __future__ import annotations

import logging
import time
from collections.abc import Callable, Sequence

import numpy as np
import scipy.sparse as sp

from tissuemech.fem.newton import NewtonError, sparse_solve
from tissuemech.fem.stepping import Step

__all__ = ["LimitPointError", "LoadStep", "ArcStep", "load_control", "arc_length", "monitor_quadratic"]

log = logging.getLogger(__name__)


# one converged-step type for every path (fem.stepping): the names of release 0.1 are aliases of it
LoadStep = Step  # Step[np.ndarray]: time = the requested load, state = x, newton_iterations summed over sub-steps
ArcStep = Step  # Step[np.ndarray]: time = the load lam on the path, state = x


class LimitPointError(NewtonError):
    """Load control cannot pass a maximum of the load (limit point): use method='arclength'.

    ``load`` is the load that failed, ``last_converged`` the last converged load (both scaled by ``scale``).
    """

    last_converged: float = float("nan")


def monitor_quadratic(hist: list, lam_t: float) -> np.ndarray | None:
    """Predictor through the last three converged states (lam_i, m_i, x_i), m the monitor: the load as a quadratic
    in m, lam(m), solved for lam(m*) = lam_t (the root next to the secant's m), then x(m*) by Lagrange
    interpolation in m. Near an inflection of the load-response curve (a blastula that inflates fast before the
    Fung law stiffens it) x bends less in m than in lam: past the bend errors 0.025-0.13 of the step against
    0.076-0.16 for Euler's exact slope (75 um shell, 8x16, 600-1000 Pa;
    measured in issue 14). None when there is no such root nearby or the monitor does not increase."""
    if len(hist) < 3:
        return None
    (l0, m0, x0), (l1, m1, x1), (l2, m2, x2) = hist
    if not (m0 < m1 < m2 and l0 < l1 < l2 < lam_t) or not all(np.isfinite((m0, m1, m2))):
        return None
    # lam(m) = l2 + b d + a d^2, d = m - m2 (Newton's divided differences)
    d0, d1 = m0 - m2, m1 - m2
    s1, s0 = (l1 - l2) / d1, (l0 - l2) / d0
    a = (s0 - s1) / (d0 - d1)
    b = s1 - a * d1  # slope at m2
    lin = (lam_t - l2) / ((l2 - l1) / (m2 - m1))  # the secant's step in m
    if b <= 0 or lin <= 0:
        return None
    if abs(a) * lin < 1e-12 * b:
        d = (lam_t - l2) / b
    else:
        disc = b * b + 4.0 * a * (lam_t - l2)
        if disc < 0:  # lam(m) turns before lam_t: a limit point ahead
            return None
        d = 2.0 * (lam_t - l2) / (b + np.sqrt(disc))  # the root next to lam_t - l2 = b d (no cancellation)
    if not 0.0 < d <= 4.0 * lin:
        return None
    w0 = (d - d1) * d / ((d0 - d1) * d0)
    w1 = (d - d0) * d / ((d1 - d0) * d1)
    w2 = (d - d0) * (d - d1) / (d0 * d1)
    return w0 * x0 + w1 * x1 + w2 * x2


def _solve_from(solve: Callable, lam: float, guess: np.ndarray, x_c: np.ndarray):
    """(result, None) of ``solve(lam, guess)``, or (None, the NewtonError). A predicted guess that Newton could not
    even start from (inadmissible: an extrapolation that turns an element inside out, residual history empty) is
    replaced by the last converged state ``x_c`` for the same step before the step is cut: a fast-inflating shell's
    secant would otherwise fail every step and exhaust the cuts (``inflate(pressures=[1e6])`` did, at 488 Pa)."""
    try:
        return solve(lam, guess), None
    except NewtonError as e:
        if e.residuals or guess is x_c:
            return None, e
    try:
        return solve(lam, x_c), None
    except NewtonError as e:
        return None, e


def load_control(
    solve: Callable,
    loads: Sequence[float] | np.ndarray,
    x0: np.ndarray,
    *,
    lam0: float = 0.0,
    monitor: Callable | None = None,
    max_cuts: int = 12,
    unit: str = "",
    scale: float = 1.0,
    tangent: Callable | None = None,
) -> list[Step[np.ndarray]]:
    """Reach every load of ``loads`` (scaled, increasing) from (lam0, x0) by Newton solves ``solve(lam, guess)``,
    halving a failed step; see the module docstring. ``tangent(lam, x)``: dx/dlam at a converged state, or None
    (then the secant predicts). Returns one ``LoadStep`` per requested load.
    Raises ``LimitPointError`` where the path flattens, ``NewtonError`` after ``max_cuts`` cuts otherwise."""
    out: list[Step[np.ndarray]] = []
    x_prev, lam_prev = np.array(x0, float), float(lam0)
    x_old: np.ndarray | None = None
    lam_old = 0.0
    slope0 = None
    hist: list = []  # the last three converged (load, monitor, x): the monitor-quadratic predictor
    for target in loads:
        lam_c, x_c = lam_prev, x_prev
        t0 = time.perf_counter()
        iters, dlam = 0, float(target) - lam_prev
        cuts = 0
        while lam_c < target - 1e-14 * max(1.0, abs(target)):
            lam_t = min(target, lam_c + dlam)
            # Euler (the slope dx/dlam at the converged state) for a step no longer than the last converged one and
            # none after a cut (where its guesses, admissible but far, cost a whole failed Newton run: the secant's
            # overshoot is refused at once)
            euler = (
                tangent is not None
                and cuts == 0
                and x_old is not None
                and 0 < lam_t - lam_c <= (lam_c - lam_old) * (1 + 1e-9)
            )
            curve = monitor_quadratic(hist, lam_t) if cuts == 0 else None
            t_c = tangent(lam_c, x_c) if curve is None and euler and tangent is not None else None
            if curve is not None:
                guess = curve
            elif t_c is not None:
                guess = x_c + t_c * (lam_t - lam_c)
            elif x_old is not None and lam_c != lam_old:
                guess = x_c + (x_c - x_old) * (lam_t - lam_c) / (lam_c - lam_old)
            else:
                guess = x_c
            res, err = _solve_from(solve, lam_t, guess, x_c)
            if res is None:
                cuts += 1
                if cuts > max_cuts:
                    s = None
                    if monitor is not None and x_old is not None and lam_c != lam_old:
                        dm = monitor(x_c) - monitor(x_old)
                        s = (lam_c - lam_old) / dm if dm != 0 else np.inf
                    if s is not None and slope0 is not None and s < 0.02 * slope0:
                        lpe = LimitPointError(
                            f"load control reached a limit point: no equilibrium just above "
                            f"{lam_c * scale:.6g}{unit}, the curve is flat there",
                            load=lam_t * scale,
                            residuals=err.residuals,
                            unit=unit,
                            hint=f"the last converged load {lam_c * scale:.6g}{unit} is (close to) the maximum; "
                            "use method='arclength' to pass it",
                        )
                        lpe.last_converged = lam_c * scale
                        raise lpe from None
                    raise NewtonError(
                        f"load step failed after {max_cuts} cuts",
                        load=lam_t * scale,
                        residuals=err.residuals,
                        hint=err.hint,
                        unit=unit,
                    ) from None
                dlam *= 0.5
                log.debug(
                    "load step to %.6g%s failed (%s); cut back to %.3g%s (cut %d)",
                    lam_t * scale,
                    unit,
                    err.args[0],
                    dlam * scale,
                    unit,
                    cuts,
                )
                continue
            x_old, lam_old = x_c, lam_c
            x_c, lam_c = res.x, lam_t
            if monitor is not None:
                m_old = hist[-1][1] if hist and hist[-1][2] is x_old else monitor(x_old)
                hist = (hist + [(lam_c, float(monitor(x_c)), x_c)])[-3:]
            iters += res.iterations
            if monitor is not None and lam_c != lam_old:
                dm = hist[-1][1] - m_old
                s = (lam_c - lam_old) / dm if dm != 0 else np.inf
                slope0 = s if slope0 is None else slope0
            if res.iterations <= 4:
                dlam *= 1.5
        if not out and target == lam_prev:  # a zero first load: solve it once
            res = solve(target, x_c)
            x_c, iters = res.x, res.iterations
        out.append(Step(float(target), x_c, iters, time.perf_counter() - t0))
        x_prev, lam_prev = x_c, lam_c
    return out


def arc_length(
    fun: Callable,
    x0: np.ndarray,
    lam0: float,
    ds: float,
    *,
    stop: Callable,
    admissible: Callable | None = None,
    max_steps: int = 500,
    rtol: float = 1e-9,
    ref_norm: float = 1.0,
    atol: float = 0.0,
    max_iter: int = 20,
    target_iter: int = 5,
    ds_max: float | None = None,
    ds_min: float | None = None,
) -> list[Step[np.ndarray]]:
    """Riks arc-length; returns a list of ``ArcStep(load, x, newton_iterations, wall_time)`` from the start (excluded)."""
    x, lam = np.array(x0, float), float(lam0)
    r, K, rl = fun(x, lam)
    tx = sparse_solve(K, -rl)
    c = max(float(np.linalg.norm(tx)), 1e-12)
    nrm = lambda a, b: np.sqrt(a @ a / c**2 + b * b)
    n0 = nrm(tx, 1.0)
    tx, tl = tx / n0, 1.0 / n0
    ds_max = 8 * ds if ds_max is None else ds_max
    ds_min = ds * 1e-4 if ds_min is None else ds_min
    out: list[Step[np.ndarray]] = []
    for _step in range(max_steps):
        t0 = time.perf_counter()
        while True:
            xp, lp = x + ds * tx, lam + ds * tl
            xi, li = xp.copy(), lp
            ok, hist = False, []
            for it in range(1, max_iter + 1):
                if admissible is not None and admissible(xi) is not None:
                    break
                r, K, rl = fun(xi, li)
                g = (tx @ (xi - xp)) / c**2 + tl * (li - lp)
                rn = float(np.linalg.norm(r))
                hist.append(rn)
                if not np.isfinite(rn):
                    break
                if rn <= rtol * ref_norm * max(1.0, abs(li)) + atol and abs(g) < 1e-12 and it > 1:
                    ok = True
                    break
                Ka = sp.bmat([[K, rl[:, None]], [(tx / c**2)[None, :], np.array([[tl]])]], format="csc")
                try:
                    d = sparse_solve(Ka, -np.concatenate([r, [g]]))
                except np.linalg.LinAlgError:
                    break
                xi, li = xi + d[:-1], li + d[-1]
            if ok:
                break
            ds *= 0.5
            log.debug("arc-length step from load %.6g failed; step length halved to %.3g", lam, ds)
            if ds < ds_min:
                raise NewtonError(
                    "arc-length step failed at the minimum step length",
                    load=lam,
                    residuals=hist,
                    hint="refine the mesh or start with a smaller step",
                )
        dxs, dls = xi - x, li - lam
        n = nrm(dxs, dls)
        tx, tl = dxs / n, dls / n
        x, lam = xi, li
        out.append(Step(lam, x, it, time.perf_counter() - t0))
        ds = min(ds_max, ds * np.clip(np.sqrt(target_iter / it), 0.5, 2.0))
        if stop(x, lam):
            break
    return out
