"""``tissuemech checks``: reduced-vs-FE tables (blastula stretch, creep, spheroid stress history, Hertz vs FE);
the work is done by :mod:`tissuemech.compare.studies.checks`."""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import Any

import pandas as pd

import tissuemech.compare.studies.checks as lib
from tissuemech.compare.cli.common import Command

__all__ = ["COMMAND", "add_parser", "run", "main"]

DESCRIPTION = (lib.__doc__ or "").strip().split("\n")[0]


def _count(text: str) -> int:
    try:
        v = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a whole number, got {text!r}") from None
    if v < 0:
        raise argparse.ArgumentTypeError(f"must not be negative, got {v}")
    return v


def _spheroid_mesh(text: str) -> str | int:
    from tissuemech.fem.spheroid import LEVELS, MESHES

    if text.isdigit() and int(text) in LEVELS:
        return int(text)
    if text in MESHES:
        return text
    raise argparse.ArgumentTypeError(
        f"unknown mesh {text!r}; choose {', '.join(MESHES)} or a level {min(LEVELS)}..{max(LEVELS)}"
    )


def _skip_list(text: str) -> set[str]:
    names = set(filter(None, (v.strip() for v in text.split(","))))
    bad = sorted(names - set(lib.TABLE_NAMES))
    if bad:
        raise argparse.ArgumentTypeError(f"unknown table(s) {', '.join(bad)}; choose from {', '.join(lib.TABLE_NAMES)}")
    return names


def _options(ap: argparse.ArgumentParser) -> argparse.ArgumentParser:
    ap.add_argument("--spheroid-random", type=_count, default=10, help="random spheroid cases (default: %(default)s)")
    ap.add_argument("--blastula-random", type=_count, default=10, help="random blastula cases (default: %(default)s)")
    ap.add_argument(
        "--mesh",
        type=_spheroid_mesh,
        default="default",
        help="FE mesh for the spheroid checks: coarse, default, fine or a level 0..4 (default: %(default)s)",
    )
    ap.add_argument("--out", default=None, help="folder for CSV tables")
    ap.add_argument("--fit", action="store_true", help="also fit FE-made synthetic records (SYNTHETIC data)")
    ap.add_argument("--skip", type=_skip_list, default=set(), help="comma list of: " + ",".join(lib.TABLE_NAMES))
    return ap


def _execute(a: argparse.Namespace, error: Any) -> int:
    skip = a.skip
    if a.out and Path(a.out).exists() and not Path(a.out).is_dir():
        error(f"--out {a.out!r} exists and is a file, not a folder")
    pd.set_option("display.width", 200)
    pd.set_option("display.max_columns", 20)
    tables = {}
    if "hertz" not in skip:
        tables["hertz"] = lib.hertz_table()
    if "blastula" not in skip:
        tables["blastula"] = lib.blastula(n_random=a.blastula_random)
    if "creep" not in skip:
        tables["creep"] = lib.blastula_creep()
    if "spheroid" not in skip:
        tables["spheroid"] = lib.spheroid(n_random=a.spheroid_random, mesh=a.mesh)
    if a.fit:
        tables["fit"], fits = lib.fit_demo()
        for label, res in fits.items():
            print(f"\n== fit to SYNTHETIC FE records ({label}, 1 % noise) ==\n{res.summary()}")
    for name, df in tables.items():
        print(f"\n== {name} ==")
        print(df.to_string(index=False, float_format=lambda v: f"{v:.4g}"))
    if "blastula" in tables:
        print(f"\nblastula: max relative deviation FE vs exact {tables['blastula']['rel. deviation [-]'].max():.2e}")
    if "creep" in tables:
        d = tables["creep"]
        print(
            f"blastula creep: max |lambda_FE/lambda_reduced - 1| {d['max dev. history [-]'].max():.2e} over the history "
            f"(ramp {d['max dev. during ramp [-]'].max():.2e}, hold {d['max dev. during hold [-]'].max():.2e}), "
            f"FE {d['FE wall [s]'].sum():.2f} s, {d['FE steps'].sum()} steps"
        )
    if "spheroid" in tables:
        d = tables["spheroid"]
        print(
            f"spheroid: max deviation after the ramp {d['max dev. after ramp [-]'].max():.2%}, "
            f"during the ramp {d['max dev. during ramp [-]'].max():.2%} (calibrated reduced vs FE, mesh {a.mesh})"
        )
    if a.out:
        Path(a.out).mkdir(parents=True, exist_ok=True)
        for name, df in tables.items():
            df.to_csv(Path(a.out) / f"checks_{name}.csv", index=False)
        print(f"wrote {a.out}/checks_*.csv")
    return 0


COMMAND = Command(
    "checks",
    "reduced-vs-FE tables: blastula stretch, creep, spheroid stress history, Hertz vs FE",
    DESCRIPTION,
    _options,
    _execute,
)
add_parser, run, main = COMMAND.add_parser, COMMAND.run, COMMAND.main

if __name__ == "__main__":
    raise SystemExit(main())
