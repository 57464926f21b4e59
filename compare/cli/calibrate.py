"""``tissuemech calibrate``: tabulate the FE master curves F_eq and r_mid of the plate scene from static FE runs
(the table the reduced spheroid model ships in ``reduced/data/``; see :mod:`tissuemech.compare.calibrate`)."""

from __future__ import annotations

import argparse
import json
from pathlib import Path
from typing import Any

import numpy as np

from tissuemech.compare import calibrate
from tissuemech.compare.cli.common import Command

__all__ = ["COMMAND", "add_parser", "run", "main"]

DESCRIPTION = "Tabulate the plate scene's FE master curves f = F_eq/(C a0^2) and g = r_mid/a0 from static FE runs."


def _count(text: str) -> int:
    try:
        v = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a whole number, got {text!r}") from None
    if v < 2:
        raise argparse.ArgumentTypeError(f"must be at least 2, got {v}")
    return v


def _workers(text: str) -> int:
    try:
        v = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a whole number of processes, got {text!r}") from None
    if v < 1:
        raise argparse.ArgumentTypeError(f"must be at least 1, got {v}")
    return v


def _fraction(text: str) -> float:
    try:
        v = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a number, got {text!r}") from None
    if not 0 < v < 0.8:
        raise argparse.ArgumentTypeError(f"must be in (0, 0.8), got {v}")
    return v


def _options(ap: argparse.ArgumentParser) -> argparse.ArgumentParser:
    ap.add_argument(
        "--out",
        default="spheroid_master.npz",
        help="table to write (default: %(default)s in the current folder; the shipped table "
        f"{calibrate.DEFAULT_OUT} is replaced only with --install)",
    )
    ap.add_argument("--install", action="store_true", help="write the shipped table reduced/data/spheroid_master.npz")
    ap.add_argument("--store", default=None, help="folder for per-run results (resume)")
    ap.add_argument(
        "--workers",
        type=_workers,
        default=None,
        help="local processes sharing the FE runs (default: every core this process may use)",
    )
    ap.add_argument("--n-x", type=_count, default=37, help="states of the main run, from x = 0 (default: %(default)s)")
    ap.add_argument(
        "--x-max",
        type=_fraction,
        default=0.36,
        help="largest x = delta/(2 a0) of the table, in (0, 0.8) (default: %(default)s)",
    )
    ap.add_argument(
        "--alphas",
        default=",".join(str(a) for a in calibrate.DEFAULT_ALPHAS),
        help="comma list of Fung exponents alpha >= 0 to tabulate (default: %(default)s)",
    )
    ap.add_argument("--mesh", default="2", help="FE level of the table (default: %(default)s)")
    ap.add_argument(
        "--error-mesh", default="3", help="finer level of the independent check ('' to skip; default: %(default)s)"
    )
    ap.add_argument("--check-alphas", default=",".join(str(a) for a in calibrate.CHECK_ALPHAS))
    ap.add_argument("--degree", type=int, default=8, help="degree in sqrt(x) of the small-x basis fit (a check)")
    ap.add_argument(
        "--reference",
        default=None,
        help="JSON of converged (Richardson) reference forces {'alpha A x X': {'reference': f}} (e.g. "
        "tests/data/plate_reference_levels1-3.json): the table's error against it sets metadata model_error_rel = max |error| / 2",
    )
    return ap


def _execute(a: argparse.Namespace, error: Any) -> int:
    try:
        alphas = [float(v) for v in a.alphas.split(",")]
        chk = [float(v) for v in a.check_alphas.split(",")]
    except ValueError:
        error(f"--alphas / --check-alphas must be comma lists of numbers, got {a.alphas!r} / {a.check_alphas!r}")
    if any(not (v >= 0) for v in alphas):
        error(f"--alphas must be >= 0, got {a.alphas!r}")
    if any(c not in alphas for c in chk):
        error(f"--check-alphas must be a subset of --alphas, got {a.check_alphas!r}")
    if a.install:
        a.out = str(calibrate.DEFAULT_OUT)
    lev = lambda v: int(v) if str(v).isdigit() else v  # a fem.spheroid level number or name
    a.mesh, a.error_mesh = lev(a.mesh), lev(a.error_mesh)
    kw = dict(n_x=a.n_x, x_max=a.x_max)
    # the table and its finer-level check in one batch on one pool (the check's long runs first: no idle core at the end)
    tables = [calibrate.plate_table(alphas=alphas, mesh=a.mesh, **kw)]
    if a.error_mesh != "":
        tables.append(calibrate.plate_table(alphas=chk, mesh=a.error_mesh, name="finer-level check", **kw))
    raw, *check = calibrate.build(tables, workers=a.workers, store=a.store)
    _, change = calibrate.smooth(raw, a.degree) if a.degree > 0 else (raw, float("nan"))
    err, err_x = None, None
    if check:
        fine = check[0]
        rows = [alphas.index(c) for c in chk]
        rel = np.abs(raw.f[rows][:, 1:] / fine.f[:, 1:] - 1.0)
        err = float(rel.max())
        err_x = float(raw.x[1:][np.argmax(rel.max(axis=0))])
    meta = dict(
        mesh=a.mesh,
        error_mesh=a.error_mesh or None,
        check_alphas=a.check_alphas,
        discretisation_error_f=err,
        discretisation_error_at_x=err_x,
        interpolation="f = f_Hertz(x) h(sqrt(x), alpha), h natural cubic splines in s = sqrt(x) and alpha",
        sqrt_basis_degree=a.degree,
        sqrt_basis_max_residual_f=change,
        command="tissuemech calibrate " + " ".join(a.words),
        radius_m=calibrate.RADIUS,
        C_Pa=calibrate.C_REF,
        kappa_Pa=calibrate.KAPPA,
        definition="f = F_eq/(C a0^2), g = r_mid/a0, x = delta/(2 a0) (total approach delta)",
    )
    calibrate.write(a.out, raw, meta)
    if a.reference:
        ref_err, ref_at = calibrate.reference_error(a.out, json.loads(Path(a.reference).read_text()))
        # the relative 1-sigma error of F_eq the fits add to their noise model (compare.fit model_error="auto"):
        # the largest error against the converged reference, taken as a 2-sigma bound
        meta.update(
            model_error_rel=ref_err / 2,
            model_error_basis=f"half the largest |f_table / f_ref - 1| = {ref_err:.3g} (at {ref_at}) over the "
            f"converged reference {a.reference}, taken as a 2-sigma bound",
        )
        calibrate.write(a.out, raw, meta)
        print(f"error against the converged reference {a.reference}: {ref_err:.2e} at {ref_at}")
    print(
        f"wrote {a.out}: {len(raw.alpha)} alphas x {len(raw.x)} points (x up to {raw.x[-1]:g}); "
        f"discretisation error of f vs level {a.error_mesh}: {err if err is not None else 'not estimated'}"
        f"{'' if err_x is None else f' (largest at x = {err_x:g})'}; sqrt(x)-basis fit residual {change:.2e}"
    )
    return 0


COMMAND = Command(
    "calibrate", "regenerate the FE master curves of the reduced spheroid", DESCRIPTION, _options, _execute
)
add_parser, run, main = COMMAND.add_parser, COMMAND.run, COMMAND.main

if __name__ == "__main__":
    raise SystemExit(main())
