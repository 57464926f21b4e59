"""``tissuemech blastula``: pressure-stretch table of the seed's Fig. 4 and 5 sets, limit pressures, PNG plot."""

from __future__ import annotations

import argparse
import threading
import time
from argparse import Namespace
from typing import Any

import numpy as np

from tissuemech.compare import cases
from tissuemech.compare.cases import UM
from tissuemech.compare.cli.common import CLIError, figure_path, positive, save_figure

__all__ = ["add_parser", "run", "blastula_curves", "blastula_table", "preload_plotting"]


def add_parser(sub: Any) -> argparse.ArgumentParser:
    """Register ``blastula`` on an argparse subparsers object."""
    b = sub.add_parser(
        "blastula",
        help="pressure-stretch table and plot for the seed's Fig. 4 and Fig. 5 sets",
        description="Inflate a hollow incompressible Fung sphere (inner radius 50 um) by internal "
        "pressure. Prints inner and outer stretch for the Fig. 4 sets (alpha = 1e-5, 0.1, 0.2, 0.3; "
        "outer radius 75 um) and the Fig. 5 sets (outer radius 52, 60, 75 um; alpha = 0.2), and the "
        "limit ('burst') pressure where one exists; writes the pressure-stretch plot to a PNG.",
    )
    b.add_argument("--out", default="blastula.png", help="PNG file for the plot (default: %(default)s)")
    b.add_argument("--C", type=positive(), default=200.0, help="Fung stiffness C in Pa (default: 200)")
    b.add_argument("--inner-radius-um", type=positive(), default=50.0, help="inner radius in um (default: 50)")
    b.add_argument("--max-pressure", type=positive(), default=1000.0, help="largest pressure in Pa (default: 1000)")
    b.add_argument("--step", type=positive(), default=100.0, help="pressure step of the table in Pa (default: 100)")
    b.add_argument("--fem", action="store_true", help="also run the finite-element model (slower) and show its stretch")
    return b


MAX_TABLE_ROWS = 10_000  # the table: max_pressure / step rows at most
ONE_POINT_ROWS = 32  # tables of up to this many rows solve each row by a one-point call (~50 us each)


JIT_CACHE_OPT_OUT = "TISSUEMECH_NO_JIT_CACHE"  # set to 1 to keep the command from writing compiled programs


def enable_jit_cache() -> str | None:
    """Keep JAX's compiled programs between runs: a persistent compilation cache in the user's cache
    folder (``$XDG_CACHE_HOME/tissuemech/jax``, default ``~/.cache/tissuemech/jax``).

    Nothing is done where ``TISSUEMECH_NO_JIT_CACHE`` is set (to anything but ``0`` or empty), where the
    user chose a cache already (``JAX_COMPILATION_CACHE_DIR``), or where the folder cannot be created.
    The cache holds only XLA executables keyed by program, JAX version and machine; deleting the folder
    is always safe. Returns the folder used, or None.
    """
    import os

    if os.environ.get(JIT_CACHE_OPT_OUT, "") not in ("", "0") or os.environ.get("JAX_COMPILATION_CACHE_DIR"):
        return None
    base = os.environ.get("XDG_CACHE_HOME") or os.path.join(os.path.expanduser("~"), ".cache")
    folder = os.path.join(base, "tissuemech", "jax")
    try:
        os.makedirs(folder, exist_ok=True)
    except OSError:
        return None
    if not os.access(folder, os.W_OK | os.X_OK):
        return None
    import jax

    jax.config.update("jax_compilation_cache_dir", folder)
    jax.config.update("jax_persistent_cache_min_compile_time_secs", 0.0)
    jax.config.update("jax_persistent_cache_min_entry_size_bytes", 0)
    return folder


def run(args: Namespace) -> None:
    """Run ``tissuemech blastula`` with parsed arguments."""
    enable_jit_cache()
    rows = args.max_pressure / args.step
    if rows > MAX_TABLE_ROWS:
        raise CLIError(
            f"--step {args.step:g} Pa with --max-pressure {args.max_pressure:g} Pa gives {rows:.3g} table rows "
            f"(at most {MAX_TABLE_ROWS}); use a larger --step"
        )
    blastula_table(args)


def blastula_curves(C: float, inner_radius: float, max_pressure: float, step: float) -> list[dict[str, Any]]:
    """Inner/outer stretch at pressures 0..max_pressure for the seed's Fig. 4 and Fig. 5 sets.

    Returns one dict per set with keys figure, alpha, outer_radius (m), pressure (Pa),
    inner_stretch, outer_stretch (NaN past the limit point), limit (p_max, stretch) or None.
    """
    from tissuemech.reduced import blastula

    pressures = np.arange(0.0, max_pressure * (1 + 1e-12) + 1e-12 * step, step)  # never above max_pressure
    out = []
    for fig, alpha, B in cases.BLASTULA_SETS:
        geo = dict(inner_radius=inner_radius, outer_radius=B)
        lim = blastula.limit_point(**geo, C=C, alpha=alpha)
        ok = pressures < lim.pressure if lim is not None else np.ones_like(pressures, bool)
        if pressures.size <= ONE_POINT_ROWS:
            # one-point calls: the compiled program every one-point call uses (the report's too), which JAX's
            # program cache then holds for a first run of this command after other commands
            la = np.array([float(blastula.inner_stretch(p, **geo, C=C, alpha=alpha)) if k else np.nan
                           for p, k in zip(pressures, ok)])  # fmt: skip
        else:
            # every set solves the full pressure array (0 Pa, lambda_a = 1 exactly, past its limit point), so
            # all sets share one compiled program (a per-set length would compile the inverse once per length)
            la = np.where(
                ok, np.asarray(blastula.inner_stretch(np.where(ok, pressures, 0.0), **geo, C=C, alpha=alpha)), np.nan
            )
        lb = np.where(ok, np.asarray(blastula.outer_stretch(np.where(ok, la, 1.0), **geo)), np.nan)
        out.append(
            dict(
                figure=fig,
                alpha=alpha,
                outer_radius=B,
                pressure=pressures,
                inner_stretch=la,
                outer_stretch=lb,
                limit=lim,
            )
        )
    return out


def _print_blastula(curves: list[dict[str, Any]], inner_radius: float) -> None:
    for fig in ("Fig. 4", "Fig. 5"):
        sets = [c for c in curves if c["figure"] == fig]
        heads = [f"a={c['alpha']:g},B={c['outer_radius'] / UM:g}um" for c in sets]
        print(f"\n{fig}: inner / outer stretch (lambda_a / lambda_b); A = {inner_radius / UM:g} um")
        print(f"{'p [Pa]':>8} " + " ".join(f"{h:>19}" for h in heads))
        for i, p in enumerate(sets[0]["pressure"]):
            cells = []
            for c in sets:
                la, lb = c["inner_stretch"][i], c["outer_stretch"][i]
                cells.append(f"{'burst':>19}" if np.isnan(la) else f"{la:9.5f} / {lb:7.5f}")
            print(f"{p:8.1f} " + " ".join(cells))
    print("\nLimit (burst) pressure under load control:")
    for c in curves:
        lim = c["limit"]
        where = f"a={c['alpha']:g}, B={c['outer_radius'] / UM:g} um"
        if lim is None:
            print(f"  {where}: none (p rises monotonically)")
        else:
            print(f"  {where}: p_max = {lim.pressure:.2f} Pa at lambda_a = {lim.inner_stretch:.4f}")


def preload_plotting() -> threading.Thread:
    """Import matplotlib's pyplot and the scene plots in a background thread (started before the table is
    computed; join it before plotting). The table's first calls compile JAX programs, and XLA compiles without
    holding Python's global lock: on a machine with a free second core the plotting imports (~0.5 s) then overlap
    the compilations instead of following them. An import error is left for the main thread's own import to raise."""

    def load() -> None:
        try:
            import matplotlib.pyplot  # noqa: F401

            import tissuemech.compare.plots.scenes  # noqa: F401
        except Exception:  # raised again, with its traceback, where the main thread imports it
            pass

    thread = threading.Thread(target=load, name="tissuemech-preload-plotting", daemon=True)
    thread.start()
    return thread


def blastula_table(args: Namespace) -> None:
    """``tissuemech blastula``: table of the Fig. 4/5 sets, limit pressures, PNG plot."""
    out = figure_path("--out", args.out)
    b_min = min(B for _, _, B in cases.BLASTULA_SETS) / UM
    if not args.inner_radius_um < b_min:
        raise CLIError(
            f"--inner-radius-um {args.inner_radius_um:g} must be below {b_min:g} um, the smallest outer radius "
            "of the seed's sets (52, 60, 75 um)"
        )
    if args.step > args.max_pressure:
        raise CLIError(f"--step {args.step:g} Pa must not exceed --max-pressure {args.max_pressure:g} Pa")
    A = args.inner_radius_um * UM
    plotting = preload_plotting()
    curves = blastula_curves(args.C, A, args.max_pressure, args.step)
    _print_blastula(curves, A)
    fem_runs = _blastula_fem(curves, args.C, A) if getattr(args, "fem", False) else {}

    plotting.join()
    from tissuemech.compare.plots.scenes import blastula_figure

    fig = blastula_figure(curves, C=args.C, inner_radius=A, max_pressure=args.max_pressure, fem_runs=fem_runs)
    save_figure(fig, out)
    print(f"\nwrote {out}")


def _blastula_fem(curves: list[dict[str, Any]], C: float, A: float) -> dict:
    """Run the FE blastula for every set (load control to the table's pressures below any limit)."""
    from tissuemech.fem import blastula as fem_blastula

    runs = {}
    print("\nFE check (fem.blastula.inflate, default mesh, kappa = 2.2 GPa):")
    for c in curves:
        ok = ~np.isnan(c["inner_stretch"])
        ps = c["pressure"][ok][1:]
        t0 = time.perf_counter()
        run = fem_blastula.inflate(inner_radius=A, outer_radius=c["outer_radius"], C=C, alpha=c["alpha"], pressures=ps)
        wall = time.perf_counter() - t0
        exact = np.interp(run.pressure, c["pressure"][ok], c["inner_stretch"][ok])
        err = np.max(np.abs(run.inner_stretch / exact - 1.0))
        print(
            f"  alpha={c['alpha']:g}, B={c['outer_radius'] / UM:g} um: {len(run.pressure)} steps in "
            f"{wall:.2f} s, max |FE/exact - 1| of inner stretch = {err:.1e}"
        )
        runs[(c["alpha"], c["outer_radius"])] = run
    return runs
