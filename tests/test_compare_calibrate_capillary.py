"""The elastocapillary table (reduced/data/capillary_master.npz) against a converged FE reference
(tests/data/capillary_reference.json: levels 1-3, Richardson with the observed order; its ``command`` wrote it)."""

import json
from pathlib import Path

import numpy as np
import pytest

from tissuemech.compare import calibrate_capillary as cc
from tissuemech.reduced import capillary as cap

REF = Path(__file__).parent / "data" / "capillary_reference.json"


def _ref() -> dict:
    return json.loads(REF.read_text())


def test_reference_is_off_the_nodes_and_converged():
    ref, t = _ref(), cap.capillary_table()
    pts = ref["points"]
    assert len(pts) >= 4 and ref["levels"] == [1, 2, 3] and "command" in ref
    assert any(p["x"] <= 0.05 for p in pts)  # small compressions included
    for p in pts:
        assert np.min(np.abs(t.gamma - p["Gamma"])) > 1e-6 and np.min(np.abs(t.alpha - p["alpha"])) > 1e-6
        f = [p["f_levels"][str(v)] for v in ref["levels"]]
        # monotone convergence toward the estimate: the finest level is the closest
        assert abs(f[-1] - p["f_ref"]) <= abs(f[0] - p["f_ref"])


def test_table_within_5e_4_of_the_converged_reference():
    err, at = cc.reference_error(_ref())
    assert err <= 5e-4, at
    assert cap.capillary_table().metadata["reference_error_f"] == pytest.approx(err, rel=1e-6)


def test_reference_richardson_recovers_a_second_order_limit():
    """Synthetic curves f_level = f_inf (1 + K h^2): the reference returns f_inf and p = 2."""
    from tissuemech.fem.spheroid import LEVELS

    x = np.array([0.05, 0.1])
    curves = [dict(alpha=0.3, Gamma=0.7, level=lev, x=x, f=x * (1 + 3.0 / LEVELS[lev][0] ** 2)) for lev in (1, 2, 3)]
    ref = cc.reference([(0.3, 0.7)], curves=curves)
    np.testing.assert_allclose([p["f_ref"] for p in ref["points"]], x, rtol=1e-10)
    np.testing.assert_allclose([p["observed_order"] for p in ref["points"]], 2.0, rtol=1e-6)
    with pytest.raises(ValueError, match="three mesh levels"):
        cc.reference([(0.3, 0.7)], levels=(1, 2), curves=curves)


@pytest.mark.slow
def test_reference_level_1_reproduces():
    """The stored level-1 values are what capillary_curve gives now (one column, level 1), to the balanced reference
    of a surface tension (fem.surface), which came after them: it moves level-1 states by 6.2e-6 at x = 0.025 (the
    smallest forces) down to 7e-8 at x = 0.25, level-2 ones by 8.4e-7 to 4.6e-8 (order 3), so the stored Richardson
    reference of levels 1-3 moves by ~1e-7, far below the table's 3.2e-5 from it."""
    ref = _ref()
    p0 = ref["points"][0]
    col = [p for p in ref["points"] if p["alpha"] == p0["alpha"] and p["Gamma"] == p0["Gamma"]]
    xs = np.array([p["x"] for p in col])
    fe = cc.capillary_curve(alpha=p0["alpha"], Gamma=p0["Gamma"], x_max=xs[-1], n=xs.size, mesh=1)
    np.testing.assert_allclose(fe["x"], xs, rtol=1e-12)
    np.testing.assert_allclose(fe["f"], [p["f_levels"]["1"] for p in col], rtol=1e-5)
