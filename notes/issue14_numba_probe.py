"""Would a compiled element kernel close the FE per-iteration gap? A numba probe (issue 14, fourth pass).

``python notes/issue14_numba_probe.py`` (needs ``pip install numba``; tissuemech does not depend on it)
compiles the mixed u-p element pass of the blastula (F at the points, the fused Fung stress and tangent of
``fem.constitutive.total_stress``, the element residuals and blocks B^T A B with the q coupling and the
mass block M / kappa, exploiting that B's rows (du_r/dR, du_r/dZ, u_r/R) touch only u_r and
(du_z/dR, du_z/dZ) only u_z) and times it against the numpy pass the assembly runs now
(``Assembler._fields`` + ``total_stress`` + ``_residual`` + ``_tangent_values``) on the 4x8 and 16x32 shells,
interleaved, min of 5 x 100 calls; it checks that both give the same residual and element blocks (to
1e-13). W'(Ibar) and W''(Ibar) still come from the one shared law (``reduced.material``) between the two
compiled passes, as the numpy pass does.
"""

from __future__ import annotations

import sys
import time

import numpy as np

try:
    import numba as nb
except ImportError:  # pragma: no cover - an optional probe
    sys.exit("this probe needs numba: pip install numba")

from tissuemech.fem import blastula as fb
from tissuemech.fem import constitutive as cm
from tissuemech.reduced.material import d2W_dI1, dW_dI1

jit = nb.njit(error_model="numpy", fastmath=True, cache=False)


@jit
def _points(G, ue, f, Ib):  # pragma: no cover - compiled
    ne, nq, _, n = G.shape
    for e in range(ne):
        for q in range(nq):
            a, b, c, d, t = 1.0, 0.0, 0.0, 1.0, 1.0
            for k in range(n):
                ur, uz = ue[e, 2 * k], ue[e, 2 * k + 1]
                a += G[e, q, 0, k] * ur
                b += G[e, q, 1, k] * ur
                t += G[e, q, 2, k] * ur
                c += G[e, q, 0, k] * uz
                d += G[e, q, 1, k] * uz
            f[e, q, 0], f[e, q, 1], f[e, q, 2], f[e, q, 3], f[e, q, 4] = a, b, c, d, t
            Ib[e, q] = (t * (a * d - b * c)) ** (-2.0 / 3.0) * (a * a + b * b + c * c + d * d + t * t)


@jit
def _elements(G, f, w1, w2, w, psi, qe, M, kinv, re, Ke):  # pragma: no cover - compiled
    ne, nq, _, n = G.shape
    nd, na = 2 * n, psi.shape[2]
    A, gJ = np.empty((5, 5)), np.empty(5)
    Vr, Vz = np.empty((5, n)), np.empty((5, n))
    Krr, Krz, Kzr, Kzz = np.empty((n, n)), np.empty((n, n)), np.empty((n, n)), np.empty((n, n))
    for e in range(ne):
        Ke[e] = 0.0
        re[e] = 0.0
        Krr[:] = 0.0
        Krz[:] = 0.0
        Kzr[:] = 0.0
        Kzz[:] = 0.0
        for q in range(nq):
            a, b, c, d, t = f[e, q, 0], f[e, q, 1], f[e, q, 2], f[e, q, 3], f[e, q, 4]
            det2 = a * d - b * c
            J = t * det2
            I1 = a * a + b * b + c * c + d * d + t * t
            gJ[0], gJ[1], gJ[2], gJ[3], gJ[4] = t * d, -t * c, -t * b, t * a, det2
            Jm23 = J ** (-2.0 / 3.0)
            Jm53 = Jm23 / J
            wq = w[e, q]
            s1, s2 = wq * w1[e, q], wq * w2[e, q]
            qv = 0.0
            for i in range(na):
                qv += psi[e, q, i] * qe[e, i]
            pJ = -(2.0 / 3.0) * s1 * Jm53 * I1 + qv * wq
            ci = 2.0 * s1 * Jm23
            c_ff = 4.0 * s2 * Jm23 * Jm23
            c_fJ = -(4.0 / 3.0) * Jm53 * (s2 * Jm23 * I1 + s1)
            c_JJ = (4.0 / 9.0) * s2 * Jm53 * Jm53 * I1 * I1 + (10.0 / 9.0) * s1 * Jm53 / J * I1
            for i in range(5):
                u0 = c_ff * f[e, q, i] + c_fJ * gJ[i]
                u1 = c_fJ * f[e, q, i] + c_JJ * gJ[i]
                for j in range(5):
                    A[i, j] = u0 * f[e, q, j] + u1 * gJ[j]
                A[i, i] += ci
            A[0, 3] += pJ * t
            A[0, 4] += pJ * d
            A[1, 2] -= pJ * t
            A[1, 4] -= pJ * c
            A[2, 1] -= pJ * t
            A[2, 4] -= pJ * b
            A[3, 0] += pJ * t
            A[3, 4] += pJ * a
            A[4, 0] += pJ * d
            A[4, 1] -= pJ * c
            A[4, 2] -= pJ * b
            A[4, 3] += pJ * a
            P = (
                ci * a + pJ * gJ[0],
                ci * b + pJ * gJ[1],
                ci * c + pJ * gJ[2],
                ci * d + pJ * gJ[3],
                ci * t + pJ * gJ[4],
            )
            g0, g1, g2 = G[e, q, 0], G[e, q, 1], G[e, q, 2]
            for j in range(5):
                for k in range(n):
                    Vr[j, k] = A[j, 0] * g0[k] + A[j, 1] * g1[k] + A[j, 4] * g2[k]
                    Vz[j, k] = A[j, 2] * g0[k] + A[j, 3] * g1[k]
            jm = (J - 1.0) * wq
            for k in range(n):
                re[e, 2 * k] += P[0] * g0[k] + P[1] * g1[k] + P[4] * g2[k]
                re[e, 2 * k + 1] += P[2] * g0[k] + P[3] * g1[k]
            for i in range(na):
                pa = psi[e, q, i]
                re[e, nd + i] += pa * jm
                for k in range(n):
                    Ke[e, nd + i, 2 * k] += pa * wq * (gJ[0] * g0[k] + gJ[1] * g1[k] + gJ[4] * g2[k])
                    Ke[e, nd + i, 2 * k + 1] += pa * wq * (gJ[2] * g0[k] + gJ[3] * g1[k])
            for k1 in range(n):
                x0, x1, x2 = g0[k1], g1[k1], g2[k1]
                for k2 in range(n):
                    Krr[k1, k2] += x0 * Vr[0, k2] + x1 * Vr[1, k2] + x2 * Vr[4, k2]
                    Krz[k1, k2] += x0 * Vz[0, k2] + x1 * Vz[1, k2] + x2 * Vz[4, k2]
                    Kzr[k1, k2] += x0 * Vr[2, k2] + x1 * Vr[3, k2]
                    Kzz[k1, k2] += x0 * Vz[2, k2] + x1 * Vz[3, k2]
        for k1 in range(n):
            for k2 in range(n):
                Ke[e, 2 * k1, 2 * k2] = Krr[k1, k2]
                Ke[e, 2 * k1, 2 * k2 + 1] = Krz[k1, k2]
                Ke[e, 2 * k1 + 1, 2 * k2] = Kzr[k1, k2]
                Ke[e, 2 * k1 + 1, 2 * k2 + 1] = Kzz[k1, k2]
        for i in range(na):
            s = 0.0
            for j in range(na):
                s += M[e, i, j] * qe[e, j]
                Ke[e, nd + i, nd + j] = -M[e, i, j] * kinv
            re[e, nd + i] -= s * kinv
            for k in range(nd):
                Ke[e, k, nd + i] = Ke[e, nd + i, k]


def compiled_pass(asm, G, x, mat):
    """(global residual (ndof,), element blocks (ne, nd + 3, nd + 3)) by the two compiled passes."""
    ne, nq = asm.w.shape
    f, Ib = np.empty((ne, nq, 5)), np.empty((ne, nq))
    qe = x[asm.qdofs]
    _points(G, x[asm.edofs], f, Ib)
    w1, w2 = dW_dI1(Ib, mat.C, mat.alpha), d2W_dI1(Ib, mat.C, mat.alpha)
    m = asm.edofs.shape[1] + asm.qdofs.shape[1]
    re, Ke = np.empty((ne, m)), np.empty((ne, m, m))
    _elements(G, f, w1, w2, asm.w, asm.psi, qe, asm.M, 1.0 / mat.kappa, re, Ke)
    return np.bincount(asm._alld_flat, weights=re.ravel(), minlength=asm.ndof), Ke


def numpy_pass(asm, x, mat):
    """The same by the numpy assembly of ``fem.forms.Assembler``."""
    f, q = asm._fields(x)
    P, A, J = cm.total_stress(f, mat.C, mat.alpha, q=q, weight=asm.w)
    return asm._residual(x, P, J, mat), asm._tangent_values(f, A, mat)


def main() -> None:
    print(f"numba {nb.__version__}; min of 5 x 100 calls, interleaved")
    for mesh in ((4, 8), (16, 32)):
        prob = fb._setup(50e-6, 75e-6, 200.0, 0.2, 2.2e9, mesh)
        asm, mat = prob.asm, prob.mat
        G = np.ascontiguousarray(asm.B[..., [0, 1, 4], 0::2])  # (ne, nq, 3, n): dN/dR, dN/dZ, N/R
        assert np.array_equal(asm.B[..., [2, 3], 1::2], asm.B[..., [0, 1], 0::2])
        rng = np.random.default_rng(0)
        x = np.zeros(asm.ndof)
        x[: asm.n_u] = 2e-3 * rng.random(asm.n_u)
        x[asm.n_u :] = 0.1 * rng.random(asm.ndof - asm.n_u)
        t = time.perf_counter()
        re, Ke = compiled_pass(asm, G, x, mat)
        first = time.perf_counter() - t
        re0, Ke0 = numpy_pass(asm, x, mat)
        err_r = np.abs(re - re0).max() / np.abs(re0).max()
        err_K = np.abs(Ke - Ke0).max() / np.abs(Ke0).max()
        assert err_r < 1e-13 and err_K < 1e-13, (err_r, err_K)
        tc, tn = [], []
        for _ in range(5):
            t = time.perf_counter()
            for _ in range(100):
                compiled_pass(asm, G, x, mat)
            tc.append((time.perf_counter() - t) / 100)
            t = time.perf_counter()
            for _ in range(100):
                numpy_pass(asm, x, mat)
            tn.append((time.perf_counter() - t) / 100)
        print(
            f"blastula {mesh}: {asm.w.size} points; compiled {1e6 * min(tc):.0f} us, numpy {1e6 * min(tn):.0f} us "
            f"({min(tn) / min(tc):.2f}x); first call (compilation) {first:.2f} s; residuals within {err_r:.1e}, "
            f"blocks within {err_K:.1e}"
        )


if __name__ == "__main__":
    main()
