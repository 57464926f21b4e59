r"""Axisymmetric finite-strain kinematics in the 5-component form used by the FE engine.

The deformation gradient in the basis (r, z, theta) has five non-zero entries, stored as
``f = (F_rR, F_rZ, F_zR, F_zZ, F_tt)``::

    F = [[1 + du_r/dR, du_r/dZ, 0], [du_z/dR, 1 + du_z/dZ, 0], [0, 0, 1 + u_r/R]]

``f`` is affine in the nodal displacements: f = e + B u_e, with the strain-displacement matrix
``B`` (5 x 2 n_nodes, interleaved dofs (u_r, u_z) per node) built by :func:`b_matrix` from the
basis values/gradients at quadrature points. Volume element dV = 2 pi R dR dZ.

API: ``IDENTITY5``, ``b_matrix(N, dN, R)``, ``invariants(f) -> (I1, J)``, ``dI1(f)``, ``dJ(f)``,
``d2J(f)``, ``full_F(f)`` (3x3), ``second_from_first(f, P)`` (S = F^-1 P, 5-comp),
``first_from_second(f, S)`` (P = F S) and its derivative ``dfirst_from_second(S)``.
Arrays carry leading batch axes (elements, quadrature points) and the component last.
"""

from __future__ import annotations

import numpy as np

__all__ = [
    "IDENTITY5",
    "b_matrix",
    "invariants",
    "det",
    "dI1",
    "dJ",
    "d2J",
    "full_F",
    "second_from_first",
    "first_from_second",
    "dfirst_from_second",
]

IDENTITY5 = np.array([1.0, 0.0, 0.0, 1.0, 1.0])


def b_matrix(N: np.ndarray, dN: np.ndarray, R: np.ndarray) -> np.ndarray:
    """B (..., 5, 2 n) from N (n, ...), dN (n, 2, ...) and R (...): f - I = B u_e.

    Rows: (du_r/dR, du_r/dZ, du_z/dR, du_z/dZ, u_r/R); columns (u_r, u_z) per node.
    """
    n = N.shape[0]
    shape = N.shape[1:]
    B = np.zeros(shape + (5, 2 * n))
    for a in range(n):  # loop over the few element nodes only (vectorised over elements, qps)
        B[..., 0, 2 * a] = dN[a, 0]
        B[..., 1, 2 * a] = dN[a, 1]
        B[..., 2, 2 * a + 1] = dN[a, 0]
        B[..., 3, 2 * a + 1] = dN[a, 1]
        B[..., 4, 2 * a] = N[a] / R
    return B


def invariants(f: np.ndarray):
    """I1 = tr(F^T F) = sum f_i^2 and J = det F = F_tt (F_rR F_zZ - F_rZ F_zR)."""
    return np.sum(f * f, axis=-1), det(f)


def det(f: np.ndarray) -> np.ndarray:
    """J = det F = F_tt (F_rR F_zZ - F_rZ F_zR) of 5-comp deformation gradients (..., 5) -> (...)."""
    return f[..., 4] * (f[..., 0] * f[..., 3] - f[..., 1] * f[..., 2])


def dI1(f: np.ndarray) -> np.ndarray:
    """dI1/df = 2 f (its Hessian is 2 * identity)."""
    return 2.0 * f


def dJ(f: np.ndarray) -> np.ndarray:
    """dJ/df (cofactor of F in 5-comp form)."""
    a, b, c, d, e = (f[..., i] for i in range(5))
    return np.stack([e * d, -e * c, -e * b, e * a, a * d - b * c], axis=-1)


def d2J(f: np.ndarray) -> np.ndarray:
    """d^2J/df^2 (..., 5, 5)."""
    a, b, c, d, e = (f[..., i] for i in range(5))
    H = np.zeros(f.shape + (5,))
    H[..., 0, 3] = H[..., 3, 0] = e
    H[..., 1, 2] = H[..., 2, 1] = -e
    H[..., 0, 4] = H[..., 4, 0] = d
    H[..., 3, 4] = H[..., 4, 3] = a
    H[..., 1, 4] = H[..., 4, 1] = -c
    H[..., 2, 4] = H[..., 4, 2] = -b
    return H


def full_F(f: np.ndarray) -> np.ndarray:
    """The 3x3 deformation gradient (..., 3, 3) in the basis (r, z, theta)."""
    F = np.zeros(f.shape[:-1] + (3, 3))
    F[..., 0, 0], F[..., 0, 1], F[..., 1, 0], F[..., 1, 1], F[..., 2, 2] = (f[..., i] for i in range(5))
    return F


def second_from_first(f: np.ndarray, P: np.ndarray) -> np.ndarray:
    """S = F^-1 P in 5-comp form (S_rr, S_rz, S_zr, S_zz, S_tt)."""
    a, b, c, d, e = (f[..., i] for i in range(5))
    det = a * d - b * c
    i11, i12, i21, i22 = d / det, -b / det, -c / det, a / det
    return np.stack(
        [
            i11 * P[..., 0] + i12 * P[..., 2],
            i11 * P[..., 1] + i12 * P[..., 3],
            i21 * P[..., 0] + i22 * P[..., 2],
            i21 * P[..., 1] + i22 * P[..., 3],
            P[..., 4] / e,
        ],
        axis=-1,
    )


def first_from_second(f: np.ndarray, S: np.ndarray) -> np.ndarray:
    """P = F S in 5-comp form."""
    a, b, c, d, e = (f[..., i] for i in range(5))
    return np.stack(
        [
            a * S[..., 0] + b * S[..., 2],
            a * S[..., 1] + b * S[..., 3],
            c * S[..., 0] + d * S[..., 2],
            c * S[..., 1] + d * S[..., 3],
            e * S[..., 4],
        ],
        axis=-1,
    )


def dfirst_from_second(S: np.ndarray) -> np.ndarray:
    """d(F S)/dF at fixed S (..., 5, 5): dP_ij/dF_kl = delta_ik S_lj."""
    T = np.zeros(S.shape + (5,))
    # P0 = a S0 + b S2 ; P1 = a S1 + b S3 ; P2 = c S0 + d S2 ; P3 = c S1 + d S3 ; P4 = e S4
    T[..., 0, 0], T[..., 0, 1] = S[..., 0], S[..., 2]
    T[..., 1, 0], T[..., 1, 1] = S[..., 1], S[..., 3]
    T[..., 2, 2], T[..., 2, 3] = S[..., 0], S[..., 2]
    T[..., 3, 2], T[..., 3, 3] = S[..., 1], S[..., 3]
    T[..., 4, 4] = S[..., 4]
    return T
