"""Benchmark of the reduced blastula paths (``reduced.blastula``, ``reduced.viscoshell``).

    python -m tissuemech.compare.bench.reduced_blastula [--n 1000000] [--baseline 2000] [--api-only]
    python -m tissuemech.compare.bench.reduced_blastula --compile   (start-up only: compile times, cold command)

Part 1 (:func:`api_rows`, issue 14): every public function called eagerly with NumPy arrays, as a
user calls it, against the same call under ``jax.jit``, interleaved in one run (median of the
repeats): the ratio eager/jit at ``n`` points and the per-call cost at N = 1; ``limit_point``'s peak
memory at 1e4 / 1e5 / 1e6 points (fresh interpreters, ``ru_maxrss``) shows it flat in N. The issue-14
targets are printed next to each row (``target``: eager/jit <= 1.5, <= 100 us per call at N = 1,
inner_stretch >= 1e6 and limit_point >= 2e5 points/s; ``met``: yes/NO for each, in that order).
:func:`dispatch_rows` times the one-point calls again in fresh interpreters, with JAX's default
asynchronous CPU dispatch and with inline dispatch (``jax_cpu_enable_async_dispatch`` False), alternated.

Each row: the path, points per call, compile time, throughput after compile (points/s, best of a
few calls with ``block_until_ready``), the max relative error against a high-accuracy reference,
and the plain-SciPy baseline (a ``scipy.integrate.quad`` loop; ``brentq`` on it for the inverse)
with the speed-up. Timings on a shared 2-core CPU are pessimistic.
"""

from __future__ import annotations

import argparse
import math
import time
from collections.abc import Callable, Sequence

import jax.numpy as jnp
import numpy as np
from scipy.optimize import brentq

from tissuemech.compare.bench.common import jit_timed as _timed
from tissuemech.compare.bench.common import print_rows
from tissuemech.compare.cases import BLASTULA_C, BLASTULA_INNER_RADIUS, FIG4_OUTER_RADIUS
from tissuemech.compare.reference import shell_pressure

A, B, C = BLASTULA_INNER_RADIUS, FIG4_OUTER_RADIUS, BLASTULA_C


def _quad_pressure(la: float, A: float, B: float, C: float, alpha: float) -> float:
    return shell_pressure(la, inner_radius=A, outer_radius=B, C=C, alpha=alpha)


def _scipy_rate(fn: Callable, items) -> float:
    t0 = time.perf_counter()
    for it in items:
        fn(*it)
    return len(items) / (time.perf_counter() - t0)


def rows(n: int = 1_000_000, n_baseline: int = 2000, seed: int = 0) -> list[dict]:
    from tissuemech.reduced import blastula as bl
    from tissuemech.reduced import viscoshell as vs

    rng = np.random.default_rng(seed)
    out: list[dict] = []
    alpha = 0.2
    geo = dict(inner_radius=A, outer_radius=B)

    # -- forward, quadrature path: random stretch in [1, 4] and alpha in [0, 0.3]
    la = jnp.asarray(rng.uniform(1.0, 4.0, n))
    al = jnp.asarray(rng.uniform(0.0, 0.3, n))
    tc, dt, p = _timed(lambda x, a: bl.pressure(x, **geo, C=C, alpha=a), la, al)
    idx = rng.choice(n, n_baseline, replace=False)
    items = [(float(la[i]), A, B, C, float(al[i])) for i in idx]
    ref = np.array([_quad_pressure(*it) for it in items])
    err = float(np.max(np.abs(np.asarray(p)[idx] / ref - 1)))
    base = _scipy_rate(_quad_pressure, items)
    out.append(
        dict(
            path="blastula.pressure quadrature",
            points=n,
            compile_s=tc,
            points_per_s=n / dt,
            max_rel_err=err,
            baseline="scipy quad loop",
            baseline_points_per_s=base,
            speedup=n / dt / base,
        )
    )

    # -- inverse (rising branch): Fung alpha = 0.2 over lambda_a in [0.5, 4]; neo-Hookean below the limit
    for a_inv, hi in ((alpha, 4.0), (0.0, float(bl.limit_point(**geo, C=C, alpha=0.0).inner_stretch) - 1e-3)):
        la = jnp.asarray(rng.uniform(0.5, hi, n))
        pt = bl.pressure(la, **geo, C=C, alpha=a_inv)
        tc, dt, la_inv = _timed(lambda q: bl.inner_stretch(q, **geo, C=C, alpha=a_inv), pt, repeats=2)
        err = float(np.nanmax(np.abs(np.asarray(la_inv) / np.asarray(la) - 1)))
        nb = max(n_baseline // 10, 20)
        sub = [(float(pt[i]), float(la[i])) for i in idx[:nb]]

        def brent(pv: float, _la: float, a_=a_inv, hi_=hi) -> float:
            f = lambda x: _quad_pressure(x, A, B, C, a_) - pv
            return brentq(f, 0.5, hi_ + 1e-3, xtol=1e-14, rtol=1e-14)

        base = _scipy_rate(brent, sub)
        out.append(
            dict(
                path=f"blastula.inner_stretch (alpha={a_inv:g})",
                points=n,
                compile_s=tc,
                points_per_s=n / dt,
                max_rel_err=err,
                baseline="brentq on quad",
                baseline_points_per_s=base,
                speedup=n / dt / base,
            )
        )

    # -- diffrax radial-ODE path (vmapped), error against the quadrature
    m = max(n // 50, 1000)
    la = jnp.asarray(rng.uniform(1.0, 4.0, m))
    tc, dt, p_ode = _timed(lambda x: bl.pressure(x, **geo, C=C, alpha=alpha, method="ode"), la, repeats=2)
    p_q = bl.pressure(la, **geo, C=C, alpha=alpha)
    err = float(np.max(np.abs(np.asarray(p_ode) / np.asarray(p_q) - 1)))
    out.append(
        dict(
            path="blastula.pressure ode (Dopri8, vmap)",
            points=m,
            compile_s=tc,
            points_per_s=m / dt,
            max_rel_err=err,
            baseline="scipy quad loop",
            baseline_points_per_s=base_fwd(out),
            speedup=m / dt / base_fwd(out),
        )
    )

    # -- limit point (scan + bisection), vmapped over alpha x B
    nl = 10_000
    al = jnp.asarray(rng.uniform(0.0, 0.05, nl))
    Bs = jnp.asarray(rng.uniform(52e-6, 100e-6, nl))
    tc, dt, lim = _timed(lambda a, b: bl.limit_point(inner_radius=A, outer_radius=b, C=C, alpha=a), al, Bs)
    out.append(
        dict(
            path="blastula.limit_point",
            points=nl,
            compile_s=tc,
            points_per_s=nl / dt,
            max_rel_err="",
            baseline="",
            baseline_points_per_s="",
            speedup="",
        )
    )

    # -- 1e6-point parameter grid (stretch x alpha x B) in one call, by broadcasting
    g = round(n ** (1 / 3))
    la_g = jnp.linspace(1.0, 4.0, g)[:, None, None]
    al_g = jnp.linspace(0.0, 0.3, g)[None, :, None]
    B_g = jnp.linspace(52e-6, 150e-6, g)[None, None, :]
    tc, dt, grid = _timed(lambda x, a, b: bl.pressure(x, inner_radius=A, outer_radius=b, C=C, alpha=a), la_g, al_g, B_g)
    ok = bool(np.all(np.isfinite(np.asarray(grid))))
    out.append(
        dict(
            path=f"pressure grid {g}x{g}x{g} (la x alpha x B)",
            points=g**3,
            compile_s=tc,
            points_per_s=g**3 / dt,
            max_rel_err="" if ok else "non-finite",
            baseline="",
            baseline_points_per_s="",
            speedup="",
        )
    )

    # -- viscoelastic shell: one creep history (step, held 60 tau), after compile
    t = jnp.linspace(0.0, 12_000.0, 61)
    kw = dict(pressure=150.0, **geo, C=C, alpha=alpha, branches=[(1.2, 200.0)])
    t0 = time.perf_counter()
    run = vs.inflate(t, **kw)
    t_first = time.perf_counter() - t0
    t0 = time.perf_counter()
    run = vs.inflate(t, **kw)
    t_run = time.perf_counter() - t0
    relaxed = float(bl.inner_stretch(150.0, **geo, C=C, alpha=alpha))
    out.append(
        dict(
            path="viscoshell.inflate (1 branch, 61 outputs)",
            points=1,
            compile_s=t_first - t_run,
            points_per_s=1 / t_run,
            max_rel_err=abs(float(run.inner_stretch[-1]) / relaxed - 1),
            baseline="vs relaxed elastic limit",
            baseline_points_per_s="",
            speedup="",
        )
    )
    return out


def _median_pair(f: Callable, g: Callable, repeats: int, inner: int = 1) -> tuple[float, float]:
    """Median seconds per call of f and of g, interleaved (f, g, f, g, ...), ``inner`` calls per sample."""
    import jax

    jax.block_until_ready(f())
    jax.block_until_ready(g())
    tf, tg = [], []
    for _ in range(repeats):
        for fn, acc in ((f, tf), (g, tg)):
            t0 = time.perf_counter()
            for _ in range(inner):
                out = fn()
            jax.block_until_ready(out)
            acc.append((time.perf_counter() - t0) / inner)
    return float(np.median(tf)), float(np.median(tg))


def _api_cases(n: int, rng: np.random.Generator) -> list[tuple[str, Callable, tuple, int]]:
    """(name, function of arrays, arguments at n points, output points per call)."""
    from tissuemech.reduced import blastula as bl

    geo = dict(inner_radius=A, outer_radius=B, C=C)
    la = rng.uniform(1.0, 4.0, n)
    al = rng.uniform(0.0, 0.3, n)
    p = np.asarray(bl.pressure(rng.uniform(0.6, 4.0, n), **geo, alpha=0.2))
    npr = max(n // 50, 1)
    Bs = rng.uniform(52e-6, 100e-6, n)
    al_lim = rng.uniform(0.0, 0.05, n)
    return [
        ("pressure", lambda x, a: bl.pressure(x, **geo, alpha=a), (la, al), n),
        ("pressure_derivative", lambda x, a: bl.pressure_derivative(x, **geo, alpha=a), (la, al), n),
        ("outer_stretch", lambda x: bl.outer_stretch(x, inner_radius=A, outer_radius=B), (la,), n),
        ("inner_stretch (alpha=0.2)", lambda q: bl.inner_stretch(q, **geo, alpha=0.2), (p,), n),
        ("profiles (n=50)", lambda x, a: bl.profiles(x, **geo, alpha=a), (la[:npr], al[:npr]), 50 * npr),
        (
            "limit_point",
            lambda b, a: bl.limit_point(inner_radius=A, outer_radius=b, C=C, alpha=a),
            (Bs, al_lim),
            n,
        ),
    ]


def limit_point_memory(n: int) -> float:
    """Peak resident memory (MB, ``ru_maxrss``) of a fresh interpreter that imports the package and calls
    ``limit_point`` once at n points (compile included): flat in n when the scan runs in blocks."""
    import subprocess
    import sys

    code = (
        "import resource, numpy as np, tissuemech.reduced\n"
        "from tissuemech.reduced import blastula as bl\n"
        "rng = np.random.default_rng(0)\n"
        "def call(m):\n"
        "    bl.limit_point(inner_radius=50e-6, outer_radius=rng.uniform(52e-6, 1e-4, m), C=200.0,"
        " alpha=rng.uniform(0, 0.05, m))\n"
        f"call({int(n)})\n"
        "print(resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024)\n"
    )
    return float(subprocess.check_output([sys.executable, "-c", code]).decode().strip().splitlines()[-1])


# issue 14 targets, printed next to the measurements (``target`` / ``met`` columns of :func:`api_rows`)
EAGER_OVER_JIT_TARGET = 1.5  # eager time / jitted time at n points
N1_TARGET_US = 100.0  # eager call with one point, microseconds
_RATE_TARGETS = {"inner_stretch (alpha=0.2)": 1e6, "limit_point": 2e5}  # eager points/s at n points


def api_rows(n: int = 1_000_000, repeats: int = 5, seed: int = 0, memory: bool = True) -> list[dict]:
    """Eager public calls (NumPy in) against the same call under ``jax.jit``, interleaved; see the module
    docstring. Columns: function, points, eager_points_per_s, jit_points_per_s, eager_over_jit, n1_eager_us,
    n1_jit_us, eager_vs_jit_max_rel (max relative difference of the results), target (the issue-14
    targets of the row) and met (yes/NO for each target, in the order printed)."""
    import jax

    rng = np.random.default_rng(seed)
    out: list[dict] = []
    small = {name: args for name, _, args, _ in _api_cases(1, np.random.default_rng(seed + 1))}
    for name, fn, args, pts in _api_cases(n, rng):
        jf = jax.jit(fn)
        big = max(1, repeats if pts <= 2e6 else 3)
        te, tj = _median_pair(lambda: fn(*args), lambda: jf(*args), big)
        e, j = jax.tree_util.tree_leaves(fn(*args)), jax.tree_util.tree_leaves(jf(*args))
        with np.errstate(invalid="ignore", divide="ignore"):  # NaN entries (no limit point) compare as equal
            diff = max(
                float(np.nanmax(np.abs(np.asarray(a) / np.asarray(b) - 1), initial=0.0)) if np.size(a) else 0.0
                for a, b in zip(e, j)
            )
        a1 = small[name]
        t1e, t1j = _median_pair(lambda: fn(*a1), lambda: jf(*a1), 15, inner=20)
        rate_target = _RATE_TARGETS.get(name)
        met = [te / tj <= EAGER_OVER_JIT_TARGET, t1e * 1e6 <= N1_TARGET_US]
        if rate_target is not None:
            met.append(pts / te >= rate_target)
        out.append(
            dict(
                function=name,
                points=pts,
                eager_points_per_s=pts / te,
                jit_points_per_s=pts / tj,
                eager_over_jit=te / tj,
                n1_eager_us=t1e * 1e6,
                n1_jit_us=t1j * 1e6,
                eager_vs_jit_max_rel=diff,
                target=f"eager/jit <= {EAGER_OVER_JIT_TARGET:g}, N=1 <= {N1_TARGET_US:g} us"
                + ("" if rate_target is None else f", >= {rate_target:.0e} points/s"),
                met=" / ".join("yes" if m else "NO" for m in met),
            )
        )
    if memory:
        mem = {m: limit_point_memory(m) for m in (10_000, 100_000, 1_000_000)}
        out.append(
            dict(
                function="limit_point peak RSS of the process (MB)",
                points="1e4/1e5/1e6",
                eager_points_per_s=" / ".join(f"{v:.0f}" for v in mem.values()),
            )
        )
    return out


def one_point_costs(repeats: int = 15, inner: int = 20) -> dict[str, float]:
    """Median seconds of an eager one-point call of each public function (the ``N = 1`` column of
    :func:`api_rows`), in this process as JAX is configured here."""
    import jax

    out = {}
    for name, fn, args, _ in _api_cases(1, np.random.default_rng(1)):
        jax.block_until_ready(fn(*args))
        samples = []
        for _ in range(repeats):
            t0 = time.perf_counter()
            for _ in range(inner):
                res = fn(*args)
            jax.block_until_ready(res)
            samples.append((time.perf_counter() - t0) / inner)
        out[name] = float(np.median(samples))
    return out


def dispatch_rows(rounds: int = 3) -> list[dict]:
    """One-point eager calls with JAX's default asynchronous CPU dispatch against inline dispatch
    (``jax.config.update("jax_cpu_enable_async_dispatch", False)`` before the first JAX call): fresh
    interpreters, alternated, median over ``rounds``. The flag is process-wide and read once, when JAX
    starts its CPU backend, so tissuemech never sets it; a script of many one-point calls may."""
    import json
    import subprocess
    import sys

    code = (
        "import sys, json, jax\n"
        "jax.config.update('jax_cpu_enable_async_dispatch', sys.argv[1] == '1')\n"
        "import tissuemech.reduced\n"
        "from tissuemech.compare.bench.reduced_blastula import one_point_costs\n"
        "print(json.dumps(one_point_costs()))\n"
    )
    got: dict[str, list[dict]] = {"1": [], "0": []}
    for _ in range(rounds):
        for flag, acc in got.items():
            text = subprocess.check_output([sys.executable, "-c", code, flag]).decode()
            acc.append(json.loads(text.strip().splitlines()[-1]))
    us = {f: {name: float(np.median([r[name] for r in runs])) * 1e6 for name in runs[0]} for f, runs in got.items()}
    return [
        dict(
            function=f"{name}, one point",
            n1_eager_us=a,
            n1_inline_dispatch_us=us["0"][name],
            inline_over_async=us["0"][name] / a,
        )
        for name, a in us["1"].items()
    ]


def cli_rows(repeats: int = 3) -> list[dict]:
    """Wall time of the whole ``tissuemech blastula`` process (its defaults, the PNG into a temporary
    folder): cold (an empty compilation cache; matplotlib's font cache where the user's is), warm (the cache
    the cold run wrote) and with the cache switched off (``TISSUEMECH_NO_JIT_CACHE=1``); median and range of
    ``repeats`` runs each, interleaved. The process is the console script's (``console_main``)."""
    import os
    import shutil
    import subprocess
    import sys
    import tempfile

    import matplotlib

    exe = [
        sys.executable,
        "-c",
        "import sys; from tissuemech.compare.cli import console_main as m; sys.exit(m())",
        "blastula",
    ]
    times: dict[str, list[float]] = {"cold": [], "warm": [], "no cache": []}
    with tempfile.TemporaryDirectory() as tmp:
        for _ in range(repeats):
            for kind in times:
                # matplotlib keeps its font cache where it always does (MPLCONFIGDIR; under a fresh
                # XDG_CACHE_HOME it would rebuild it, a once-per-machine cost of 0.3-0.7 s here, not ours)
                env = dict(
                    os.environ, XDG_CACHE_HOME=os.path.join(tmp, "cache"), MPLCONFIGDIR=matplotlib.get_cachedir()
                )
                env.pop("JAX_COMPILATION_CACHE_DIR", None)
                if kind == "cold":
                    shutil.rmtree(os.path.join(env["XDG_CACHE_HOME"], "tissuemech"), ignore_errors=True)
                if kind == "no cache":
                    env["TISSUEMECH_NO_JIT_CACHE"] = "1"
                t0 = time.perf_counter()
                subprocess.run(
                    exe + ["--out", os.path.join(tmp, "b.png")], env=env, cwd=tmp, check=True, capture_output=True
                )
                times[kind].append(time.perf_counter() - t0)
    return import_rows(repeats) + [
        dict(
            function=f"tissuemech blastula (whole process, {kind})",
            points="",
            eager_points_per_s=f"{np.median(v):.2f} s (runs {min(v):.2f}-{max(v):.2f} s)",
        )
        for kind, v in times.items()
    ]


def import_rows(repeats: int = 3) -> list[dict]:
    """Import time of ``ml_dtypes`` and of ``jax`` (which imports it) in fresh processes, median of
    ``repeats``: part of every command's start-up (ml_dtypes 0.7.0 took ~0.57 s here, 0.6.0 ~6 ms,
    hence the pin in pyproject.toml)."""
    import subprocess
    import sys
    from importlib.metadata import version

    code = "import time, numpy; t = time.perf_counter(); import {0}; print(time.perf_counter() - t)"
    rows = []
    for name in ("ml_dtypes", "jax"):
        ts = [
            float(subprocess.run([sys.executable, "-c", code.format(name)], capture_output=True, text=True).stdout)
            for _ in range(repeats)
        ]
        rows.append(
            dict(
                function=f"import {name} {version(name)} (fresh process, numpy already imported)",
                points="",
                eager_points_per_s=f"{1e3 * np.median(ts):.0f} ms",
            )
        )
    return rows


def compile_rows(repeats: int = 3) -> list[dict]:
    """Compile and run time of the blastula's three eager programs (limit point, inverse, pressure) at one point and
    at 1024 points, with XLA's defaults and with the options small eager calls use (``reduced.programs``:
    ``SMALL_CALL_COMPILER_OPTIONS`` up to 1024 points, ``ONE_POINT_COMPILER_OPTIONS`` at one point); one process,
    after a warm-up compilation, the median of ``repeats`` compilations and of 20 runs (the Fig. 4 shell with alpha
    0.2 and lambda_a 1.3 at one point; at 1024 points alpha uniform on 0..0.3 and lambda_a on 1.01..1.5)."""
    import jax

    from tissuemech.reduced import blastula
    from tissuemech.reduced.programs import ONE_POINT_COMPILER_OPTIONS, SMALL_CALL_COMPILER_OPTIONS

    jax.jit(lambda x: x + 1.0).lower(1.0).compile()  # XLA's one-time start-up, not any program's
    rows = []
    for n in (1, 1024):
        rng = np.random.default_rng(0)
        alpha = np.full((), 0.2) if n == 1 else rng.uniform(0.0, 0.3, n)  # one shell, n materials
        params = tuple(np.full(n, v) for v in (A, B, C)) + (alpha,) if n > 1 else np.array([A, B, C, 0.2])
        la = np.full((), 1.3) if n == 1 else rng.uniform(1.01, 1.5, n)
        p = np.asarray(blastula.pressure(la, inner_radius=A, outer_radius=B, C=C, alpha=alpha))
        cores = {
            "limit_point": (blastula._limit_core, (params,)),
            "inner_stretch": (blastula._inverse_core, (p, params)),
            "pressure": (blastula._pressure_core, (la, params)),
        }
        small = ONE_POINT_COMPILER_OPTIONS if n == 1 else SMALL_CALL_COMPILER_OPTIONS
        for name, (core, args) in cores.items():
            row: dict = dict(function=f"{name} program", points=n)
            for label, options in (("default", {}), ("small-call", small)):
                compile_s, runs = [], []
                for _ in range(repeats):
                    jax.clear_caches()  # JAX keeps compiled programs in memory: compile anew each time
                    lowered = core.lower(*args)
                    t0 = time.perf_counter()
                    exe = lowered.compile(dict(options))
                    compile_s.append(time.perf_counter() - t0)
                jax.block_until_ready(exe(*args))
                for _ in range(20):
                    t0 = time.perf_counter()
                    jax.block_until_ready(exe(*args))
                    runs.append(time.perf_counter() - t0)
                row[f"compile_{label}"] = f"{np.median(compile_s):.3f} s"
                row[f"run_{label}"] = f"{1e6 * np.median(runs):.0f} us"
            rows.append(row)
    return rows


# issue 40 item 6: workload-honest rows (random shells, not one geometry)
SHELL_RATIO = (1.03, 1.6)  # B/A of the random shells
SHELL_STRETCH = (1.01, 3.0)  # inner stretch, below each shell's limit stretch (the rising branch)
SHELL_ALPHA = (0.0, 0.3)
PRESSURE_TARGET = 1e7  # points/s, exact pressure on random shells
INVERSE_TARGET = 1e6  # points/s, inner_stretch on random shells
TRANSCENDENTALS = ("exponential", "log", "log-plus-one", "exponential-minus-one", "power", "tanh", "sqrt")


def random_shells(n: int, seed: int = 0) -> dict[str, np.ndarray | float]:
    """n random shells and states on their rising branch: A = 50 um, B/A uniform in ``SHELL_RATIO``, alpha uniform
    in ``SHELL_ALPHA``, C = 200 Pa, inner stretch uniform between 1.01 and min(3, the shell's limit stretch - 1e-3);
    the pressure at each state. States whose pressure the inverse does not bring back to the drawn stretch (a
    shell whose curve dips below a slope of zero between the limit search's grid nodes: ~1e-4 of the draws) are
    redrawn, five rounds at most, then set to the smallest stretch. Keys: A, B, C, alpha, stretch, pressure."""
    from tissuemech.reduced import blastula as bl

    rng = np.random.default_rng(seed)
    A, C = 50e-6, 200.0
    B = A * rng.uniform(*SHELL_RATIO, n)
    al = rng.uniform(*SHELL_ALPHA, n)
    lim = np.asarray(bl.limit_point(inner_radius=A, outer_radius=B, C=C, alpha=al).inner_stretch)
    top = np.where(np.isnan(lim), SHELL_STRETCH[1], np.minimum(SHELL_STRETCH[1], lim - 1e-3))
    la = SHELL_STRETCH[0] + (top - SHELL_STRETCH[0]) * rng.uniform(0.0, 1.0, n)
    for round_ in range(6):
        p = np.asarray(bl.pressure(la, inner_radius=A, outer_radius=B, C=C, alpha=al))
        back, ok = bl.inner_stretch_solve(p, inner_radius=A, outer_radius=B, C=C, alpha=al)
        bad = ~(np.asarray(ok) & (np.abs(np.asarray(back) / la - 1.0) <= 1e-9))
        if not bad.any():
            break
        fresh = SHELL_STRETCH[0] + (top[bad] - SHELL_STRETCH[0]) * rng.uniform(0.0, 1.0, int(bad.sum()))
        la[bad] = fresh if round_ < 5 else SHELL_STRETCH[0]
    return dict(A=A, B=B, C=C, alpha=al, stretch=la, pressure=p)


def transcendentals_per_point(n: int = 4096) -> dict[str, float]:
    """Transcendental calls (and divisions) per point of the compiled one-panel pressure program (the program an
    eager ``pressure`` call runs), counted in XLA's optimised HLO on n random shells: the arithmetic's floor."""
    import re

    import jax

    from tissuemech.reduced import blastula as bl

    sh = random_shells(n, seed=1)
    fn = jax.jit(lambda x, b, a: bl.pressure(x, inner_radius=sh["A"], outer_radius=b, C=sh["C"], alpha=a))
    text = fn.lower(sh["stretch"], sh["B"], sh["alpha"]).compile().as_text()
    ops = TRANSCENDENTALS + ("divide",)
    counts: dict[str, float] = {}
    for m in re.finditer(r"= f64\[([\d,]*)\][^ ]* (" + "|".join(ops) + r")\(", text):
        size = math.prod(int(v) for v in m.group(1).split(",") if v)
        counts[m.group(2)] = counts.get(m.group(2), 0.0) + size / n
    return counts


def exp_seconds(m: int = 4_000_000, repeats: int = 5) -> float:
    """Seconds per float64 exponential of XLA on this machine (jit(exp) over m values, best of ``repeats``)."""
    import jax

    x = jnp.asarray(np.random.default_rng(0).uniform(-2.0, 2.0, m))
    f = jax.jit(jnp.exp)
    jax.block_until_ready(f(x))
    best = np.inf
    for _ in range(repeats):
        t0 = time.perf_counter()
        jax.block_until_ready(f(x))
        best = min(best, time.perf_counter() - t0)
    return best / m


def workload_rows(n: int = 1_000_000, repeats: int = 3, seed: int = 0) -> list[dict]:
    """Issue 40 item 6 on random shells (:func:`random_shells`): eager ``pressure`` and ``inner_stretch`` at n
    points (best of ``repeats``, interleaved), their targets, the pressure program's transcendental calls per point
    and the roofline they set with this machine's measured float64 exponential: points/s <= 1 / (calls x time per
    call), one core."""
    import jax

    from tissuemech.reduced import blastula as bl

    sh = random_shells(n, seed)
    kw = dict(inner_radius=sh["A"], outer_radius=sh["B"], C=sh["C"], alpha=sh["alpha"])
    fwd = lambda: bl.pressure(sh["stretch"], **kw)
    inv = lambda: bl.inner_stretch(sh["pressure"], **kw)
    for f in (fwd, inv):
        jax.block_until_ready(f())
    ts: list[list[float]] = [[], []]
    for _ in range(repeats):
        for i, f in enumerate((fwd, inv)):
            t0 = time.perf_counter()
            jax.block_until_ready(f())
            ts[i].append(time.perf_counter() - t0)
    rate_p, rate_i = n / min(ts[0]), n / min(ts[1])
    err_i = float(np.max(np.abs(np.asarray(inv()) / sh["stretch"] - 1.0)))
    calls = transcendentals_per_point()
    n_tr = sum(v for k, v in calls.items() if k in TRANSCENDENTALS)
    t_exp = exp_seconds()
    roof = 1.0 / (n_tr * t_exp) if n_tr else float("nan")  # nan: no transcendental found in this backend's HLO
    what = f"{n:.0e} random shells (B/A {SHELL_RATIO[0]:g}-{SHELL_RATIO[1]:g}, alpha {SHELL_ALPHA[0]:g}-{SHELL_ALPHA[1]:g})"
    return [
        dict(
            function=f"pressure, {what}",
            points=n,
            eager_points_per_s=rate_p,
            target=f">= {PRESSURE_TARGET:.0e} points/s",
            met="yes" if rate_p >= PRESSURE_TARGET else "NO",
            note=f"roofline {roof:.3g} points/s: {n_tr:.0f} transcendental calls per point ("
            + ", ".join(f"{v:.0f} {k}" for k, v in calls.items())
            + f") x {t_exp * 1e9:.2f} ns per float64 exp (measured, jit(exp) on 4e6 values)",
        ),
        dict(
            function=f"inner_stretch, {what}",
            points=n,
            eager_points_per_s=rate_i,
            target=f">= {INVERSE_TARGET:.0e} points/s",
            met="yes" if rate_i >= INVERSE_TARGET else "NO",
            note=f"{rate_p / rate_i:.1f} pressure calls' time per inverse; max |lambda/drawn - 1| = {err_i:.1e}",
        ),
    ]


def base_fwd(rows_so_far: list[dict]) -> float:
    return rows_so_far[0]["baseline_points_per_s"]


def main(argv: Sequence[str] | None = None) -> list[dict]:
    import tissuemech.reduced  # noqa: F401  (x64)

    ap = argparse.ArgumentParser(prog="python -m tissuemech.compare.bench.reduced_blastula")
    ap.add_argument("--n", type=int, default=1_000_000, help="points per vectorised call")
    ap.add_argument("--baseline", type=int, default=2000, help="points in the scipy quad loop")
    ap.add_argument("--api-only", action="store_true", help="only part 1: eager calls against jit (issue 14)")
    ap.add_argument("--no-cli", action="store_true", help="skip the tissuemech blastula process timings")
    ap.add_argument(
        "--workload-only", action="store_true",
        help="only the workload rows (issue 40 item 6: random shells), e.g. on a GPU machine",
    )  # fmt: skip
    ap.add_argument(
        "--compile", action="store_true",
        help="only the start-up rows (issue 40 item 5): program compile and run times, imports, the whole "
        "tissuemech blastula process cold and warm",
    )  # fmt: skip
    args = ap.parse_args(list(argv) if argv is not None else None)
    if args.compile:
        from tissuemech.compare.bench.common import machine_line

        print(machine_line())
        start = compile_rows()
        print_rows(start)
        cli = cli_rows(5)
        print_rows(cli)
        return start + cli
    if args.workload_only:
        import jax

        from tissuemech.compare.bench.common import machine_line

        print(machine_line())
        print(f"JAX {jax.__version__}, backend {jax.default_backend()}: {jax.devices()[0].device_kind}")
        work = workload_rows(args.n)
        print_rows(work)
        return work
    api = api_rows(args.n) + ([] if args.no_cli else cli_rows())
    print_rows(api)
    api += dispatch_rows()
    print_rows(api[-len(_api_cases(1, np.random.default_rng(1))) :])
    work = workload_rows(args.n)
    print_rows(work)
    api += work
    if args.api_only:
        return api
    r = rows(args.n, args.baseline)
    print_rows(r)
    return api + r


if __name__ == "__main__":
    main()
