"""The FE point functions: one FE run per scene at one parameter point (SI units), written once.

They are module-level functions of keyword arguments (picklable for process pools and dask) returning
dicts of NumPy arrays and scalars, the form ``compare.batch.run`` stores. ``compare.scan``'s FE spot-checks
and ``tissuemech batch --function fe-spheroid|fe-blastula`` both run them.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np

__all__ = ["fe_spheroid", "fe_blastula", "FUNCTIONS", "BLASTULA_RAMP_STEPS"]

BLASTULA_RAMP_STEPS = 10  # equal pressure steps from rest to the point's pressure


def fe_spheroid(
    *,
    radius: float = 500e-6,
    C: float,
    alpha: float,
    beta: float,
    tau: float,
    displacement: float,
    ramp_time: float = 0.2,
    end_time: float = 1500.0,
    mesh: Any = "default",
) -> dict:
    """One FE compression-relaxation (``fem.spheroid.compress``, one Maxwell branch; none for beta = 0), SI units.

    Returns the curves ``time`` [s], ``force`` [N], ``nominal_stress`` [Pa] and the scalars
    ``sigma_peak`` and ``sigma_end`` [Pa] (largest and last nominal stress), ``steps``."""
    from tissuemech.fem import spheroid

    r = spheroid.compress(
        radius=radius,
        C=C,
        alpha=alpha,
        branches=[(beta, tau)] if beta > 0 else [],
        displacement=displacement,
        ramp_time=ramp_time,
        end_time=end_time,
        mesh=int(mesh) if isinstance(mesh, float) and mesh.is_integer() else mesh,
    )
    s = np.asarray(r.nominal_stress)
    return dict(
        time=np.asarray(r.time),
        force=np.asarray(r.force),
        nominal_stress=s,
        sigma_peak=float(s.max()),
        sigma_end=float(s[-1]),
        steps=len(r.time),
    )


def fe_blastula(
    *, inner_radius: float = 50e-6, outer_radius: float, C: float, alpha: float, pressure: float, mesh: Any = "default"
) -> dict:
    """One FE inflation (``fem.blastula.inflate``) from rest to ``pressure`` (Pa) in ``BLASTULA_RAMP_STEPS`` equal
    load steps (each Newton solve starts near its solution), SI units; returns the scalars ``inner_stretch`` and
    ``outer_stretch`` [-] at that pressure and ``newton_iterations`` (over all steps)."""
    from tissuemech.fem import blastula

    pressures = np.linspace(0.0, pressure, BLASTULA_RAMP_STEPS + 1)[1:]
    r = blastula.inflate(
        inner_radius=inner_radius, outer_radius=outer_radius, C=C, alpha=alpha, pressures=pressures, mesh=mesh
    )
    return dict(
        inner_stretch=float(np.asarray(r.inner_stretch)[-1]),
        outer_stretch=float(np.asarray(r.outer_stretch)[-1]),
        newton_iterations=int(np.asarray(r.newton_iterations).sum()),
    )


FUNCTIONS: dict[str, Callable[..., Any]] = {"fe-spheroid": fe_spheroid, "fe-blastula": fe_blastula}
