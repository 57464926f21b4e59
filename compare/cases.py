r"""The seed study's cases, defined once (SI units: m, Pa, s).

Blastula (scene 1, Peters & Iber Figs 3-5): a hollow incompressible Fung sphere, inner radius
``BLASTULA_INNER_RADIUS`` = 50 um, C = ``BLASTULA_C`` = 200 Pa, inflated by internal pressure.

* ``FIG3``: the von Mises figure (alpha = 0.2, B = 75 um, p = 1 kPa);
* ``FIG4_ALPHAS`` at B = ``FIG4_OUTER_RADIUS`` (75 um); ``FIG5_OUTER_RADII`` at alpha = ``FIG5_ALPHA``;
  ``BLASTULA_SETS`` lists both as (figure, alpha, outer radius in m);
* ``NEO_HOOKEAN_ALPHA`` (1e-5): the seed's "neo-Hookean" run, whose limit ("burst") pressure the seed
  puts at ``SEED_BURST_PRESSURE`` = 0.1 kPa;
* ``ACCURACY_PRESSURES``: the pressures at which accuracy studies compare with the exact shell;
* ``CREEP_CASES``: viscoelastic shell ramp-and-hold cases (issue 5).

Spheroid (scene 2, Figs 8-10): a Fung ball of radius 500 um between rigid plates.

* ``FIG89`` / ``FIG89_END_TIME`` / ``FIG89_FIELD_TIMES``: the Figs 8-9 case (200 um approach in 0.2 s);
* ``FIG10`` / ``FIG10_END_TIME`` / ``FIG10_TIMES``: the Fig. 10 relaxation case (50 um in 0.2 s);
* ``SPHEROID_CHECK_CASES``: the two seed cases in the (C, alpha, beta, tau, displacement) form the
  reduced-vs-FE checks use.

The dicts are keyword arguments of ``reduced.spheroid.force`` / ``fem.spheroid.compress`` (FIG89,
FIG10) or of the studies; treat them as read-only (copy before changing).
"""

from __future__ import annotations

from typing import Any

UM = 1e-6  # one micrometre in m

# ---- blastula -------------------------------------------------------------------------------
BLASTULA_INNER_RADIUS = 50 * UM
BLASTULA_C = 200.0
FIG3: dict[str, float] = dict(alpha=0.2, outer_radius=75 * UM, pressure=1000.0)
FIG4_ALPHAS = (1e-5, 0.1, 0.2, 0.3)
FIG4_OUTER_RADIUS = 75 * UM
FIG5_ALPHA = 0.2
FIG5_OUTER_UM = (52.0, 60.0, 75.0)
FIG5_OUTER_RADII = tuple(b * UM for b in FIG5_OUTER_UM)
BLASTULA_SETS: tuple[tuple[str, float, float], ...] = tuple(
    ("Fig. 4", a, FIG4_OUTER_RADIUS) for a in FIG4_ALPHAS
) + tuple(("Fig. 5", FIG5_ALPHA, b) for b in FIG5_OUTER_RADII)
NEO_HOOKEAN_ALPHA = 1e-5
SEED_BURST_PRESSURE = 100.0  # the seed: "the blastula would burst in the neo-Hookean limit ... for p > 0.1 kPa"
ACCURACY_PRESSURES = (200.0, 500.0, 1000.0)
CREEP_CASES: dict[str, dict[str, float]] = {  # A = 50 um, B = 75 um, C = 200 Pa; ramp over ramp_time, held `hold` s
    "issue 5": dict(alpha=0.2, beta=0.5, tau=100.0, pressure=300.0, ramp_time=1.0, hold=600.0),
}

# ---- spheroid -------------------------------------------------------------------------------
SPHEROID_RADIUS = 500 * UM
SPHEROID_RAMP_TIME = 0.2
FIG89: dict[str, Any] = dict(
    radius=SPHEROID_RADIUS,
    C=200.0,
    alpha=0.2,
    branches=[(1.2, 200.0)],
    displacement=200 * UM,
    ramp_time=SPHEROID_RAMP_TIME,
)
FIG89_END_TIME = 1497.0
FIG89_FIELD_TIMES = (0.2, 1497.0)
FIG10: dict[str, Any] = dict(
    radius=SPHEROID_RADIUS,
    C=150.0,
    alpha=0.2,
    branches=[(0.4, 200.0)],
    displacement=50 * UM,
    ramp_time=SPHEROID_RAMP_TIME,
)
FIG10_END_TIME = 1500.0
FIG10_TIMES = (0.2, 1500.0)  # where the accuracy studies read sigma~
# issue 35's fast two-branch case (a branch a quarter of the ramp, as cell cortex relaxation gives): time convergence
FAST_BRANCHES: dict[str, Any] = dict(
    radius=SPHEROID_RADIUS,
    C=150.0,
    alpha=0.2,
    branches=[(0.8, 0.05), (0.3, 20.0)],
    displacement=100 * UM,
    ramp_time=SPHEROID_RAMP_TIME,
    end_time=200.0,
)
SPHEROID_CHECK_CASES: dict[str, dict[str, float]] = {
    "Fig. 10": dict(C=150.0, alpha=0.2, beta=0.4, tau=200.0, displacement=50 * UM),
    "Figs 8-9": dict(C=200.0, alpha=0.2, beta=1.2, tau=200.0, displacement=200 * UM),
}


def describe_spheroid(case: dict[str, Any]) -> str:
    """One-line description of a spheroid case dict such as ``FIG10`` (units in the text)."""
    (beta, tau), *_ = case["branches"]
    return (
        f"C = {case['C']:g} Pa, alpha = {case['alpha']:g}, beta = {beta:g}, tau = {tau:g} s, "
        f"{case['displacement'] / UM:g} um in {case['ramp_time']:g} s (a0 = {case['radius'] / UM:g} um)"
    )


def spheroid_keywords(
    params: dict[str, Any], *, radius: float, displacement: float, ramp_time: float
) -> dict[str, Any]:
    """The keywords a single-branch spheroid case passes both to ``reduced.spheroid.nominal_stress`` and to
    ``fem.spheroid.compress``.

    Arguments:
        params: ``C`` [Pa], ``alpha`` [-], ``beta`` [-], ``tau`` [s].
        radius: ball radius a0 [m]. displacement: plate approach [m]. ramp_time: ramp duration [s].
    """
    return dict(
        radius=radius,
        C=params["C"],
        alpha=params["alpha"],
        branches=[(params["beta"], params["tau"])],
        displacement=displacement,
        ramp_time=ramp_time,
    )
