r"""Accuracy versus speed, per scene: every method's error against its wall time, in one run.

Blastula (``blastula_accuracy``): alpha = 0.2, A = 50 um, B = 75 um, C = 200 Pa, target pressures
p_i in {200, 500, 1000} Pa. Each method returns a state (p_i, lambda_a,i); its error is the relative
pressure residual of that state against the exact incompressible shell,

    error = max_i | p_exact(lambda_a,i) / p_i - 1 |,
    p_exact(lambda_a) = int_{lambda_b}^{lambda_a} 4 C exp(alpha (2 l^2 + l^-4 - 3)) (l^3 + 1) / l^5 dl

(scipy ``quad`` at rtol 1e-13; ``compare.reference.shell_pressure``), which puts the forward
(p from lambda_a) and inverse (lambda_a from p) methods on one scale. Methods:

* reduced, quadrature path: ``reduced.blastula.inner_stretch(p)`` (20-point Gauss-Legendre + Newton);
* reduced, diffrax path: ``reduced.blastula.pressure(lambda_exact, method="ode")`` with the Dopri8
  tolerance set to rtol in {1e-3 .. 1e-10} (its ``rtol=`` argument);
* FE: ``fem.blastula.inflate`` (load control, kappa = 2.2 GPa) on 4 mesh levels (n_radial, n_circ).

Wall times: the fastest of ``repeats`` calls after one warm-up call (``wall_time [s]``; ``REDUCED_CALLS`` (21)
calls for the jitted reduced paths, ``REDUCED_CALLS_QUICK`` (7) in quick mode; the fastest call is the least
disturbed by other work on a shared machine), with their spread ``wall_time min [s]`` .. ``wall_time max [s]``
and median ``wall_time median [s]``; JIT compile and mesh set-up of the warm-up call are in ``first call [s]``. ``pareto`` only lets a row
dominate another when it is faster beyond the spread.

Spheroid (``spheroid_accuracy``, needs ``fem.spheroid`` and ``reduced.spheroid``): the seed's Fig. 10
case; the reference is the converged FE value: the Richardson extrapolation of sigma~ over the three
finest contact-edge-fitted levels run (observed order; ``compare.bench.fem_spheroid.richardson``), so no
method (not the finest level, not a table calibrated on one level) is compared with itself; error = max
over t in {0.2 s, 1500 s} of |sigma~(t) / sigma~_ref(t) - 1| (sigma~ = F / A_mid, Pa). Methods: the
reduced lumped model (jitted; the fastest of ``reduced_calls`` calls after compile) with the Hertz law and with an
FE-calibrated law (tables passed by the caller), FE on every level (the fastest of ``fe_repeats`` runs,
mesh set-up included in each).

Spheroid in time (``spheroid_time_convergence``, issue 35): the fast two-branch case (``cases.FAST_BRANCHES``,
tau = 0.05 s on a 0.2 s ramp) on one contact-edge-fitted level, F at t = 0.05, 0.1, 0.2 s for fixed ramp steps
(``fem.stepping.Fixed``) and adaptive ones (``fem.stepping.Adaptive``, the default), against the level's own
time-converged force (the Richardson limit of the three finest fixed runs, observed order), next to the lumped
recursion's estimate of the same error (``fem.stepping.lumped_force``, what ``Adaptive`` controls).

``pareto(df)`` marks the rows not dominated in (wall time, error).
"""

from __future__ import annotations

import time
from collections.abc import Callable, Sequence
from typing import Any, TypeVar, cast

import numpy as np
import pandas as pd

from tissuemech.compare import cases, runcache
from tissuemech.compare.reference import shell_inner_stretch, shell_pressure

A, C = cases.BLASTULA_INNER_RADIUS, cases.BLASTULA_C
B, ALPHA = cases.FIG3["outer_radius"], cases.FIG3["alpha"]
PRESSURES = cases.ACCURACY_PRESSURES
ODE_RTOLS = (1e-3, 1e-4, 1e-6, 1e-8, 1e-10)
FE_MESHES = ((2, 4), (4, 8), (8, 16), (16, 32))
FE_MESHES_QUICK = ((1, 2), (2, 4), (4, 8), (8, 16))

__all__ = [
    "blastula_accuracy",
    "spheroid_accuracy",
    "spheroid_time_convergence",
    "TIME_TIMES",
    "spheroid_fe_jobs",
    "blastula_fe_jobs",
    "time_convergence_jobs",
    "pareto",
    "timed",
    "timed_stats",
    "FE_MESHES",
    "FE_MESHES_QUICK",
]


_T = TypeVar("_T")

REDUCED_CALLS = 21  # timed calls of a jitted reduced path (its fastest is the least disturbed by other work)
REDUCED_CALLS_QUICK = 7  # the same in quick mode (the reduced rows' timing was ~4 s of a cold quick report)


def reduced_calls(quick: bool) -> int:
    """Timed calls of each jitted reduced path in the accuracy tables (after the compiling first call)."""
    return REDUCED_CALLS_QUICK if quick else REDUCED_CALLS


def timed_stats(fn: Callable[[], _T], repeats: int = 5) -> tuple[float, np.ndarray, _T]:
    """(first-call seconds, seconds of each of ``repeats`` further calls, last result)."""
    t0 = time.perf_counter()
    out = fn()
    first = time.perf_counter() - t0
    walls = []
    for _ in range(max(int(repeats), 1)):
        t0 = time.perf_counter()
        out = fn()
        walls.append(time.perf_counter() - t0)
    return first, np.asarray(walls), out


WALL = "wall_time [s]"  # the table headers of the timing columns
WALL_MIN, WALL_MAX, FIRST = "wall_time min [s]", "wall_time max [s]", "first call [s]"
WALL_MEDIAN = "wall_time median [s]"


def _wall_columns(first: float, walls: np.ndarray) -> dict:
    """wall_time (the fastest of the repeats), its min / max (the spread), median, the first call, repeats."""
    return {
        WALL: float(np.min(walls)),
        WALL_MIN: float(np.min(walls)),
        WALL_MAX: float(np.max(walls)),
        WALL_MEDIAN: float(np.median(walls)),
        FIRST: first,
        "repeats": int(walls.size),
    }


def timed(fn: Callable[[], _T], repeats: int = 3) -> tuple[float, float, _T]:
    """(first-call seconds, best seconds of ``repeats`` further calls, last result)."""
    t0 = time.perf_counter()
    out = fn()
    first = time.perf_counter() - t0
    best = np.inf
    for _ in range(max(int(repeats), 1)):
        t0 = time.perf_counter()
        out = fn()
        best = min(best, time.perf_counter() - t0)
    return first, best, out


def _pressure_error(stretch: Any, pressure: Any, alpha: float = ALPHA) -> float:
    return float(
        max(
            abs(shell_pressure(float(l), outer_radius=B, alpha=alpha) / float(p) - 1.0)
            for l, p in zip(stretch, pressure)
        )
    )


def blastula_fe_jobs(quick: bool = False, repeats: int = 3) -> list[tuple[Callable, dict, int]]:
    """The FE runs of :func:`blastula_accuracy` as ``(function, keywords, repeats)``, one per mesh (the first call
    and ``repeats`` timed ones; what ``compare.runcache.prefetch`` can start ahead)."""
    from tissuemech.fem.blastula import inflate

    kw = dict(inner_radius=A, outer_radius=B, C=C, alpha=ALPHA, pressures=np.asarray(PRESSURES))
    return [(inflate, dict(kw, mesh=m), max(int(repeats), 1) + 1) for m in (FE_MESHES_QUICK if quick else FE_MESHES)]


def blastula_reduced_job(quick: bool = False, repeats: int = 3) -> tuple[Callable, dict, int]:
    """The reduced rows of :func:`blastula_accuracy` as one ``(function, keywords, repeats)`` job (what
    ``compare.runcache.prefetch`` can start ahead: JAX compiles and timed calls, ~5-8 s)."""
    return blastula_reduced_rows, dict(quick=bool(quick), repeats=int(repeats)), 1


def blastula_reduced_rows(quick: bool = False, repeats: int = 3) -> list[dict]:
    """The reduced rows of :func:`blastula_accuracy` (quadrature inverse, diffrax forward at ``ODE_RTOLS``): each
    jitted, timed over ``max(repeats, reduced_calls(quick))`` calls after the compiling first one."""
    import jax

    from tissuemech.reduced import blastula as bl

    ps = np.asarray(PRESSURES)
    la_ex = np.array([shell_inner_stretch(p, outer_radius=B, alpha=ALPHA) for p in ps])
    geo = dict(inner_radius=A, outer_radius=B, C=C, alpha=ALPHA)
    rows: list[dict] = []

    inv = jax.jit(lambda q: bl.inner_stretch(q, **geo))
    first, walls, la = timed_stats(lambda: jax.block_until_ready(inv(ps)), max(repeats, reduced_calls(quick)))
    la = np.asarray(la)
    rows.append(
        dict(
            method="reduced quadrature",
            setting="20-pt Gauss-Legendre",
            **_wall_columns(first, walls),
            error=_pressure_error(la, ps),
            stretch_error=float(np.max(np.abs(la / la_ex - 1))),
        )
    )

    for rtol in ODE_RTOLS:
        fwd = jax.jit(lambda x, rtol=rtol: bl.pressure(x, **geo, method="ode", rtol=rtol))
        first, walls, p = timed_stats(lambda: jax.block_until_ready(fwd(la_ex)), max(repeats, reduced_calls(quick)))
        p = np.asarray(p)
        rows.append(
            dict(
                method="reduced diffrax (Dopri8)",
                setting=f"rtol={rtol:.0e}",
                **_wall_columns(first, walls),
                error=float(np.max(np.abs(ps / p - 1))),
                stretch_error=np.nan,
            )
        )

    return rows


def blastula_accuracy(quick: bool = False, repeats: int = 3) -> pd.DataFrame:
    """Error against wall time for the reduced (quadrature, diffrax) and FE blastula paths.

    Returns a DataFrame with columns method, setting, ``wall_time [s]`` (the fastest of ``repeats`` calls
    after a warm-up), ``wall_time min [s]``, ``wall_time max [s]`` (their spread), ``wall_time median [s]``,
    ``first call [s]``
    (first call, includes JIT compile / mesh set-up), repeats, error (see the module docstring),
    stretch_error (max |lambda_a / lambda_exact - 1|) and pareto (bool).
    """
    ps = np.asarray(PRESSURES)
    la_ex = np.array([shell_inner_stretch(p, outer_radius=B, alpha=ALPHA) for p in ps])
    # through the run cache, like the FE runs: the report's builder computes them ahead in its second process
    rows = list(runcache.call(*blastula_reduced_job(quick, repeats)[:2]).result)

    for m, job in zip(FE_MESHES_QUICK if quick else FE_MESHES, blastula_fe_jobs(quick, repeats)):
        # through the run cache (compare.runcache): a later report reuses the runs and the times they took
        timed_runs = runcache.call(*job[:2], repeats=job[2])  # timed_stats: first + repeats
        first, walls, r = timed_runs.walls[0], np.asarray(timed_runs.walls[1:]), timed_runs.result
        rows.append(
            dict(
                method="FE Q2/P1 mixed",
                setting=f"mesh {m[0]}x{m[1]}",
                **_wall_columns(first, walls),
                error=_pressure_error(r.inner_stretch, r.pressure),
                stretch_error=float(np.max(np.abs(r.inner_stretch / la_ex - 1))),
            )
        )
    df = pd.DataFrame(rows)
    df["pareto"] = pareto(df)
    return df


def pareto(df: pd.DataFrame, x: str = WALL, y: str = "error") -> np.ndarray:
    """Boolean mask of rows on the Pareto front: no other row is both faster and more accurate.

    With ``wall_time min [s]`` / ``wall_time max [s]`` columns (the spread of the repeated timings), row j
    dominates row i when it is more accurate and not slower beyond the spread (j's fastest call no
    slower than i's slowest), or as accurate and faster beyond the spread (j's slowest call faster
    than i's fastest). Timing noise inside the measured spreads cannot change the flags.
    """
    xs, ys = df[x].to_numpy(float), df[y].to_numpy(float)
    lo = df[WALL_MIN].to_numpy(float) if WALL_MIN in df else xs
    hi = df[WALL_MAX].to_numpy(float) if WALL_MAX in df else xs
    ok = np.isfinite(xs) & np.isfinite(ys)
    mask = np.zeros(len(df), bool)
    for i in np.flatnonzero(ok):
        better_not_slower = (ys < ys[i]) & (lo <= hi[i])
        as_good_faster = (ys <= ys[i]) & (hi < lo[i])
        dominated = ok & (better_not_slower | as_good_faster)
        dominated[i] = False
        mask[i] = not dominated.any()
    return mask


# ---------------------------------------------------------------------------------------------
# Spheroid (optional: needs fem.spheroid and reduced.spheroid)
# ---------------------------------------------------------------------------------------------

FIG10 = cases.FIG10
SPHEROID_TIMES = cases.FIG10_TIMES


_SPHEROID_COLUMNS = {
    "sigma_0_2s": "sigma 0.2 s [Pa]",
    "sigma_1500s": "sigma 1500 s [Pa]",
}


def spheroid_available() -> str | None:
    """None when both spheroid modules import, else the reason (shown as 'not available')."""
    try:
        import tissuemech.fem.spheroid
        import tissuemech.reduced.spheroid  # noqa: F401
    except Exception as exc:  # ImportError, or a module that is still being written
        return f"{type(exc).__name__}: {exc}"
    return None


def spheroid_fe_jobs(meshes: Sequence, fe_repeats: int) -> list[tuple[Callable, dict, int]]:
    """The FE runs of :func:`spheroid_accuracy` as ``(function, keywords, repeats)``, one per mesh level (what
    ``compare.runcache.prefetch`` can start ahead)."""
    from tissuemech.fem import spheroid as fes

    end = float(np.asarray(SPHEROID_TIMES)[-1])
    return [(fes.compress, dict(**FIG10, end_time=end, mesh=m), int(fe_repeats)) for m in meshes]


def spheroid_accuracy(
    quick: bool = False,
    meshes: Sequence | None = None,
    equilibria: dict | None = None,
    fe_repeats: int = 2,
    settings: dict | None = None,
) -> tuple[pd.DataFrame, dict]:
    """Error of sigma~ at t = 0.2 s and 1500 s against the extrapolated FE reference, with wall times (Fig. 10).

    ``meshes``: FE mesh levels from coarsest to finest (>= 3; the three finest give the Richardson
    reference); default (0, 1, 2, 3) (quick: (0, 1, 2)). ``equilibria``: name -> keyword arguments of
    ``reduced.spheroid.nominal_stress`` (e.g. ``{"hertz": dict(equilibrium="hertz")}``, the default, or
    ``dict(equilibrium="fem")``); ``settings``: name -> the text of the row's setting column (default:
    the name). ``fe_repeats``: runs per FE level (>= 1; the fastest is the wall time, the spread is kept).
    Returns (table, {mesh: FE result}); table columns: method, setting, ``wall_time [s]`` (fastest
    call), ``wall_time min [s]``, ``wall_time max [s]``, ``wall_time median [s]``, ``first call [s]``,
    repeats, error, ``sigma 0.2 s [Pa]``, ``sigma 1500 s [Pa]`` (sigma~ at those times), pareto.
    """
    import jax

    from tissuemech.compare.bench.fem_spheroid import richardson
    from tissuemech.fem import spheroid as fes
    from tissuemech.reduced import spheroid as rs

    meshes = list(meshes or ((0, 1, 2) if quick else (0, 1, 2, 3)))
    if len(meshes) < 3:
        raise ValueError("spheroid_accuracy needs >= 3 mesh levels (the three finest give the reference)")
    if int(fe_repeats) < 1:
        raise ValueError(f"fe_repeats (FE runs per mesh level) must be >= 1; got {fe_repeats}")
    equilibria = equilibria or {"hertz": dict(equilibrium="hertz")}
    settings = settings or {}
    ts = np.asarray(SPHEROID_TIMES)
    fe: dict[Any, tuple[dict, Any]] = {}
    for m, (fn, kwargs, repeats) in zip(meshes, spheroid_fe_jobs(meshes, fe_repeats)):
        # every run includes its mesh set-up: the fastest is the least disturbed; through the run cache
        # (compare.runcache): a later report reuses the runs and the times they took
        runs = runcache.call(fn, kwargs, repeats=repeats)
        fe[m] = (_wall_columns(runs.walls[0], np.asarray(runs.walls, float)), runs.result)
    sig = {m: np.interp(ts, r.time, r.nominal_stress) for m, (_, r) in fe.items()}
    h = [1.0 / fes.LEVELS[m][0] for m in meshes[-3:]]
    s_ref = np.array([richardson([sig[m][k] for m in meshes[-3:]], h)[1] for k in range(ts.size)])
    rows: list[dict[str, Any]] = [
        dict(
            method="FE Richardson",
            setting="Richardson over levels " + ", ".join(str(m) for m in meshes[-3:]),
            error=np.nan,
            sigma_0_2s=s_ref[0],
            sigma_1500s=s_ref[1],
        )
    ]
    for m in meshes:
        cols, r = fe[m]
        s = sig[m]
        rows.append(
            dict(
                method="FE Q2/P1 mixed",
                setting=f"level {m}",
                **cols,
                error=float(np.max(np.abs(s / s_ref - 1))),
                sigma_0_2s=s[0],
                sigma_1500s=s[1],
            )
        )
    for name, kw in equilibria.items():
        fn = jax.jit(lambda tt, kw=kw: rs.nominal_stress(tt, **FIG10, **kw))  # tables become constants
        first, red_walls, s = timed_stats(
            cast(Callable[[], np.ndarray], lambda fn=fn: np.asarray(jax.block_until_ready(fn(ts)))),
            reduced_calls(quick),
        )
        rows.append(
            dict(
                method=f"reduced ({name})",
                setting=settings.get(name, name),
                **_wall_columns(first, red_walls),
                error=float(np.max(np.abs(s / s_ref - 1))),
                sigma_0_2s=s[0],
                sigma_1500s=s[1],
            )
        )
    df = pd.DataFrame(rows).rename(columns=_SPHEROID_COLUMNS)
    df["pareto"] = pareto(df)
    return df, {m: r for m, (_, r) in fe.items()}


TIME_TIMES = (0.05, 0.1, 0.2)  # s, where spheroid_time_convergence reads F (the ramp of cases.FAST_BRANCHES)


def _time_convergence_settings(
    quick: bool, level: int | None, fixed: Sequence[int] | None, tols: Sequence[float] | None
) -> tuple[int, list[int], list[float]]:
    level = (0 if quick else 1) if level is None else int(level)
    fixed = list(fixed or ((6, 12, 24) if quick else (6, 12, 24, 48)))
    tols = list(tols or ((1e-3,) if quick else (5e-4, 2e-4)))
    return level, fixed, tols


def time_convergence_jobs(
    quick: bool = False,
    level: int | None = None,
    fixed: Sequence[int] | None = None,
    tols: Sequence[float] | None = None,
) -> list[tuple[Callable, dict, int]]:
    """The FE runs of :func:`spheroid_time_convergence` as ``(function, keywords, repeats)``: the fixed step counts,
    then the adaptive tolerances (what ``compare.runcache.prefetch`` can start ahead)."""
    from tissuemech.fem.spheroid import compress
    from tissuemech.fem.stepping import Adaptive

    level, fixed, tols = _time_convergence_settings(quick, level, fixed, tols)
    case = dict(cases.FAST_BRANCHES, end_time=TIME_TIMES[-1], mesh=level, field_times=list(TIME_TIMES))
    return [(compress, dict(case, n_ramp=int(n)), 1) for n in fixed] + [
        (compress, dict(case, stepping=Adaptive(tol=float(tol))), 1) for tol in tols
    ]


def spheroid_time_convergence(
    quick: bool = False,
    level: int | None = None,
    fixed: Sequence[int] | None = None,
    tols: Sequence[float] | None = None,
) -> pd.DataFrame:
    """F / F_ref - 1 at ``TIME_TIMES`` per step strategy on the fast two-branch case (see the module docstring).

    Defaults: level 1, fixed n_ramp = 6, 12, 24, 48, Adaptive tol = 5e-4, 2e-4; quick: level 0, n_ramp = 6, 12, 24,
    tol = 1e-3 (the run ends at the ramp's end, 0.2 s). Columns: method ("FE fixed", "FE adaptive", "FE
    Richardson"), setting, ramp steps, ``error 0.05 s`` ..., error (max |.| over the times), ``lumped estimate``
    (the same max for the lumped recursion on the same steps, against its own 100x finer run), ``wall_time [s]``.
    """
    from tissuemech.fem.stepping import lumped_force

    level, fixed, tols = _time_convergence_settings(quick, level, fixed, tols)
    if len(fixed) < 3:
        raise ValueError("spheroid_time_convergence needs >= 3 fixed step counts (the three finest give the reference)")
    case = dict(cases.FAST_BRANCHES, end_time=TIME_TIMES[-1])
    ts = np.asarray(TIME_TIMES)
    beta = [b for b, _ in case["branches"]]
    tau = [t for _, t in case["branches"]]
    shape = lambda t: np.minimum(np.asarray(t, float) / case["ramp_time"], 1.0) ** 1.5
    fine = np.unique(np.r_[np.linspace(0.0, ts[-1], 20001)[1:], ts])
    F_fine = lumped_force(fine, shape, beta, tau)
    lumped_ref = np.array([F_fine[np.argmin(np.abs(fine - t))] for t in ts])

    def run(label: str, setting: str, job: tuple[Callable, dict, int]) -> dict:
        # through the run cache (compare.runcache): a later report reuses the run and the time it took
        timed = runcache.call(job[0], job[1])
        r, wall = timed.result, timed.wall
        k = [int(np.argmin(np.abs(r.time - t))) for t in ts]
        Fl = lumped_force(r.time, shape, beta, tau)[k]
        return dict(
            method=label,
            setting=setting,
            ramp_steps=int(np.sum(r.time <= case["ramp_time"] * (1 + 1e-12))),
            F=r.force[k],
            lumped=float(np.max(np.abs(Fl / lumped_ref - 1))),
            **{WALL: wall},
        )

    jobs = time_convergence_jobs(quick, level, fixed, tols)
    rows = [run("FE fixed", f"n_ramp = {n}", job) for n, job in zip(fixed, jobs)]
    rows += [run("FE adaptive", f"tol = {tol:g}", job) for tol, job in zip(tols, jobs[len(fixed) :])]
    F1, F2, F4 = (rows[i]["F"] for i in range(len(fixed) - 3, len(fixed)))
    with np.errstate(divide="ignore", invalid="ignore"):
        p = np.clip(np.nan_to_num(np.log2(np.abs(F2 - F1) / np.abs(F4 - F2)), nan=2.0), 1.0, 3.0)
    F_ref = F4 + (F4 - F2) / (2.0**p - 1.0)
    out = []
    for r in rows:
        e = r.pop("F") / F_ref - 1.0
        out.append(
            dict(
                **{k: r[k] for k in ("method", "setting", "ramp_steps")},
                **{f"error {t:g} s": v for t, v in zip(ts, e)},
                error=float(np.max(np.abs(e))),
                **{"lumped estimate": r["lumped"], WALL: r[WALL]},
            )
        )
    out.append(
        dict(
            method="FE Richardson",
            setting=f"n_ramp = {', '.join(map(str, fixed[-3:]))}; order " + ", ".join(f"{v:.2f}" for v in p),
            ramp_steps=np.nan,
            error=np.nan,
        )
    )
    df = pd.DataFrame(out)
    df.attrs["level"] = level
    return df
