r"""Nearly incompressible Fung law at quadrature points (5-component axisymmetric form).

Uses the shared scalar law ``reduced.material`` (W, W', W''), never re-implements it.
With f the 5-comp deformation gradient (see ``fem.kinematics``), I1 = |f|^2, J = det F,
Ibar1 = J^(-2/3) I1 and W_iso = W(Ibar1):

    P_iso = W'(Ibar1) dIbar,   A_iso = W'' dIbar (x) dIbar + W' d2Ibar
    dIbar  = J^(-2/3) dI1 - 2/3 J^(-5/3) I1 dJ
    d2Ibar = 2 J^(-2/3) Id - 2/3 J^(-5/3) (dI1 (x) dJ + dJ (x) dI1) + 10/9 J^(-8/3) I1 dJ (x) dJ
             - 2/3 J^(-5/3) I1 d2J

(P the first Piola-Kirchhoff stress, A = dP/dF; exact for alpha = 0.) Volumetric parts:
pressure-like field q (mixed form): P = q dJ, A = q d2J; penalty U(J): P = U' dJ, A = kappa dJ(x)dJ + U' d2J.
Units: whatever C is given in (the engine passes C = 1, i.e. stresses scaled by C).

API: ``iso_stress(f, C, alpha) -> (P, A)``, ``iso_energy(f, C, alpha)``, ``iso_second_piola(f, C, alpha)``
(S_iso, what the viscoelastic recursion needs), ``vol_q(f, q)``, ``vol_penalty(f, kappa)``,
``cauchy(f, P) -> 3x3 sigma`` and ``von_mises(sigma)``.
"""

from __future__ import annotations

import numpy as np

from tissuemech.fem.kinematics import d2J, dI1, dJ, full_F, invariants, second_from_first
from tissuemech.reduced.material import d2W_dI1, dU_dJ, dW_dI1, fung_energy

__all__ = ["iso_stress", "iso_energy", "iso_second_piola", "vol_q", "vol_penalty", "cauchy", "von_mises"]


def _ibar_derivs(f):
    I1, J = invariants(f)
    g1, gJ = dI1(f), dJ(f)
    Jm23 = J ** (-2.0 / 3.0)
    Jm53 = Jm23 / J
    Ib = Jm23 * I1
    dIb = Jm23[..., None] * g1 - (2.0 / 3.0) * (Jm53 * I1)[..., None] * gJ
    eye = np.eye(5)
    d2Ib = (
        2.0 * Jm23[..., None, None] * eye
        - (2.0 / 3.0)
        * Jm53[..., None, None]
        * (g1[..., :, None] * gJ[..., None, :] + gJ[..., :, None] * g1[..., None, :])
        + (10.0 / 9.0) * (Jm53 / J * I1)[..., None, None] * gJ[..., :, None] * gJ[..., None, :]
        - (2.0 / 3.0) * (Jm53 * I1)[..., None, None] * d2J(f)
    )
    return Ib, dIb, d2Ib


def iso_energy(f: np.ndarray, C: float, alpha: float) -> np.ndarray:
    """W_iso(Ibar1) per reference volume."""
    I1, J = invariants(f)
    return fung_energy(J ** (-2.0 / 3.0) * I1, C, alpha)


def iso_stress(f: np.ndarray, C: float, alpha: float):
    """Isochoric first Piola stress P (..., 5) and tangent A = dP/df (..., 5, 5)."""
    Ib, dIb, d2Ib = _ibar_derivs(f)
    w1, w2 = dW_dI1(Ib, C, alpha), d2W_dI1(Ib, C, alpha)
    P = w1[..., None] * dIb
    A = w2[..., None, None] * dIb[..., :, None] * dIb[..., None, :] + w1[..., None, None] * d2Ib
    return P, A


def iso_second_piola(f: np.ndarray, C: float, alpha: float) -> np.ndarray:
    """Isochoric 2nd Piola-Kirchhoff stress S_iso = F^-1 P_iso (5-comp, symmetric: S_rz = S_zr)."""
    return second_from_first(f, iso_stress(f, C, alpha)[0])


def vol_q(f: np.ndarray, q: np.ndarray):
    """Mixed volumetric part q (J - 1): P = q dJ/df, A = q d2J/df2 (q the mean Cauchy stress)."""
    return q[..., None] * dJ(f), q[..., None, None] * d2J(f)


def vol_penalty(f: np.ndarray, kappa: float):
    """Displacement-only volumetric part U(J) = kappa/2 (J-1)^2: P = U' dJ, A = kappa dJ dJ + U' d2J."""
    _, J = invariants(f)
    gJ = dJ(f)
    up = dU_dJ(J, kappa)
    return up[..., None] * gJ, kappa * gJ[..., :, None] * gJ[..., None, :] + up[..., None, None] * d2J(f)


def cauchy(f: np.ndarray, P: np.ndarray) -> np.ndarray:
    """Cauchy stress sigma = P F^T / J as (..., 3, 3) in (r, z, theta)."""
    _, J = invariants(f)
    return full_F(P) @ np.swapaxes(full_F(f), -1, -2) / J[..., None, None]


def von_mises(sig: np.ndarray) -> np.ndarray:
    """Von Mises stress sqrt(3/2 s:s), s the deviator of sigma (..., 3, 3)."""
    tr = np.trace(sig, axis1=-2, axis2=-1)
    s = sig - tr[..., None, None] / 3.0 * np.eye(3)
    return np.sqrt(1.5 * np.sum(s * s, axis=(-2, -1)))
