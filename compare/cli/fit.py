r"""``tissuemech fit``: fit the spheroid model to your own compression-relaxation measurements.

    tissuemech fit DATA.csv [DATA2.csv ...] --radius-um R --displacement-um D [D2 ...] --ramp-time T
                   [--quantity auto|stress|force] [--equilibrium fem|hertz] [--branches N]
                   [--model-error auto|X] [--protocol auto|relaxation|creep|history] [--force-un F] [--out DIR]
                   [--fit-surface-tension] [--surface-tension G] [--profile R1,R2,R3 | PROFILE.csv] [--profile-sd S]
                   [--profile-force-un F]

The files: one CSV per compression level, time in s and nominal stress in Pa or plate force in N, an optional
header naming the columns with units, ``#`` comments (:mod:`tissuemech.compare.fit.records` has the format).
Creep and measured-history files carry ``time, approach, force`` columns (e.g. ``time [min], approach [um],
force [uN]``); ``--protocol`` says what each records, or (auto) it is inferred from the columns and the force and
printed; they are fitted with :func:`tissuemech.compare.fit.protocols.records_fit`, mixed with relaxation files
if any, and ``fit-records.csv`` holds each record's data, model and residual.

Output: the parameter table with 95 % intervals and the identifiability report (stdout), and in
``--out`` (default ``fit-results``): ``fit.json`` (everything: parameters, intervals and their kind,
noise, covariance, identifiability, the inputs) and ``fit.png`` (data, model and residuals).
A malformed file gives one line naming the file and the line (exit code 2).

Surface tension (``--fit-surface-tension``, or ``--surface-tension G``: its starting value in N/m): relaxation records
at two or more compression levels are fitted with the elastocapillary model (:func:`tissuemech.compare.fit.tension.
tension_relaxation`: C, gamma, alpha, the branches); ``--profile R1,R2,R3`` (um: the meridional radius of curvature at
the equator, the equatorial radius and the contact radius, measured at the end of the last record's hold; or a CSV
whose rows are R1, R2, R3 in um, averaged, their sd of the mean the uncertainty unless ``--profile-sd`` says it) adds
the classic formula gamma = F / (pi R3^2 (1/R1 + 1/R2)) to the likelihood with its propagated uncertainty. Without
data files, ``--profile`` with ``--profile-force-un`` gives the formula's gamma and its error alone.
"""

from __future__ import annotations

import argparse
import json
from collections.abc import Sequence
from pathlib import Path
from typing import Any

from tissuemech.compare.cli.common import nonnegative, output_folder, positive, save_figure
from tissuemech.compare.fit.records import UM

__all__ = ["add_parser", "run"]

_positive = positive()


def _model_error(text: str):
    if text == "auto":
        return "auto"
    try:
        return nonnegative(text)
    except argparse.ArgumentTypeError as err:
        raise argparse.ArgumentTypeError(f"expected 'auto' or a relative error such as 0.005 ({err})") from None


def add_parser(subparsers: Any) -> argparse.ArgumentParser:
    """Register ``tissuemech fit`` on an argparse subparsers object."""
    f = subparsers.add_parser(
        "fit",
        help="fit C, alpha, beta, tau with 95 %% intervals to your compression-relaxation CSV files",
        description="Fit the lumped generalized-Maxwell spheroid model (FE-calibrated equilibrium law) to "
        "measured compression-relaxation records, one CSV per compression level: time (s) and nominal "
        "stress (Pa) or plate force (N); a header line may name the columns with units, '#' comments. Prints the parameters with 95 % "
        "intervals and the identifiability report; writes fit.json and fit.png to --out.",
    )
    f.add_argument(
        "files", nargs="*", metavar="DATA.csv", help="one CSV file per compression level (none: --profile alone)"
    )
    f.add_argument("--radius-um", type=_positive, required=True, help="undeformed spheroid radius a0 in um")
    f.add_argument(
        "--displacement-um",
        type=_positive,
        nargs="+",
        action="extend",  # a repeated option adds its values (it kept only the last)
        default=None,
        help="total plate approach in um: one for all files or one per file (default: '# displacement_um:' in each file)",
    )
    f.add_argument("--ramp-time", type=_positive, required=True, help="duration of the loading ramp in s")
    f.add_argument(
        "--quantity",
        choices=["auto", "stress", "force"],
        default="auto",
        help="second column: nominal stress in Pa or force in N (auto: from the header; default %(default)s)",
    )
    f.add_argument("--equilibrium", choices=["fem", "hertz"], default="fem", help="equilibrium law (default: fem)")
    f.add_argument("--branches", type=int, default=1, help="number of Maxwell branches (default: 1)")
    f.add_argument(
        "--model-error",
        type=_model_error,
        default="auto",
        help="relative 1-sigma model error of the force added to the noise model ('auto': the FE table's estimate)",
    )
    f.add_argument(
        "--misfit",
        type=nonnegative,
        default=0.0,
        help="lower bound of the model's smooth misfit (relative RMS, e.g. 0.002) the intervals allow for; the "
        "residuals show only the part the parameters cannot absorb (default 0: estimated from them alone)",
    )
    f.add_argument(
        "--protocol",
        choices=["auto", "relaxation", "creep", "history"],
        default="auto",
        help="what each file records: relaxation (time, stress or force; the displacement is held), creep (time, "
        "approach, force: the held force drives the model, the approach is fitted), history (time, approach, force: "
        "the measured approach drives the model, the force is fitted); auto (default): relaxation for files without "
        "an approach column, else creep when the force is held after the ramp, history otherwise (printed)",
    )
    f.add_argument(
        "--force-un",
        type=_positive,
        default=None,
        help="the held force of creep files in uN (default: the median of each file's force column over the hold)",
    )
    f.add_argument(
        "--model",
        choices=["reduced", "fe"],
        default="reduced",
        help="the model fitted: reduced (default: the lumped model on the FE-calibrated table, milliseconds) or fe "
        "(the finite elements themselves, compress(gradient=True) per record and iteration: beyond the table, alpha > "
        "1.5 or deep compression, or as a check of a reduced fit; relaxation records of nominal stress only)",
    )
    f.add_argument(
        "--mesh",
        default="default",
        help="--model fe: the FE mesh level (coarse, default, fine, ...; default %(default)s)",
    )
    f.add_argument(
        "--contact",
        choices=["nodal", "fitted"],
        default="nodal",
        help="--model fe: node-by-node contact on that mesh (default, ~2x faster) or every step on its "
        "contact-edge-fitted mesh (no edge quantisation in the force)",
    )
    f.add_argument(
        "--initial",
        nargs="+",
        metavar="NAME=VALUE",
        default=None,
        help="--model fe: starting values in SI (C=150 alpha=1.2 beta=0.4 tau=200; every parameter); default: the "
        "reduced fit's estimate, or the rough guess from the curves where the reduced model cannot fit the records",
    )
    f.add_argument(
        "--fit-surface-tension",
        action="store_true",
        help="fit the tissue surface tension gamma too (elastocapillary model; relaxation records, two or more levels)",
    )
    f.add_argument(
        "--surface-tension",
        type=_positive,
        default=None,
        help="starting value of gamma in N/m (e.g. 0.006); implies --fit-surface-tension",
    )
    f.add_argument(
        "--profile",
        default=None,
        help="profile measurement R1,R2,R3 in um (meridional radius at the equator, equatorial radius, contact "
        "radius) at the end of the last record, or a CSV of such rows (um); enters the gamma fit via the classic "
        "formula F / (pi R3^2 (1/R1 + 1/R2))",
    )
    f.add_argument(
        "--profile-sd", type=_positive, default=None, help="1-sigma uncertainty of each profile radius in um"
    )
    f.add_argument(
        "--profile-force-un",
        type=_positive,
        default=None,
        help="plate force in uN at the profile's time (with --profile and no data files: the formula's gamma alone)",
    )
    f.add_argument("--alpha", type=nonnegative, default=None, help="gamma fit: fix the Fung alpha (default: fitted)")
    f.add_argument("--out", default="fit-results", help="folder for fit.json and fit.png (default: %(default)s)")
    f.add_argument("--no-figure", action="store_true", help="skip fit.png")
    return f


def run(args: argparse.Namespace) -> None:
    """Carry out ``tissuemech fit`` (errors: ValueError with a one-line message)."""
    from tissuemech.compare import fit
    from tissuemech.compare.cli.blastula import enable_jit_cache

    enable_jit_cache()  # compiled residuals kept between runs (the compile is most of a dense record's time)
    if args.branches < 1:
        raise ValueError(f"--branches must be at least 1; got {args.branches}")
    output_folder("--out", args.out)  # before the fit
    radius = args.radius_um * UM
    tension = args.fit_surface_tension or args.surface_tension is not None or args.profile is not None
    if not args.files and not (args.profile is not None and args.profile_force_un is not None):
        raise ValueError(
            "give at least one DATA.csv file (or --profile R1,R2,R3 with --profile-force-un F for the classic "
            "formula's gamma alone)"
        )
    if tension:
        return _run_tension(args, radius)
    if args.model == "fe":
        return _run_fe(args, radius)
    if args.initial is not None:
        raise ValueError("--initial is for --model fe (the reduced fit finds its own start)")
    if args.protocol != "relaxation" and any(_has_approach(p) for p in args.files):
        return _run_protocols(args, radius)
    if args.protocol in ("creep", "history"):
        raise ValueError(
            f"--protocol {args.protocol} needs files with time, approach and force columns (a header such as "
            "'time [s], approach [um], force [uN]'); none of the files names approach and force columns"
        )
    disps = None if args.displacement_um is None else [d * UM for d in args.displacement_um]
    recs, forces = fit.load_records(
        list(args.files), radius=radius, displacements=disps, ramp_time=args.ramp_time, quantity=args.quantity
    )
    if any(forces) and not all(forces):
        raise ValueError("mix of force (N) and stress (Pa) files: give all records as the same quantity")
    midplane = "incompressible" if all(forces) else ("fem" if args.equilibrium == "fem" else "incompressible")
    model = fit.incompressible_model() if all(forces) else None
    res = fit.relaxation(recs, model=model, **_options(args, radius))
    out = _write_json(
        res,
        args,
        {
            "files": [str(f) for f in args.files],
            "radius_m": radius,
            "displacement_m": [r[2] for r in recs],
            "ramp_time_s": args.ramp_time,
            "quantity": ["force_N" if f else "stress_Pa" for f in forces],
            "equilibrium": args.equilibrium,
            "midplane": midplane,
            "n_points": [int(r[0].size) for r in recs],
            "misfit_rel": args.misfit,
        },
    )
    written = [str(out / "fit.json")]
    if not args.no_figure:
        from tissuemech.compare.plots.fit import fit_figure

        fig = fit_figure(
            recs, res, radius=radius, ramp_time=args.ramp_time, equilibrium=args.equilibrium, midplane=midplane
        )
        save_figure(fig, str(out / "fit.png"))
        written.append(str(out / "fit.png"))
    print("wrote " + ", ".join(written))


def _options(args: argparse.Namespace, radius: float) -> dict:
    """The fit's keywords from the command line (SI: radius in m, ramp time in s)."""
    return dict(
        radius=radius,
        ramp_time=args.ramp_time,
        n_branches=args.branches,
        equilibrium=args.equilibrium,
        model_error=args.model_error,
        misfit=args.misfit,
    )


def _write_json(res, args: argparse.Namespace, inputs: dict) -> Path:
    """Print the fit's summary and write ``fit.json`` (the result and its ``inputs``) into ``--out``; its folder."""
    print(res.summary())
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    d = res.to_dict()
    d["inputs"] = inputs
    (out / "fit.json").write_text(json.dumps(d, indent=1))
    return out


def _has_approach(path: str) -> bool:
    """True for a creep / measured-history file: its header names an approach and a force column."""
    from tissuemech.compare.fit.records import header_columns, read_table

    cols = header_columns(read_table(path))
    return "approach" in cols and "force" in cols


def _run_protocols(args: argparse.Namespace, radius: float) -> None:
    """``tissuemech fit`` on creep / measured-history files (mixed with relaxation files, if any)."""
    import numpy as np

    from tissuemech.compare import fit
    from tissuemech.compare.fit import protocols

    recs, kinds = [], []
    relax = [p for p in args.files if not _has_approach(p)]
    disps = None if args.displacement_um is None else [d * UM for d in args.displacement_um]
    if relax:
        rr, forces = fit.load_records(relax, radius=radius, displacements=disps, ramp_time=args.ramp_time)
        if any(forces):
            raise ValueError(
                "relaxation files of forces (N) cannot be mixed with creep or history files: give them as nominal "
                "stress (Pa), or record the approach too ('time, approach, force' columns) and fit them as histories"
            )
        by_path = dict(zip(relax, rr))
    force = None if args.force_un is None else args.force_un * UM
    for path in args.files:
        if path in relax:
            recs.append(fit.Record(*by_path[path]))
            kinds.append("relaxation")
            print(f"{path}: relaxation (no approach and force columns)")
            continue
        asked = "auto" if args.protocol == "auto" else args.protocol
        rec, kind, why = protocols.read_protocol_csv(path, protocol=asked, ramp_time=args.ramp_time, force=force)
        print(f"{path}: {why}")
        recs.append(rec)
        kinds.append(kind)
    res = protocols.records_fit(recs, **_options(args, radius))
    out = _write_json(
        res,
        args,
        {
            "files": [str(f) for f in args.files],
            "protocols": kinds,
            "radius_m": radius,
            "ramp_time_s": args.ramp_time,
            "equilibrium": args.equilibrium,
            "n_points": [int(np.size(r[0])) for r in recs],
            "misfit_rel": args.misfit,
        },
    )
    # data, model and residual of every record, in the records' units
    lines = ["record,protocol,time [s],observed,model,residual,unit"]
    kw = dict(radius=radius, ramp_time=args.ramp_time, equilibrium=args.equilibrium)
    for j, (rec, kind, unit) in enumerate(zip(recs, kinds, res.units)):
        y = np.asarray(rec[2] if kind == "history" else rec[1])
        m = protocols.predict(rec, res.params, **kw) * (res.model_error_factors[j] if res.model_error_factors else 1.0)
        lines += [f"{j + 1},{kind},{t:.9g},{a:.9g},{b:.9g},{a - b:.9g},{unit}" for t, a, b in zip(rec[0], y, m)]
        rms = float(np.sqrt(np.mean((y - m) ** 2)))
        rel = 100 * rms / np.max(np.abs(y))
        print(f"record {j + 1} ({kind}, {args.files[j]}): RMS residual {rms:.3g} {unit} ({rel:.2g} % of the peak)")
    (out / "fit-records.csv").write_text("\n".join(lines) + "\n")
    written = [str(out / "fit.json"), str(out / "fit-records.csv")]
    if not args.no_figure:
        from tissuemech.compare.plots.fit import protocol_figure

        fig = protocol_figure(recs, res, radius=radius, ramp_time=args.ramp_time, equilibrium=args.equilibrium)
        save_figure(fig, str(out / "fit.png"))
        written.append(str(out / "fit.png"))
    print("wrote " + ", ".join(written))


def _initial(args: argparse.Namespace, names: Sequence[str]) -> dict[str, float] | None:
    """``--initial NAME=VALUE ...`` as a dict (SI), or None when not given."""
    if args.initial is None:
        return None
    out = {}
    for item in args.initial:
        name, sep, value = item.partition("=")
        try:
            out[name.strip()] = float(value) if sep else float("nan")
        except ValueError:
            raise ValueError(f"--initial {item!r}: expected NAME=VALUE with a number, e.g. C=150") from None
        if not sep:
            raise ValueError(f"--initial {item!r}: expected NAME=VALUE, e.g. C=150")
    if set(out) != set(names):
        raise ValueError(
            f"--initial must give every parameter ({', '.join(names)}); missing {sorted(set(names) - set(out))}, "
            f"unknown {sorted(set(out) - set(names))}"
        )
    return out


def _run_fe(args: argparse.Namespace, radius: float) -> None:
    """``tissuemech fit --model fe``: :func:`tissuemech.compare.fit.fe_relaxation` on relaxation records of nominal
    stress, started from ``--initial`` or the reduced fit (fit.json, fit.png, progress lines as the FE runs)."""
    import logging
    import sys

    import numpy as np

    from tissuemech.compare import fit

    unsupported = []
    if args.protocol in ("creep", "history") or any(_has_approach(p) for p in args.files):
        unsupported.append("creep and measured-history records (files with approach and force columns)")
    if args.equilibrium != "fem":
        unsupported.append(f"--equilibrium {args.equilibrium} (the FE has no equilibrium law to choose)")
    if args.model_error != "auto" or args.misfit > 0:
        unsupported.append("--model-error and --misfit (the FE is taken as exact, the noise as white)")
    if unsupported:
        raise ValueError(
            "--model fe does not support " + "; ".join(unsupported) + " yet: use --model reduced for those"
        )
    disps = None if args.displacement_um is None else [d * UM for d in args.displacement_um]
    recs, forces = fit.load_records(
        list(args.files), radius=radius, displacements=disps, ramp_time=args.ramp_time, quantity=args.quantity
    )
    if any(forces):
        raise ValueError(
            "--model fe fits nominal stress (Pa) records; the plate-force files "
            f"{[f for f, k in zip(args.files, forces) if k]} are not supported yet: convert them to nominal stress "
            "or use --model reduced"
        )
    names = fit.parameter_names(args.branches)
    initial = _initial(args, names)
    if initial is None:
        try:
            start = fit.relaxation(recs, intervals="wald", **_options(args, radius))
            initial = dict(start.params)
            how = "the reduced fit's estimate"
        except (ValueError, RuntimeError) as err:
            guess = fit.initial_guess([fit.Record(*r) for r in recs], radius, args.ramp_time, args.branches)
            initial = dict(zip(names, map(float, guess)))
            how = f"the rough guess from the curves (the reduced fit cannot: {str(err).splitlines()[0]})"
        print("starting from " + how + ": " + ", ".join(f"{n} = {v:.4g}" for n, v in initial.items()))
    # progress: one line per FE evaluation (on stderr, as the command's other progress lines)
    logger = logging.getLogger("tissuemech.compare.fit.fe")
    handler = None
    if not logger.isEnabledFor(logging.INFO) or not logging.getLogger().handlers:
        handler = logging.StreamHandler(sys.stderr)
        handler.setFormatter(logging.Formatter("%(message)s"))
        logger.addHandler(handler)
        old_level = logger.level
        logger.setLevel(logging.INFO)
    try:
        res = fit.fe_relaxation(
            recs, radius=radius, ramp_time=args.ramp_time, initial=initial, n_branches=args.branches,
            mesh=args.mesh, contact=args.contact, progress=True,
        )  # fmt: skip
    finally:
        if handler is not None:
            logger.removeHandler(handler)
            logger.setLevel(old_level)
    out = _write_json(
        res,
        args,
        {
            "files": [str(f) for f in args.files],
            "model": "fe",
            "mesh": args.mesh,
            "contact": args.contact,
            "initial": initial,
            "radius_m": radius,
            "displacement_m": [r[2] for r in recs],
            "ramp_time_s": args.ramp_time,
            "quantity": ["stress_Pa" for _ in recs],
            "n_points": [int(np.size(r[0])) for r in recs],
        },
    )
    written = [str(out / "fit.json")]
    if not args.no_figure:
        from tissuemech.compare.plots.fit import fe_fit_figure

        save_figure(fe_fit_figure(recs, res, ramp_time=args.ramp_time), str(out / "fit.png"))
        written.append(str(out / "fit.png"))
    print("wrote " + ", ".join(written))


def _profile(args: argparse.Namespace) -> tuple[float, float, float, float]:
    """(R1, R2, R3, sd) in m from ``--profile`` (three numbers or a CSV of rows) and ``--profile-sd`` (um)."""
    import numpy as np

    text = args.profile
    if Path(text).is_file():
        from tissuemech.compare.fit.records import read_table

        rows = read_table(text).values
        if rows.ndim != 2 or rows.shape[1] < 3 or rows.shape[0] < 1:
            raise ValueError(f"--profile {text}: expected rows of R1, R2, R3 in um")
        rows = rows[:, :3]
    else:
        try:
            rows = np.array([[float(v) for v in text.split(",")]])
        except ValueError:
            raise ValueError(f"--profile {text!r}: expected R1,R2,R3 in um (e.g. 160,190,95) or a CSV file") from None
        if rows.shape != (1, 3):
            raise ValueError(f"--profile {text!r}: expected three radii R1,R2,R3 in um")
    if not np.all(np.isfinite(rows)) or np.any(rows <= 0):
        raise ValueError(f"--profile: the radii R1, R2, R3 must be positive (um); got {rows.tolist()}")
    R = rows.mean(axis=0)
    if args.profile_sd is not None:
        sd = args.profile_sd
    elif rows.shape[0] >= 2:
        sd = float(np.max(rows.std(axis=0, ddof=1)) / np.sqrt(rows.shape[0]))
    else:
        raise ValueError(
            "--profile with one measurement needs --profile-sd (the 1-sigma uncertainty of each radius, um)"
        )
    return float(R[0] * UM), float(R[1] * UM), float(R[2] * UM), float(sd * UM)


def _run_tension(args: argparse.Namespace, radius: float) -> None:
    """``tissuemech fit --fit-surface-tension`` / ``--profile``: gamma from relaxation records and/or a profile."""
    import math

    from scipy import stats

    from tissuemech.compare import fit
    from tissuemech.compare.fit import tension

    if args.model == "fe" or args.protocol in ("creep", "history"):
        raise ValueError("the surface-tension fit takes relaxation records with --model reduced")
    prof = None if args.profile is None else _profile(args)
    if not args.files:  # the classic formula alone
        assert prof is not None
        F = args.profile_force_un * UM
        g, sd = tension.formula_tension(F, *prof[:3], radius_sd=prof[3])
        z = float(stats.norm.ppf(0.975))
        d = dict(
            params={"gamma": g},
            intervals={"gamma": [g - z * sd, g + z * sd]},
            sd={"gamma": sd},
            method="classic formula gamma = F / (pi R3^2 (1/R1 + 1/R2)): exact for a liquid drop at rest; over-states "
            "gamma while the aggregate is still elastic",
            inputs=dict(R1_m=prof[0], R2_m=prof[1], R3_m=prof[2], radius_sd_m=prof[3], force_N=F),
        )
        print(
            f"classic formula: gamma = {g:.5g} N/m, 95 % interval [{g - z * sd:.5g}, {g + z * sd:.5g}] (sd {sd:.2g} "
            f"N/m = {100 * sd / g:.2g} %, from the radii's {prof[3] / UM:g} um). Exact only for a liquid at rest: an "
            "aggregate that is still partly elastic makes it over-state gamma (fit the relaxation records too)"
        )
        out = Path(args.out)
        out.mkdir(parents=True, exist_ok=True)
        (out / "fit.json").write_text(json.dumps(d, indent=1))
        print(f"wrote {out / 'fit.json'}")
        return None
    disps = None if args.displacement_um is None else [d * UM for d in args.displacement_um]
    recs, forces = fit.load_records(
        list(args.files), radius=radius, displacements=disps, ramp_time=args.ramp_time, quantity=args.quantity
    )
    if any(forces) and not all(forces):
        raise ValueError("mix of force (N) and stress (Pa) files: give all records as the same quantity")
    profile = None if prof is None else tension.Profile(*prof)
    initial = None if args.surface_tension is None else {"gamma": args.surface_tension}
    res = tension.tension_relaxation(
        recs, radius=radius, ramp_time=args.ramp_time, n_branches=args.branches, alpha=args.alpha, initial=initial,
        profile=profile, midplane="incompressible" if all(forces) else "fem",
    )  # fmt: skip
    if args.profile_force_un is not None:
        print("note: --profile-force-un is for --profile alone; with records the force is the last record's")
    print(res.summary())
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    d = res.to_dict()
    d["inputs"] = {
        "files": [str(f) for f in args.files],
        "model": "elastocapillary (reduced.capillary)",
        "radius_m": radius,
        "displacement_m": [r[2] for r in recs],
        "ramp_time_s": args.ramp_time,
        "quantity": ["force_N" if f else "stress_Pa" for f in forces],
        "midplane": "incompressible" if all(forces) else "fem",
        "profile_m": None if prof is None else dict(zip(("R1", "R2", "R3", "sd"), prof)),
        "n_points": [int(r[0].size) for r in recs],
    }
    (out / "fit.json").write_text(json.dumps(d, indent=1, default=lambda v: None if not math.isfinite(v) else v))
    written = [str(out / "fit.json")]
    if not args.no_figure:
        from tissuemech.compare.plots.fit import tension_fit_figure

        save_figure(tension_fit_figure(recs, res, radius=radius, ramp_time=args.ramp_time), str(out / "fit.png"))
        written.append(str(out / "fit.png"))
    print("wrote " + ", ".join(written))
    return None
