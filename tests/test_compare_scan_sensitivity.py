"""compare.scan.fe_sensitivities: the scan's sensitivities computed by the FE (exact parameter sensitivities at
spot-checks) agree with the reduced model's exact JAX derivatives where both exist."""

from __future__ import annotations

import numpy as np
import pytest

from tissuemech.compare import scan


@pytest.mark.slow
def test_fe_sensitivities_agree_with_the_reduced_ones_inside_the_table():
    """A 2 x 2 grid in alpha and beta (inside the plate table: alpha <= 0.4, x = 0.2): the FE's derivatives of
    sigma_peak, sigma_end and the relaxed fraction (coarse mesh, node-by-node contact, at the scan's times) match
    the reduced model's at the same four points, and both say the same parameter drives each summary. Measured:
    beta's mean |dy/du| within 4e-4, alpha's within 1.3 % (the coarse mesh's error of the alpha-dependence, which
    the table calibrates on finer meshes; alpha's share of sigma_peak is 6.6 % against 6.7 %)."""
    df = scan.spheroid(alpha=[0.1, 0.4], beta=[0.4, 1.0], C=150.0, tau=200.0, displacement=200e-6, n=2)
    red = scan.sensitivities(df, log=()).set_index(["quantity", "parameter"])
    fe = scan.fe_sensitivities(df, k=len(df), log=()).set_index(["quantity", "parameter"])
    for q, p, tol in [("sigma_peak", "alpha", 0.02), ("sigma_end", "alpha", 0.02), ("sigma_peak", "beta", 1e-3),
                      ("sigma_end", "beta", 1e-3), ("relaxed_fraction", "beta", 1e-3)]:  # fmt: skip
        a, b = fe.loc[(q, p), "mean_abs_dy_du"], red.loc[(q, p), "mean_abs_dy_du"]
        assert a == pytest.approx(b, rel=tol), (q, p, a, b)
        assert fe.loc[(q, p), "direction"] == red.loc[(q, p), "direction"]
    for q in ("sigma_peak", "sigma_end", "relaxed_fraction", "t_half"):
        assert fe.loc[q, "share [-]"].idxmax() == red.loc[q, "share [-]"].idxmax()
    assert fe.loc[("relaxed_fraction", "alpha"), "share [-]"] < 1e-4  # the relaxed fraction does not see alpha
    assert np.all(fe["points"] == len(df))
