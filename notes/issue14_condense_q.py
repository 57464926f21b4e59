"""Would condensing the q field out of the blastula's Newton systems pay? (issue 14, tenth pass; not adopted)

``python notes/issue14_condense_q.py``: on a mid-sweep tangent (p = 500 Pa, B = 75 um, alpha = 0.2) of each uniform
mesh, the free saddle-point matrix [[K_uu, G^T], [G, -M/kappa]] against its Schur complement S = K_uu - K_uq D^-1
K_qu (D the 3 x 3 q-blocks of the elements, inverted at once; formed by scipy sparse products): dofs, the time to form
S, and SuperLU's symmetric-mode factorisation of each (orderings computed beforehand: MMD of K + K^T and the
supervariable MMD; median of 3) with its fill. Newton's iterates would be the same (block elimination of the same
linear system); the question is only whether the smaller LU gains more than forming S costs.
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from tissuemech.compare.bench import fem_perf as fp
from tissuemech.fem import newton as nw

SYM = dict(permc_spec="NATURAL", diag_pivot_thresh=0.0, options=dict(SymmetricMode=True))


def main() -> None:
    print(
        "mesh     dofs (saddle / S)   form S ms   LU saddle ms (MMD, supervariable)   LU S ms (MMD, supervariable)  fill"
    )
    for mesh in [(4, 8), (8, 16), (16, 32), (24, 48), (32, 64)]:
        prob, _, K = fp._blastula_state(mesh)
        K = K.tocsr()
        q = prob.free >= prob.asm.n_u
        iu, iq = np.flatnonzero(~q), np.flatnonzero(q)

        def schur():
            Kqq = K[iq][:, iq].tocoo()
            nb = iq.size // 3
            blocks = np.zeros((nb, 3, 3))
            blocks[Kqq.row // 3, Kqq.row % 3, Kqq.col % 3] = Kqq.data
            Dinv = sp.bsr_matrix((np.linalg.inv(blocks), np.arange(nb), np.arange(nb + 1)), shape=(3 * nb, 3 * nb))
            return (K[iu][:, iu] - K[iu][:, iq] @ (Dinv.tocsr() @ K[iq][:, iu])).tocsr()

        S = schur()
        t_form = fp._med(schur, 3)
        cols = []
        for M in (K, S):
            ts, fills = [], []
            for order in (nw._mmd, nw._supervariable_mmd):
                p = order(M)
                Mp = sp.csc_matrix(M[p][:, p])
                ts.append(fp._med(lambda: spla.splu(Mp, **SYM), 3))
                lu = spla.splu(Mp, **SYM)
                fills.append(lu.L.nnz + lu.U.nnz)
            cols.append((ts, fills))
        (ta, fa), (tb, fb_) = cols
        print(
            f"{mesh[0]:2d}x{mesh[1]:<3d}  {K.shape[0]:6d} / {S.shape[0]:6d}   {t_form * 1e3:8.2f}   "
            f"{ta[0] * 1e3:8.2f}, {ta[1] * 1e3:8.2f}                   {tb[0] * 1e3:8.2f}, {tb[1] * 1e3:8.2f}"
            f"               {min(fa) / 1e6:.2f}M -> {min(fb_) / 1e6:.2f}M",
            flush=True,
        )


if __name__ == "__main__":
    main()
