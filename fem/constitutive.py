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

Small-strain option (``small_strain_stress``, opt-in, used by ``fem.indentation``'s ``kinematics="small"``): the
geometrically linear limit of the same law, eps = sym(H) with H = f - I (incl. the hoop term u_r/R), Hooke's
deviatoric law with the Fung law's small-strain shear modulus mu = 2 W'(3) = 2 C (any alpha), and tr(eps) in
place of J - 1 in the mixed constraint.

API: ``iso_stress(f, C, alpha) -> (P, A)``, ``iso_energy(f, C, alpha)``, ``iso_second_piola(f, C, alpha)``
(S_iso, what the viscoelastic recursion needs), ``vol_q(f, q)``, ``vol_penalty(f, kappa)``,
``cauchy(f, P) -> 3x3 sigma`` and ``von_mises(sigma)``; ``total_stress(f, C, alpha, ...)`` the fused kernel
the assembly uses (iso + volumetric + fixed extra stress in one pass, weights folded in, few temporaries).

Fused form of the tangent (what ``total_stress`` evaluates): with gJ = dJ/df and H = d2J/df2 (linear in f),
A_iso = c_ff f (x) f + c_fJ (f (x) gJ + gJ (x) f) + c_JJ gJ (x) gJ + c_I Id - 2/3 W' J^(-5/3) I1 H, where
c_ff = 4 W'' J^(-4/3), c_fJ = -4/3 J^(-5/3) (W'' J^(-2/3) I1 + W'), c_JJ = 4/9 W'' J^(-10/3) I1^2
+ 10/9 W' J^(-8/3) I1, c_I = 2 W' J^(-2/3) (the expansion of the formulas above with dI1 = 2 f).
"""

from __future__ import annotations

import numpy as np

from tissuemech.fem.kinematics import d2J, dI1, dJ, first_from_second, full_F, invariants, second_from_first
from tissuemech.reduced.material import d2W_dI1, dU_dJ, dW_dI1, fung_energy

__all__ = [
    "total_stress",
    "iso_stress",
    "iso_energy",
    "iso_second_piola",
    "vol_q",
    "vol_penalty",
    "cauchy",
    "von_mises",
    "small_strain_stress",
    "TRACE5",
]

TRACE5 = np.array([1.0, 0.0, 0.0, 1.0, 1.0])  # tr(eps) = TRACE5 . H in the 5-comp form (the linearised dJ/df)


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


# flat (row-major) positions in a 5 x 5 block of the entries of H = d2J/df2 and of T = d(F S)/dF
_H_POS = np.array([3, 4, 7, 9, 11, 14, 15, 19, 20, 21, 22, 23])
_T_POS = np.array([0, 1, 5, 6, 12, 13, 17, 18, 24])
_DIAG = np.arange(0, 25, 6)


def total_stress(
    f: np.ndarray,
    C: float,
    alpha: float,
    *,
    q: np.ndarray | None = None,
    kappa: float | None = None,
    iso_scale: float = 1.0,
    extra_S: np.ndarray | None = None,
    weight: np.ndarray | None = None,
    tangent: bool | str = True,
):
    """Weighted total first Piola stress and tangent in one pass (the assembly kernel).

    Args:
        f: 5-comp deformation gradients (..., 5).
        C: Fung stiffness (in the caller's stress unit).
        alpha: Fung exponent (dimensionless).
        q: mixed volumetric field (..., ) (P_vol = q dJ); or None with ``kappa`` for the penalty U(J).
        kappa: bulk modulus (stress unit) of the penalty form, used only when ``q`` is None.
        iso_scale: factor on the isochoric part (viscoelastic algorithmic stress).
        extra_S: fixed 2nd Piola stress (..., 5) added as P = F S (its tangent d(F S)/dF at fixed S).
        weight: quadrature weights (...,) multiplied into P and A (None: 1).
        tangent: False skips A; "lazy" returns in its place a zero-argument callable that evaluates A from
            this pass's intermediates (the same numbers as ``tangent=True``, without recomputing P).

    Returns:
        (P, A, J): w P (..., 5), w A (..., 5, 5) (None, or the callable), J = det F (...,).
    Equals ``iso_scale * iso_stress + vol_q`` (or ``vol_penalty``) ``+ first_from_second`` to round-off.
    """
    a, b, c, d, e = f[..., 0], f[..., 1], f[..., 2], f[..., 3], f[..., 4]
    det2 = a * d - b * c
    J = e * det2
    I1 = np.einsum("...i,...i->...", f, f)
    gJ = np.stack([e * d, -e * c, -e * b, e * a, det2], axis=-1)
    Jm23 = J ** (-2.0 / 3.0)
    Jm53 = Jm23 / J
    Ib = Jm23 * I1
    w1 = dW_dI1(Ib, C, alpha)
    sw = iso_scale if weight is None else iso_scale * weight
    s1 = sw * w1
    # P = s W' dIbar + P_vol + F S0, dIbar = 2 J^(-2/3) f - 2/3 J^(-5/3) I1 gJ
    pv: np.ndarray | float
    if q is not None:
        pv = q
    elif kappa is not None:
        pv = dU_dJ(J, kappa)
    else:
        pv = 0.0
    pJ = -(2.0 / 3.0) * s1 * Jm53 * I1 + (pv if weight is None else pv * weight)
    P = (2.0 * s1 * Jm23)[..., None] * f + pJ[..., None] * gJ
    S0 = None
    if extra_S is not None:
        S0 = extra_S if weight is None else extra_S * weight[..., None]
        P = P + first_from_second(f, S0)
    if tangent == "lazy":
        return P, lambda: _tangent(f, Ib, C, alpha, sw, s1, Jm23, Jm53, J, I1, gJ, pJ, q, kappa, weight, S0), J
    if not tangent:
        return P, None, J
    return P, _tangent(f, Ib, C, alpha, sw, s1, Jm23, Jm53, J, I1, gJ, pJ, q, kappa, weight, S0), J


def _tangent(f, Ib, C, alpha, sw, s1, Jm23, Jm53, J, I1, gJ, pJ, q, kappa, weight, S0) -> np.ndarray:
    """w A (..., 5, 5) of ``total_stress`` from its stress pass's intermediates (the fused form in the
    module docstring)."""
    a, b, c, d, e = f[..., 0], f[..., 1], f[..., 2], f[..., 3], f[..., 4]
    s2 = sw * d2W_dI1(Ib, C, alpha)
    c_ff = 4.0 * s2 * Jm23 * Jm23
    c_fJ = -(4.0 / 3.0) * Jm53 * (s2 * Jm23 * I1 + s1)
    c_JJ = (4.0 / 9.0) * s2 * Jm53 * Jm53 * I1 * I1 + (10.0 / 9.0) * s1 * Jm53 / J * I1
    if q is None and kappa is not None:
        c_JJ = c_JJ + (kappa if weight is None else kappa * weight)
    W0 = c_ff[..., None] * f + c_fJ[..., None] * gJ
    W1 = c_fJ[..., None] * f + c_JJ[..., None] * gJ
    A = f[..., :, None] * W0[..., None, :]
    A += gJ[..., :, None] * W1[..., None, :]
    A2 = A.reshape(A.shape[:-2] + (25,))
    A2[..., _DIAG] += (2.0 * s1 * Jm23)[..., None]
    cH = pJ[..., None]  # H multiplies -2/3 s W' J^(-5/3) I1 + q (the same factor as gJ in P)
    A2[..., _H_POS] += cH * np.stack([e, d, -e, -c, -e, -b, e, a, d, -c, -b, a], axis=-1)
    if S0 is not None:
        A2[..., _T_POS] += S0[..., [0, 2, 1, 3, 0, 2, 1, 3, 4]]
    return A


def cauchy(f: np.ndarray, P: np.ndarray) -> np.ndarray:
    """Cauchy stress sigma = P F^T / J as (..., 3, 3) in (r, z, theta)."""
    _, J = invariants(f)
    return full_F(P) @ np.swapaxes(full_F(f), -1, -2) / J[..., None, None]


def von_mises(sig: np.ndarray) -> np.ndarray:
    """Von Mises stress sqrt(3/2 s:s), s the deviator of sigma (..., 3, 3)."""
    tr = np.trace(sig, axis1=-2, axis2=-1)
    s = sig - tr[..., None, None] / 3.0 * np.eye(3)
    return np.sqrt(1.5 * np.sum(s * s, axis=(-2, -1)))


def small_strain_stress(f: np.ndarray, C: float, q: np.ndarray | None = None, weight: np.ndarray | None = None):
    """Geometrically linear Fung law: (P, A, tr_eps) at the points from the 5-comp f (H = f - I).

    W = mu (eps : eps - tr(eps)^2 / 3) + q tr(eps), mu = 2 C (the Fung law's small-strain shear modulus),
    eps = sym(H): eps_rr = H_0, eps_zz = H_3, eps_tt = H_4 (u_r/R), eps_rz = (H_1 + H_2) / 2. P = dW/dH (..., 5)
    (the linear stress, weighted by ``weight``), A = d2W/dH2 (5, 5) constant (times ``weight``: (..., 5, 5)),
    tr_eps (...,) the linearised J - 1. ``q`` (...,): the mixed field (None: no volumetric part)."""
    mu = 2.0 * C
    H = f - np.array([1.0, 0.0, 0.0, 1.0, 1.0])
    tr = H @ TRACE5
    P = np.empty_like(H)
    for i in (0, 3, 4):
        P[..., i] = 2.0 * mu * (H[..., i] - tr / 3.0)
    P[..., 1] = P[..., 2] = mu * (H[..., 1] + H[..., 2])
    if q is not None:
        P = P + q[..., None] * TRACE5
    A0 = 2.0 * mu * (np.diag(TRACE5) - np.outer(TRACE5, TRACE5) / 3.0)
    A0[1:3, 1:3] = mu
    if weight is None:
        return P, A0, tr
    return P * weight[..., None], A0 * weight[..., None, None], tr
