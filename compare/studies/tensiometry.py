r"""Parallel-plate tensiometry: how elastic may an aggregate be before the surface-tension formula fails?

Plate compression tensiometry (Forgacs et al. 1998; Norotte et al. 2008) reads the tissue surface tension
gamma of a compressed cell aggregate from its plate force F and three radii of its profile,

    gamma_app = F / (pi R3^2 (1/R1 + 1/R2)),

R3 the contact-disc radius, R2 the equatorial radius, R1 the meridional radius of curvature at the equator.
The formula is the Young-Laplace balance of a LIQUID drop on non-wetting plates (``tissuemech.reduced.drop``:
there it is exact). An aggregate that keeps some elasticity (a long-time modulus C) carries part of the force
by elastic stress, which the formula books as tension. This study applies the formula to

* the exact drop (:func:`drop_point`: it returns gamma to the solver's accuracy), and
* FE spheroids with tension (``fem.spheroid.compress(..., surface_tension=gamma)``), with R1, R2, R3 read
  from the FE profile as an experimenter would (:func:`profile_radii`), as a function of the
  elastocapillary number gamma / (C a0) (:func:`sweep`, :func:`threshold`).

Realistic numbers (the defaults): S180 aggregates, a0 = 175 um, gamma = 6 mN/m, E ~ 1 kPa (C = E/6 ~ 170
Pa), i.e. gamma / (C a0) ~ 0.2. Measured (``sweep()`` at 10 % compression, delta = 0.2 a0, mesh level 1,
node-by-node contact): see ``docs/tension.md`` for the table; the formula is within 5 % only for
gamma / (C a0) above the value :func:`threshold` returns (about 10): the aggregate must have relaxed
(flowed) to a long-time modulus ~50 times below 1 kPa before the formula can be trusted.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np
import pandas as pd

from tissuemech.fem import spheroid as fem_spheroid
from tissuemech.fem.forms import line_shape
from tissuemech.fem.mesh import AxiMesh
from tissuemech.fem.output import SpheroidResult
from tissuemech.reduced import drop

__all__ = [
    "apparent_tension",
    "ProfileRadii",
    "profile_radii",
    "fit_meridional_radius",
    "TensiometryPoint",
    "drop_point",
    "fe_point",
    "sweep",
    "threshold",
    "table",
    "hold_series",
    "A0",
    "E0",
    "ETA",
    "TAU",
    "HOLD_NUMBERS",
    "HOLD_TIMES",
    "GAMMA",
    "NUMBERS",
]

A0 = 175e-6  # m, S180 aggregate radius
GAMMA = 6e-3  # N/m, S180 surface tension
NUMBERS = (0.2, 0.5, 1.0, 2.0, 5.0, 10.0, 20.0, 50.0)  # elastocapillary numbers gamma / (C a0) of the sweep
FIT_SPAN = 0.1  # the equatorial band |z| < FIT_SPAN h fitted for R1 (0.25: R1 of the exact drop 1.3 % short)


def apparent_tension(force, R1, R2, R3):
    """The tensiometry formula gamma_app = F / (pi R3^2 (1/R1 + 1/R2)) (N/m; F in N, radii in m)."""
    return np.asarray(force) / (np.pi * np.asarray(R3) ** 2 * (1.0 / np.asarray(R1) + 1.0 / np.asarray(R2)))


class ProfileRadii(NamedTuple):
    """The three radii of a compressed profile (m)."""

    R1: float  # meridional radius of curvature at the equator
    R2: float  # equatorial radius
    R3: float  # contact-disc radius


def fit_meridional_radius(r: np.ndarray, z: np.ndarray, half_gap: float, span: float = FIT_SPAN) -> tuple[float, float]:
    """(R1, R2) (m) from profile points (r, z) (m, z >= 0 from the midplane): the least-squares fit
    r = R2 - z^2 / (2 R1) + c z^4 over the band z < span * half_gap (what an experimenter does with a side
    view). Raises ValueError with fewer than 4 points in the band."""
    r, z = np.asarray(r, float), np.abs(np.asarray(z, float))
    sel = z < span * half_gap
    if sel.sum() < 4:
        raise ValueError(f"only {int(sel.sum())} profile points within z < {span} h: cannot fit R1")
    A = np.stack([np.ones(sel.sum()), z[sel] ** 2, z[sel] ** 4], axis=1)
    c = np.linalg.lstsq(A, r[sel], rcond=None)[0]
    return float(-1.0 / (2.0 * c[1])), float(c[0])


def profile_radii(result: SpheroidResult, n_per_edge: int = 9, field: int = -1) -> ProfileRadii:
    """R1, R2, R3 (m) of a stored state of an FE spheroid run (``field`` indexes ``result.fields``; default the
    last).

    R2: the midplane radius; R1: the deformed outer surface sampled on its quadratic edges (``n_per_edge``
    points each) fitted by :func:`fit_meridional_radius`; R3: where the profile leaves the plate, between
    the outermost node in contact (r_k) and the next candidate (r_1), from the gaps g_1, g_2 of the next two
    with the law of a surface that leaves the plate tangentially with a finite curvature, g ~ (r - R3)^2:
    sqrt(g_1 / g_2) = (r_1 - R3) / (r_2 - R3), clamped to [r_k, r_1] (a tense surface has no Hertz root
    (r - a)^(3/2): the tension bounds its curvature; on a node-by-node contact this estimate is the
    experimenter's side view)."""
    if not result.fields:
        raise ValueError("the result stores no field (the deformed profile is needed)")
    f, m = result.fields[field], result.mesh
    assert isinstance(m, AxiMesh) and result.parameters is not None  # a compress result carries both
    step = int(np.argmin(np.abs(np.asarray(result.time) - f.time)))  # the step the field was stored at
    edges = m.edges["outer"]
    N, _ = line_shape(edges.shape[1], np.linspace(-1.0, 1.0, n_per_edge))
    xd = f.deformed_nodes[edges]  # (n_edges, nn, 2)
    pts = np.einsum("aq,ean->eqn", N, xd).reshape(-1, 2)
    h = result.parameters["radius"] - result.approach[step] / 2
    R1, _ = fit_meridional_radius(pts[:, 0], pts[:, 1], h)
    R3 = float(result.contact_radius[step])
    cand = f.contact_nodes if f.contact_nodes is not None else np.array([], int)
    if cand.size:
        x = f.deformed_nodes[cand]
        order = np.argsort(x[:, 0])
        x, Nf = x[order], f.contact_nodal_force[order]
        on = np.flatnonzero(Nf > 0)
        if on.size and on[-1] + 2 < x.shape[0]:
            k = int(on[-1])
            g1, g2 = h - x[k + 1, 1], h - x[k + 2, 1]
            r1, r2, rk = x[k + 1, 0], x[k + 2, 0], x[k, 0]
            if g2 > g1 > 0 and r2 > r1 > rk:
                rho = math.sqrt(g1 / g2)
                R3 = float(np.clip((r1 - rho * r2) / (1.0 - rho), rk, r1))
    return ProfileRadii(R1, float(result.midplane_radius[step]), R3)


class TensiometryPoint(NamedTuple):
    """The formula applied to one compressed body (SI)."""

    elastocapillary: float  # gamma / (C a0) (inf for the drop)
    force: float  # N
    radii: ProfileRadii  # m
    apparent_tension: float  # N/m
    ratio: float  # apparent / true tension
    drop_force_ratio: float  # F / F_drop at the same approach (1 for the drop)


def drop_point(compression: float = 0.1, radius: float = A0, surface_tension: float = GAMMA) -> TensiometryPoint:
    """The formula on the exact drop at approach delta = 2 a0 ``compression`` with its exact radii."""
    s = drop.compress(2 * radius * compression, radius=radius, surface_tension=surface_tension)
    radii = ProfileRadii(s.meridional_radius, s.equatorial_radius, s.contact_radius)
    g = float(apparent_tension(s.force, *radii))
    return TensiometryPoint(math.inf, s.force, radii, g, g / surface_tension, 1.0)


def fe_point(
    number: float,
    compression: float = 0.1,
    radius: float = A0,
    surface_tension: float = GAMMA,
    alpha: float = 0.2,
    mesh: int = 1,
    contact: str = "nodal",
) -> TensiometryPoint:
    """The formula on the FE spheroid of elastocapillary number ``number`` = gamma / (C a0) (C set from it),
    statically compressed by delta = 2 a0 ``compression``, radii from the FE profile (:func:`profile_radii`).
    ``contact="nodal"`` (default; the sweep's numbers were measured with it): the fitted contact edge failed to
    start for gamma / (C a0) >~ 2 before its continuation in the tension (``fem.contact.EdgeSearch``; level 1 now
    starts at 2, 5 and 10, see docs/tension.md)."""
    C = surface_tension / (number * radius)
    d = 2 * radius * compression
    r = fem_spheroid.compress(radius=radius, C=C, alpha=alpha, displacement=d, ramp_time=1.0, end_time=1.0,
                              static=True, mesh=mesh, contact=contact, surface_tension=surface_tension)  # fmt: skip
    radii = profile_radii(r)
    F = float(r.force[-1])
    g = float(apparent_tension(F, *radii))
    Fd = drop.compress(d, radius=radius, surface_tension=surface_tension).force
    return TensiometryPoint(float(number), F, radii, g, g / surface_tension, F / Fd)


def sweep(numbers=NUMBERS, **kw) -> list[TensiometryPoint]:
    """:func:`fe_point` for each elastocapillary number (``kw`` go to it)."""
    return [fe_point(float(n), **kw) for n in numbers]


def threshold(points: list[TensiometryPoint], tol: float = 0.05) -> float:
    """The elastocapillary number above which |gamma_app / gamma - 1| <= tol, interpolated in log of the
    number between the sweep's points (inf if no point is within ``tol``; the first number if all are)."""
    n = np.array([p.elastocapillary for p in points])
    e = np.abs(np.array([p.ratio for p in points]) - 1.0)
    order = np.argsort(n)
    n, e = n[order], e[order]
    ok = e <= tol
    if not ok.any():
        return math.inf
    k = int(np.argmax(ok))
    if not ok[k:].all():  # not monotone: the last entry of the last bad run
        k = int(np.max(np.flatnonzero(~ok))) + 1
        if k >= n.size:
            return math.inf
    if k == 0:
        return float(n[0])
    t = (e[k - 1] - tol) / (e[k - 1] - e[k])
    return float(np.exp(np.log(n[k - 1]) + t * (np.log(n[k]) - np.log(n[k - 1]))))


E0 = 1.0e3  # Pa, instantaneous Young's modulus of an S180 aggregate
ETA = 5.0e5  # Pa s, its flow viscosity
TAU = 3.0 * ETA / E0  # s, the Maxwell time eta / G of an incompressible branch (G = E / 3): 1500 s
HOLD_NUMBERS = (2.0, 5.0, 20.0)  # long-time elastocapillary numbers gamma / (C_inf a0) of the hold study
HOLD_TIMES = (1.0, 10.0, 30.0, 100.0, 300.0, 1000.0, 3000.0, 1e4, 3e4)  # s after the start of the compression


def hold_series(
    number: float,
    compression: float = 0.1,
    radius: float = A0,
    surface_tension: float = GAMMA,
    E0: float = E0,
    tau: float = TAU,
    ramp_time: float = 1.0,
    times: tuple[float, ...] = HOLD_TIMES,
    alpha: float = 0.2,
    mesh: int = 1,
) -> pd.DataFrame:
    """The formula read at ``times`` (s) while an aggregate relaxes under held plates.

    The aggregate: instantaneous Young's modulus ``E0`` (Pa; C(1 + beta) = E0 / 6), one Maxwell branch of
    time ``tau`` (s; default 3 eta / E0 for the S180 flow viscosity eta = 5e5 Pa s: 1500 s) that relaxes it
    to the long-time modulus C_inf = gamma / (``number`` a0); compressed by delta = 2 a0 ``compression`` in
    ``ramp_time`` (s) and held; radii from the FE profile at each time (:func:`profile_radii`, node-by-node
    contact). Returns a table: ``time [s]``, ``gamma_app/gamma``, ``F/F_drop``, ``F [N]`` and the radii, with
    ``gamma/(C_inf a0)`` the number. A pure liquid (C_inf = 0) is the limit number -> inf; this solid with a
    small C_inf is how the FE models it today (the drop, ``reduced.drop``, is that limit's exact answer)."""
    C_inf = surface_tension / (number * radius)
    beta = E0 / 6.0 / C_inf - 1.0
    if beta < 0:
        raise ValueError(
            f"the long-time modulus C_inf = {C_inf:.4g} Pa (gamma / (number a0)) exceeds the instantaneous E0 / 6 = "
            f"{E0 / 6:.4g} Pa: raise the elastocapillary number or E0"
        )
    d = 2 * radius * compression
    ts = tuple(float(t) for t in times if t >= ramp_time)
    r = fem_spheroid.compress(radius=radius, C=C_inf, alpha=alpha, branches=[(beta, tau)], displacement=d,
                              ramp_time=ramp_time, end_time=max(ts), mesh=mesh, contact="nodal",
                              surface_tension=surface_tension, field_times=ts)  # fmt: skip
    Fd = drop.compress(d, radius=radius, surface_tension=surface_tension).force
    rows = []
    for k, f in enumerate(r.fields):
        radii = profile_radii(r, field=k)
        step = int(np.argmin(np.abs(r.time - f.time)))
        F = float(r.force[step])
        g = float(apparent_tension(F, *radii))
        rows.append((float(number), f.time, F, *radii, g / surface_tension, F / Fd))
    return pd.DataFrame(
        rows,
        columns=["gamma/(C_inf a0)", "time [s]", "F [N]", "R1 [m]", "R2 [m]", "R3 [m]", "gamma_app/gamma", "F/F_drop"],
    )


def table(points: list[TensiometryPoint]) -> pd.DataFrame:
    """A tidy table of the points (units in the column names)."""
    return pd.DataFrame(
        {
            "gamma/(C a0)": [p.elastocapillary for p in points],
            "F [N]": [p.force for p in points],
            "R1 [m]": [p.radii.R1 for p in points],
            "R2 [m]": [p.radii.R2 for p in points],
            "R3 [m]": [p.radii.R3 for p in points],
            "gamma_app [N/m]": [p.apparent_tension for p in points],
            "gamma_app/gamma": [p.ratio for p in points],
            "F/F_drop": [p.drop_force_ratio for p in points],
        }
    )
