r"""The result tables of the README and the validation page, printed from the commands that make them.

    tissuemech readme-tables [--only hertz,blastula,spheroid,timings] [--check docs/validation.md]

Each table is a markdown block between ``<!-- readme_tables:NAME -->`` and ``<!-- /readme_tables:NAME -->``
lines; paste the printed blocks into README.md (the spheroid block) or docs/validation.md (all of them).
``--check FILE`` recomputes every deterministic block that FILE contains and exits 1 (printing the
difference) when one differs: ``tests/test_compare_readme_tables.py`` runs it in CI. Blocks (all
deterministic: float64 FE and quadrature, printed to 2-3 digits):

* ``hertz``: F_Hertz / F_FE from the shipped calibrated master curve (``studies.checks.hertz_table``);
* ``blastula``: exact neo-Hookean limit pressures, FE error vs the exact shell on the default mesh,
  locking at kappa/C = 1e7, viscoelastic creep FE vs ``reduced.viscoshell`` (``studies.checks.blastula_creep``);
* ``spheroid``: calibrated reduced model vs FE sigma~(t) at the FE step times, Fig. 10, Figs 8-9 and 10
  random cases on the default mesh (``studies.checks.spheroid``, the table ``tissuemech checks`` prints);
* ``timings`` (not checked: machine-dependent): the FE wall times of the runs above, with the
  machine and the date.
"""

from __future__ import annotations

import datetime
import difflib
import platform
import re
import time
import warnings
from collections.abc import Callable, Sequence
from pathlib import Path

import numpy as np

from tissuemech.compare import cases

__all__ = ["BLOCKS", "render", "blocks_in", "check"]

DETERMINISTIC = ("hertz", "blastula", "spheroid")
BLOCKS = (*DETERMINISTIC, "timings")
_TIMINGS: dict[str, float] = {}


def _hertz() -> list[str]:
    from tissuemech.compare.studies.checks import hertz_table

    df = hertz_table()
    cols = list(df.columns)
    head = ["delta/(2 a0) [-]"] + [c.replace("F_Hertz/F_FE ", "") for c in cols[1:]]
    lines = [
        "F_Hertz / F_FE (FE-calibrated master curve, `tissuemech checks --skip blastula,creep,spheroid`):",
        "",
        "| " + " | ".join(head) + " |",
        "|" + "---|" * len(head),
    ]
    for row in df.itertuples(index=False):
        lines.append(f"| {row[0]:g} | " + " | ".join(f"{v:.3f}" for v in row[1:]) + " |")
    return lines


def _blastula() -> list[str]:
    from tissuemech.compare.reference import shell_inner_stretch
    from tissuemech.compare.studies.checks import blastula_creep
    from tissuemech.fem.blastula import LockingWarning, inflate
    from tissuemech.fem.newton import NewtonError
    from tissuemech.reduced import blastula as bl

    A, C = cases.BLASTULA_INNER_RADIUS, cases.BLASTULA_C
    B, alpha = cases.FIG3["outer_radius"], cases.FIG3["alpha"]
    ps = cases.ACCURACY_PRESSURES
    t0 = time.perf_counter()
    r = inflate(inner_radius=A, outer_radius=B, C=C, alpha=alpha, pressures=list(ps))
    _TIMINGS["FE blastula, 3 pressures, default mesh"] = time.perf_counter() - t0
    ex = np.array([shell_inner_stretch(p, outer_radius=B, alpha=alpha) for p in ps])
    err = np.abs(r.inner_stretch / ex - 1)
    lim = {
        b: bl.limit_point(inner_radius=A, outer_radius=b * cases.UM, C=C, alpha=cases.NEO_HOOKEAN_ALPHA)
        for b in cases.FIG5_OUTER_UM
    }
    lock = {}
    ex_lock = np.array([shell_inner_stretch(p, outer_radius=B, alpha=alpha) for p in (250.0, 500.0)])
    for form in ("mixed", "displacement"):
        try:
            with warnings.catch_warnings():  # the locking row runs the locking formulation on purpose
                warnings.simplefilter("ignore", LockingWarning)
                rk = inflate(
                    inner_radius=A,
                    outer_radius=B,
                    C=C,
                    alpha=alpha,
                    pressures=[250.0, 500.0],
                    kappa=1e7 * C,
                    formulation=form,
                )
            lock[form] = f"{np.max(np.abs(rk.inner_stretch / ex_lock - 1)):.1e}"
        except NewtonError:
            lock[form] = "does not converge"
    t0 = time.perf_counter()
    cr = blastula_creep().iloc[0]
    _TIMINGS["FE blastula creep (issue 5 case), default mesh"] = time.perf_counter() - t0
    lims = "; ".join(
        f"B = {b:g} um: {float(v[0]):.2f} Pa at lambda_a = {float(v[1]):.4f}" for b, v in lim.items() if v is not None
    )
    return [
        "| what | result |",
        "|---|---|",
        f"| neo-Hookean (alpha = 1e-5) limit pressure, exact | {lims} |",
        "| FE Q2/P1 u-p, default mesh, kappa = 2.2 GPa, alpha = 0.2, B = 75 um: inner-stretch error vs exact "
        f"at {' / '.join(f'{p:g}' for p in ps)} Pa | {' / '.join(f'{e:.1e}' for e in err)} |",
        f"| locking at kappa/C = 1e7 (default mesh, 250 and 500 Pa) | mixed u-p {lock['mixed']}; displacement-only "
        f"{lock['displacement']} |",
        "| viscoelastic creep, FE shell vs reduced `viscoshell` (alpha 0.2, beta 0.5, tau 100 s, 300 Pa in 1 s, held "
        f"600 s) | max inner-stretch deviation {cr['max dev. history [-]']:.1e} ({int(cr['FE steps'])} FE steps) |",
    ]


def _spheroid() -> list[str]:
    from tissuemech.compare.studies.checks import spheroid

    t0 = time.perf_counter()
    d = spheroid()
    _TIMINGS["FE spheroid, 12 checks cases, default mesh"] = time.perf_counter() - t0
    after, during = d["max dev. after ramp [-]"], d["max dev. during ramp [-]"]
    hz = d["Hertz: max dev. after ramp [-]"]
    seed = d[d.case.isin(list(cases.SPHEROID_CHECK_CASES))]
    return [
        'Calibrated reduced model (`equilibrium="fem"`) vs FE sigma~(t), compared at the FE step times '
        "(`tissuemech checks`, default mesh):",
        "",
        "| cases | max deviation after the ramp | max deviation during the ramp | Hertz law, after the ramp |",
        "|---|---|---|---|",
        f"| Fig. 10 and Figs 8-9 | {100 * seed['max dev. after ramp [-]'].max():.2f} % | "
        f"{100 * seed['max dev. during ramp [-]'].max():.2f} % | "
        f"{100 * seed['Hertz: max dev. after ramp [-]'].min():.0f}-{100 * seed['Hertz: max dev. after ramp [-]'].max():.0f} % |",
        f"| all {len(d)} (seed + {len(d) - len(seed)} random) | {100 * after.max():.2f} % | {100 * during.max():.2f} % | "
        f"{100 * hz.min():.0f}-{100 * hz.max():.0f} % |",
    ]


def _timings() -> list[str]:
    stamp = (
        f"{platform.machine()} / {platform.system()}, {platform.python_version()}, {datetime.date.today().isoformat()}"
    )
    lines = [f"Wall times of the runs above (machine-dependent, not checked): {stamp}", ""]
    lines += [f"* {k}: {v:.2f} s" for k, v in _TIMINGS.items()] or ["* (no runs in this call)"]
    return lines


_MAKERS: dict[str, Callable[[], list[str]]] = dict(
    hertz=_hertz, blastula=_blastula, spheroid=_spheroid, timings=_timings
)


def render(name: str) -> str:
    """The markdown block ``name`` (one of ``BLOCKS``), with its begin / end markers."""
    if name not in _MAKERS:
        raise ValueError(f"unknown README table {name!r}; choose from {', '.join(BLOCKS)}")
    body = "\n".join(_MAKERS[name]())
    return f"<!-- readme_tables:{name} -->\n{body}\n<!-- /readme_tables:{name} -->"


def blocks_in(text: str) -> dict[str, str]:
    """{name: block text with markers} of every generated block in a markdown text."""
    pat = re.compile(r"<!-- readme_tables:(\w+) -->\n.*?\n<!-- /readme_tables:\1 -->", re.S)
    return {m.group(1): m.group(0) for m in pat.finditer(text)}


def check(path: str | Path, names: Sequence[str] | None = None) -> list[str]:
    """Recompute the deterministic blocks found in ``path``; returns a unified diff per differing block."""
    found = blocks_in(Path(path).read_text())
    diffs = []
    for name in names or DETERMINISTIC:
        if name not in found or name not in DETERMINISTIC:
            continue
        new = render(name)
        if new != found[name]:
            diffs.append(
                "\n".join(
                    difflib.unified_diff(found[name].splitlines(), new.splitlines(), "README", "command", lineterm="")
                )
            )
    return diffs


if __name__ == "__main__":  # kept: the same as tissuemech readme-tables
    from tissuemech.compare.cli.readme_tables import main

    raise SystemExit(main())
