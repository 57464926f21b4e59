r"""A stability map: each method pushed until it fails, with the boundary measured.

Every function returns a ``pandas.DataFrame`` (one row per attempt) that ``compare.plots.charts``
charts and ``compare.report`` writes as CSV (the exact references live in ``compare.reference``):

``limit_point_map``      neo-Hookean (alpha = 1e-5) blastula, B in {52, 60, 75} um: the largest
                         pressure that FE load control reaches (it stops at the limit point), the
                         maximum traced by FE arc-length (which passes it), and the exact limit
                         ``reduced.blastula.limit_point``.
``kappa_map``            kappa/C from 1e2 to 1e7: displacement-only P2 ("displacement") against mixed
                         Q2/P1 u-p ("mixed"): inner-stretch error against the incompressible exact
                         shell (alpha = 0.2, B = 75 um), or the load where Newton failed.
``compression_map``      spheroid, static elastic: the largest total approach (fraction of the
                         diameter) that converges (needs ``fem.spheroid``).
``viscous_step_map``     the lumped Maxwell branch of physics.md,
                             F(t) = F_eq(t) + q(t),  dq/dt = -q/tau + beta dF_eq/dt,
                         F_eq = (delta(t)/delta_0)^(3/2) (the Hertz shape; ramp t_r = 0.2 s, hold
                         to 1500 s), advanced with a uniform step h by three update formulas:
                           exact-linear:   q+ = e^-x q + beta (1 - e^-x)/x dF       (x = h/tau)
                           backward Euler: q+ = (q + beta dF) / (1 + x)
                           forward Euler:  q+ = (1 - x) q + beta dF
                         error = max_n |F_n - F(t_n)| / max F against the exact convolution
                         q(t) = beta int_0^t e^{-(t-s)/tau} F_eq'(s) ds; the largest h with error
                         <= 1e-3 is the boundary.
``stiff_solver_map``     the same ODE in diffrax with tau << t_r: explicit Tsit5 / Dopri5 against
                         implicit Kvaerno5 (PID control, rtol = atol = 1e-8, max_steps 20 000):
                         accepted and rejected steps, failures, error against the exact solution.
"""

from __future__ import annotations

import time
import warnings
from collections.abc import Callable, Sequence
from typing import Any

import numpy as np
import pandas as pd

from tissuemech.compare import cases, runcache
from tissuemech.compare.reference import exact_lumped_force, lumped_equilibrium, shell_inner_stretch

UM = cases.UM
A, C = cases.BLASTULA_INNER_RADIUS, cases.BLASTULA_C


def _positive_list(name: str, values: Sequence[float] | np.ndarray, unit: str = "") -> np.ndarray:
    v = np.atleast_1d(np.asarray(values, dtype=float))
    if v.size == 0 or not np.all(np.isfinite(v)) or np.any(v <= 0):
        raise ValueError(f"{name} must be a non-empty list of positive numbers{unit}; got {list(np.ravel(values))!r}")
    return v


__all__ = [
    "limit_point_map",
    "kappa_map",
    "kappa_jobs",
    "compression_map",
    "compression_jobs",
    "viscous_step_map",
    "stiff_solver_map",
    "exact_lumped_force",
    "TOLERANCE",
]

TOLERANCE = 1e-3  # the accuracy a viscoelastic step must keep

# the rows are built with identifier keys; the tables carry ``name [unit]`` headers
_COLUMNS = {
    "B_um": "B [um]",
    "p_reached_Pa": "p reached [Pa]",
    "p_max_exact_Pa": "p max exact [Pa]",
    "wall_s": "wall_time [s]",
    "force_N": "force [N]",
    "approach_um": "approach [um]",
    "step_s": "step [s]",
    "largest_ok_step_s": "largest ok step [s]",
    "tau_s": "tau [s]",
}


def _table(rows: list[dict]) -> pd.DataFrame:
    """The rows as a DataFrame with ``name [unit]`` column headers."""
    return pd.DataFrame(rows).rename(columns=_COLUMNS)


# ---------------------------------------------------------------------------------------------
# Blastula: limit point
# ---------------------------------------------------------------------------------------------


def limit_point_map(
    outer_um: Sequence[float] = (52.0, 60.0, 75.0),
    mesh="default",
    n_load_steps: int = 60,
    sweep_range: tuple[float, float] = (1.0, 1000.0),
) -> tuple[pd.DataFrame, dict]:
    """Load control vs arc-length vs reduced at the neo-Hookean limit point (alpha = 1e-5).

    Load control runs the same geometric sweep (``n_load_steps`` pressures over ``sweep_range``, Pa)
    for every B, with adaptive cut-back; it is not told the exact limit. Its p_reached is the last
    converged load and its stretch_reached the FE inner stretch there (both from the FE alone); the
    exact columns are only compared with afterwards.

    Returns (table, arc-length results keyed by B in um). Table columns: ``B [um]``, method,
    ``p reached [Pa]`` (largest converged pressure; for arc-length the maximum along the trace),
    stretch_reached (FE inner stretch at p_reached for load control; the last traced stretch for
    arc-length; NaN for the closed form, which has no "reached"), ``p max exact [Pa]``,
    stretch_limit_exact, rel_err_p (p_reached / p_max - 1), passed_limit (bool), ``wall_time [s]``, note.
    """
    from tissuemech.fem.blastula import LimitPointError, inflate
    from tissuemech.reduced import blastula as bl

    _positive_list("outer_um (outer radii)", outer_um, " in um")
    if any(b <= A / UM for b in outer_um):
        raise ValueError(f"outer radii must exceed the inner radius {A / UM:g} um; got {list(outer_um)}")
    alpha = cases.NEO_HOOKEAN_ALPHA
    rows, traces = [], {}
    for b in outer_um:
        B = b * UM
        geo: dict[str, Any] = dict(inner_radius=A, outer_radius=B, C=C, alpha=alpha)
        bl.limit_point(**geo)  # warm-up (JIT compile)
        t0 = time.perf_counter()
        lim = bl.limit_point(**geo)
        assert lim is not None, "the exact shell has a limit point for every alpha this study takes"
        wall = time.perf_counter() - t0
        pmax, lstar = float(lim.pressure), float(lim.inner_stretch)
        base = dict(B_um=b, p_max_exact_Pa=pmax, stretch_limit_exact=lstar)
        note = "closed-form slope root; inner_stretch(p > p_max) raises ValueError (no solution)"
        try:
            bl.inner_stretch(1.01 * pmax, **geo)
        except ValueError:
            pass
        else:  # pragma: no cover - would be a bug in reduced.blastula
            note = "inner_stretch above p_max did NOT raise"
        rows.append(
            dict(
                base,
                method="reduced (exact)",
                p_reached_Pa=pmax,
                stretch_reached=np.nan,
                rel_err_p=0.0,
                passed_limit=True,
                wall_s=wall,
                note=note,
            )
        )

        # load control on a sweep fixed in advance (the same for every B, not built from the exact p_max);
        # p_reached and stretch_reached are the FE's own: the last converged load step, re-run to read its stretch
        # FE runs through the run cache (compare.runcache): a later report reuses them and the times they took
        sweep = np.geomspace(sweep_range[0], sweep_range[1], n_load_steps)
        t0 = time.perf_counter()
        try:
            run = runcache.call(inflate, dict(**geo, pressures=sweep, mesh=mesh))
            r, wall = run.result, run.wall
            p_last, note = float(r.pressure[-1]), f"reached the end of the sweep ({sweep_range[1]:g} Pa)"
            la_last = float(r.inner_stretch[-1])
        except LimitPointError as e:
            failed_wall = time.perf_counter() - t0
            p_last = float(e.last_converged)
            note = "LimitPointError: " + str(e).split(" (load level")[0][:160]
            run = runcache.call(
                inflate, dict(**geo, pressures=np.r_[sweep[sweep < p_last * (1 - 1e-9)], p_last], mesh=mesh)
            )
            r, wall = run.result, failed_wall + run.wall
            la_last = float(r.inner_stretch[-1])
        rows.append(
            dict(
                base,
                method="FE load control",
                p_reached_Pa=p_last,
                stretch_reached=la_last,
                rel_err_p=p_last / pmax - 1,
                passed_limit=p_last > pmax,
                wall_s=wall,
                note=note,
            )
        )

        run = runcache.call(
            inflate, dict(**geo, pressures=None, method="arclength", max_inner_stretch=1.3 * lstar, mesh=mesh)
        )
        r, wall = run.result, run.wall
        traces[b] = r
        p_top, l_top = _parabolic_max(r.inner_stretch, r.pressure)
        rows.append(
            dict(
                base,
                method="FE arc-length",
                p_reached_Pa=p_top,
                stretch_reached=float(r.inner_stretch[-1]),
                rel_err_p=p_top / pmax - 1,
                passed_limit=bool(r.inner_stretch[-1] > lstar),
                wall_s=wall,
                note=f"{len(r.pressure)} steps; maximum (parabola through the 3 steps around it) "
                f"at inner stretch {l_top:.4f}",
            )
        )
    return _table(rows), traces


def _parabolic_max(x: np.ndarray, y: np.ndarray) -> tuple[float, float]:
    """(y_max, x at y_max) of the parabola through the largest sample of y and its two neighbours."""
    i = int(np.argmax(y))
    if i == 0 or i == len(y) - 1:
        return float(y[i]), float(x[i])
    c = np.polyfit(x[i - 1 : i + 2], y[i - 1 : i + 2], 2)
    if c[0] >= 0:
        return float(y[i]), float(x[i])
    xm = -c[1] / (2 * c[0])
    return float(np.polyval(c, xm)), float(xm)


# ---------------------------------------------------------------------------------------------
# Blastula: locking versus kappa / C
# ---------------------------------------------------------------------------------------------


KAPPA_SHELL = (75e-6, 0.2)  # (B in m, alpha) of the kappa map


def kappa_jobs(
    ratios: Sequence[float] = (1e2, 1e3, 1e4, 1e5, 1e6, 1e7), mesh=(4, 8), pressures: Sequence[float] = (250.0, 500.0)
) -> list[tuple[Callable, dict, int]]:
    """The FE runs :func:`kappa_map` asks for (same arguments), mixed then displacement-only, each over ``ratios``,
    as ``(function, keywords, repeats)`` (what ``compare.runcache.prefetch`` can start ahead)."""
    from tissuemech.fem.blastula import inflate

    B, alpha = KAPPA_SHELL
    kw = dict(inner_radius=A, outer_radius=B, C=C, alpha=alpha, pressures=list(pressures), mesh=mesh)
    return [(inflate, dict(kw, kappa=k * C, formulation=form), 1) for form in ("mixed", "displacement") for k in ratios]


def kappa_map(
    ratios: Sequence[float] = (1e2, 1e3, 1e4, 1e5, 1e6, 1e7), mesh=(4, 8), pressures: Sequence[float] = (250.0, 500.0)
) -> pd.DataFrame:
    """Inner-stretch error vs kappa/C for displacement-only and mixed u-p elements (alpha = 0.2, B = 75 um).

    error = max_p |lambda_a,FE / lambda_a,exact - 1| against the incompressible exact shell (so it
    contains the physical compressibility error ~ C/kappa as well as locking). A Newton failure is
    recorded (error NaN, failed True, the message). Columns: formulation, kappa_over_C, error, failed,
    ``wall_time [s]``, note.
    """
    from tissuemech.fem.blastula import LockingWarning
    from tissuemech.fem.newton import NewtonError

    _positive_list("ratios (kappa/C)", ratios)
    _positive_list("pressures", pressures, " in Pa")
    B, alpha = KAPPA_SHELL
    ex = np.array([shell_inner_stretch(p, outer_radius=B, alpha=alpha) for p in pressures])
    rows = []
    jobs = iter(kappa_jobs(ratios, mesh, pressures))
    for form in ("mixed", "displacement"):
        for k in ratios:
            t0 = time.perf_counter()
            err, failed, note = np.nan, False, ""
            try:
                with np.errstate(all="ignore"), warnings.catch_warnings():
                    warnings.simplefilter("ignore", LockingWarning)  # the study measures the locking it warns of
                    run = runcache.call(*next(jobs)[:2])  # reused between reports
                err = float(np.max(np.abs(run.result.inner_stretch / ex - 1)))
                wall = run.wall
            except NewtonError as e:
                failed, note = True, str(e)[:200]
                wall = time.perf_counter() - t0
            rows.append(dict(formulation=form, kappa_over_C=k, error=err, failed=failed, wall_s=wall, note=note))
    return _table(rows)


# ---------------------------------------------------------------------------------------------
# Spheroid: compression depth (optional)
# ---------------------------------------------------------------------------------------------


CAP_FRACTION = 0.8  # fem.spheroid.compress refuses displacement >= 1.6 a0 (80 % of the diameter)


def compression_jobs(
    fractions: Sequence[float] = (0.2, 0.3, 0.4, 0.5, 0.6),
    mesh="default",
    radius: float = 500 * UM,
    C_: float = 200.0,
    alpha: float = 0.2,
    probe_cap: bool = True,
) -> list[tuple[Callable, dict, int]]:
    """The static FE runs :func:`compression_map` asks for (same arguments), as ``(function, keywords, repeats)``
    (what ``compare.runcache.prefetch`` can start ahead; the map stops at the first failure)."""
    from tissuemech.fem import spheroid as fes

    tries = [float(f) for f in fractions]
    if probe_cap and max(tries) < CAP_FRACTION:
        tries.append(CAP_FRACTION)
    static = dict(radius=radius, C=C_, alpha=alpha, branches=(), ramp_time=1.0, end_time=1.0, mesh=mesh, static=True)
    return [(fes.compress, dict(static, displacement=2 * radius * f), 1) for f in tries]


def compression_map(
    fractions: Sequence[float] = (0.2, 0.3, 0.4, 0.5, 0.6),
    mesh="default",
    radius: float = 500 * UM,
    C_: float = 200.0,
    alpha: float = 0.2,
    probe_cap: bool = True,
) -> pd.DataFrame:
    """Static elastic compression to increasing total approach (fraction of the diameter) until it fails.

    Needs ``fem.spheroid``. Columns: fraction, ``approach [um]``, converged, ``force [N]``, steps,
    newton_iterations, nodal_contact_states (states beyond the fitted-contact range),
    failure (how it failed: "Newton", "contact check", "refused (cap)", ...),
    ``wall_time [s]``, note. Stops at the first failure. With ``probe_cap`` and no failure below it, one more
    attempt at ``CAP_FRACTION`` records that ``fem.spheroid.compress`` refuses it up front (the
    model's stated cap: the ball squeezed below 20 % of its height), so a reader sees whether the
    method or the cap ended the push.
    """
    fr = _positive_list("fractions (approach / diameter)", fractions)
    if np.any(fr >= 1):
        raise ValueError(f"fractions are total approach / diameter and must be below 1; got {list(fractions)}")
    from tissuemech.fem.newton import NewtonError

    tries = [float(f) for f in fractions]
    if probe_cap and max(tries) < CAP_FRACTION:
        tries.append(CAP_FRACTION)
    rows = []
    jobs = compression_jobs(tries, mesh, radius, C_, alpha, probe_cap=False)
    for f, (fn, kw, _) in zip(tries, jobs):
        t0 = time.perf_counter()
        try:
            run = runcache.call(fn, kw)  # reused between reports (compare.runcache), with the time it took
            r = run.result
            rows.append(
                dict(
                    fraction=f,
                    approach_um=float(r.approach[-1]) / UM,
                    converged=True,
                    force_N=float(r.force[-1]),
                    steps=len(r.force),
                    newton_iterations=int(np.sum(r.newton_iterations)),
                    nodal_contact_states=sum(1 for c in (r.parameters or {}).get("contact", ()) if c == "nodal"),
                    failure="",
                    wall_s=run.wall,
                    note="",
                )
            )
        except Exception as e:  # the boundary: say how it failed
            if isinstance(e, NewtonError):
                how = "Newton"
            elif isinstance(e, ValueError) and f >= CAP_FRACTION:
                how = "refused (cap)"
            elif isinstance(e, RuntimeError):
                how = "contact check"
            else:
                how = type(e).__name__
            rows.append(
                dict(
                    fraction=f,
                    approach_um=2 * radius * f / UM,
                    converged=False,
                    force_N=np.nan,
                    steps=0,
                    newton_iterations=0,
                    nodal_contact_states=0,
                    failure=how,
                    wall_s=time.perf_counter() - t0,
                    note=f"{type(e).__name__}: {str(e)[:160]}",
                )
            )
            break
    return _table(rows)


# ---------------------------------------------------------------------------------------------
# Viscoelastic update formulas: the largest step that keeps 1e-3
# ---------------------------------------------------------------------------------------------


def _step_grid(h: float, ramp_time: float, end_time: float) -> np.ndarray:
    n_r = max(1, int(np.ceil(ramp_time / h - 1e-9)))
    n_h = max(1, int(np.ceil((end_time - ramp_time) / h - 1e-9)))
    return np.concatenate([np.linspace(0, ramp_time, n_r + 1), np.linspace(ramp_time, end_time, n_h + 1)[1:]])


def _lumped_steps(t: np.ndarray, update: str, beta: float, tau: float, ramp_time: float) -> np.ndarray:
    """F_n on the grid t by one update formula (piecewise-uniform steps, so a linear filter per piece)."""
    from scipy.signal import lfilter

    F = lumped_equilibrium(t, ramp_time)
    dF = np.diff(F)
    x = np.diff(t) / tau
    if update == "exact-linear":
        a, b = np.exp(-x), beta * -np.expm1(-x) / x
    elif update == "backward Euler":
        a, b = 1.0 / (1.0 + x), beta / (1.0 + x)
    elif update == "forward Euler":
        a, b = 1.0 - x, beta * np.ones_like(x)
    else:
        raise ValueError(f"update must be 'exact-linear', 'backward Euler' or 'forward Euler', got {update!r}")
    q = np.zeros(t.size)
    # group runs of equal step size: q_{n+1} = a q_n + b dF_n is a first-order IIR filter on each run
    cuts = np.flatnonzero(np.abs(np.diff(x)) > 1e-9 * x[:-1]) + 1
    for start, stop in zip(np.r_[0, cuts], np.r_[cuts, x.size]):
        seg = lfilter([b[start]], [1.0, -a[start]], dF[start:stop], zi=[a[start] * q[start]])[0]
        q[start + 1 : stop + 1] = seg
    return F + q


def viscous_step_map(
    steps: Sequence[float] | np.ndarray | None = None,
    *,
    beta: float = 1.2,
    tau: float = 200.0,
    ramp_time: float = 0.2,
    end_time: float = 1500.0,
    updates: Sequence[str] = ("exact-linear", "backward Euler", "forward Euler"),
) -> tuple[pd.DataFrame, pd.DataFrame]:
    """Error of each update formula vs the step h; returns (all rows, boundary per update).

    Rows: update, ``step [s]``, error, n_steps, ok (error <= TOLERANCE and finite). Boundary: update,
    ``largest ok step [s]`` (largest h such that every tested h' <= h keeps the tolerance), its error,
    and whether that is simply the largest step tried (then the true boundary lies beyond).
    """
    for name, v, unit in (
        ("beta", beta, ""),
        ("tau", tau, " s"),
        ("ramp_time", ramp_time, " s"),
        ("end_time", end_time, " s"),
    ):
        if not (np.isfinite(v) and v > 0):
            raise ValueError(f"{name} must be a positive number{unit}; got {v!r}")
    if end_time <= ramp_time:
        raise ValueError(f"end_time ({end_time} s) must be after the end of the ramp ({ramp_time} s)")
    steps = np.geomspace(1e-3, end_time, 34) if steps is None else _positive_list("steps", steps, " in s")
    rows = []
    for h in steps:
        t = _step_grid(float(h), ramp_time, end_time)
        ref = exact_lumped_force(t, beta=beta, tau=tau, ramp_time=ramp_time)
        scale = np.max(np.abs(ref))
        for u in updates:
            with np.errstate(all="ignore"):
                F = _lumped_steps(t, u, beta, tau, ramp_time)
                err = float(np.max(np.abs(F - ref)) / scale)
            rows.append(
                dict(
                    update=u,
                    step_s=float(h),
                    error=err,
                    n_steps=t.size - 1,
                    ok=bool(np.isfinite(err) and err <= TOLERANCE),
                )
            )
    df = _table(rows)
    bounds = []
    for u in updates:
        d = df[df["update"] == u].sort_values("step [s]")
        bad = np.flatnonzero(~d["ok"].to_numpy())
        last = (bad[0] - 1) if bad.size else len(d) - 1
        if last < 0:
            bounds.append(
                dict(
                    update=u,
                    largest_ok_step_s=np.nan,
                    error_at_boundary=np.nan,
                    step_over_tau=np.nan,
                    limited_by_range=False,
                )
            )
            continue
        row = d.iloc[last]
        bounds.append(
            dict(
                update=u,
                largest_ok_step_s=row["step [s]"],
                error_at_boundary=row["error"],
                step_over_tau=row["step [s]"] / tau,
                limited_by_range=not bad.size,
            )
        )
    return df, _table(bounds)


# ---------------------------------------------------------------------------------------------
# Explicit vs implicit diffrax on the stiff lumped ODE
# ---------------------------------------------------------------------------------------------


def stiff_solver_map(
    tau_over_ramp: Sequence[float] = (1e-1, 1e-2, 1e-3, 1e-4, 1e-5),
    *,
    beta: float = 1.2,
    ramp_time: float = 0.2,
    end_time: float = 2.0,
    rtol: float = 1e-8,
    max_steps: int = 20_000,
    solvers: Sequence[str] = ("Tsit5", "Dopri5", "Kvaerno5"),
) -> pd.DataFrame:
    """Steps, rejections and failures of diffrax solvers on dq/dt = -q/tau + beta F_eq'(t), tau << t_r.

    The ramp end is a jump time of the step-size controller. Error = max |q - q_exact| / beta at
    t in {t_r/2, t_r, 2 t_r} (``exact_lumped_force``). Columns: solver, implicit, tau_over_ramp,
    ``tau [s]``, steps (accepted), rejected, failed, error, ``wall_time [s]`` (after compile), note.
    """
    import diffrax
    import equinox as eqx
    import jax
    import jax.numpy as jnp

    import tissuemech.reduced  # noqa: F401  (enables float64)

    _positive_list("tau_over_ramp", tau_over_ramp)
    if not end_time > 2 * ramp_time:
        raise ValueError(
            f"end_time ({end_time} s) must exceed twice the ramp time ({ramp_time} s): errors are read at 2 t_r"
        )
    ts_out = np.array([0.5 * ramp_time, ramp_time, 2 * ramp_time])

    def rhs(t, q, tau):
        s = jnp.clip(t / ramp_time, 0.0, 1.0)
        dF = jnp.where(t < ramp_time, 1.5 * jnp.sqrt(s) / ramp_time, 0.0)
        return -q / tau + beta * dF

    rows = []
    for name in solvers:
        solver = getattr(diffrax, name)()

        @eqx.filter_jit
        def solve(tau, solver=solver):
            ctrl = diffrax.ClipStepSizeController(
                diffrax.PIDController(rtol=rtol, atol=rtol), jump_ts=jnp.asarray([ramp_time])
            )
            return diffrax.diffeqsolve(
                diffrax.ODETerm(rhs),
                solver,
                t0=0.0,
                t1=end_time,
                dt0=None,
                y0=jnp.asarray(0.0),
                args=tau,
                saveat=diffrax.SaveAt(ts=jnp.asarray(ts_out)),
                stepsize_controller=ctrl,
                max_steps=max_steps,
                throw=False,
            )

        for r in tau_over_ramp:
            tau = float(r) * ramp_time
            tau_j = jnp.asarray(tau)
            jax.block_until_ready(solve(tau_j))  # compile (once per solver) / warm-up
            t0 = time.perf_counter()
            sol = jax.block_until_ready(solve(tau_j))
            wall = time.perf_counter() - t0
            ok = bool(sol.result == diffrax.RESULTS.successful)
            err, note = np.nan, ""
            if ok:
                ex = exact_lumped_force(ts_out, beta=beta, tau=tau, ramp_time=ramp_time) - lumped_equilibrium(
                    ts_out, ramp_time
                )
                err = float(np.max(np.abs(np.asarray(sol.ys) - ex)) / beta)
            else:
                note = f"failed: {sol.result} (max_steps = {max_steps})"
            rows.append(
                dict(
                    solver=name,
                    implicit=name.startswith("Kvaerno"),
                    tau_over_ramp=float(r),
                    tau_s=tau,
                    steps=int(sol.stats["num_accepted_steps"]),
                    rejected=int(sol.stats["num_rejected_steps"]),
                    failed=not ok,
                    error=err,
                    wall_s=wall,
                    note=note,
                )
            )
    return _table(rows)
