"""compare.calibrate_indentation: the FE-calibrated indentation table's generator."""

import json

import numpy as np
import pytest

from tissuemech.compare import calibrate_indentation as ci
from tissuemech.reduced import indentation as ri


def test_depth_ratio_is_the_probe_contact_depth_over_its_radius():
    rho, x = 0.3, 0.01
    d1, _ = ri.contact_depths(2 * x, radius=1.0, probe_radius=rho)
    assert ci.depth_ratio(x, rho) == pytest.approx(float(d1) / (rho / (1 + rho)), rel=1e-13)
    assert ci.x_of_depth_ratio(ci.depth_ratio(x, rho), rho) == pytest.approx(x, rel=1e-14)


@pytest.mark.slow
def test_tabulate_writes_a_richardson_table_the_reduced_model_reads(tmp_path):
    """A small grid on levels 0 and 1 (no check): the extrapolation formula, the file, ``MasterTable`` at a node."""
    table, meta = ci.tabulate(
        rhos=(0.2, 1.0), alphas=(0.0, 0.5), ys=(0.0125, 0.025, 0.05), mesh=1, coarse_mesh=0, check_mesh=None,
        executor="serial",
    )  # fmt: skip
    g = 1.0 / ((10 / 6) ** ci.ORDER - 1.0)  # n_zone of levels 1 and 0
    assert np.allclose(table["h"][:, :, 1:], table["h_fine"] + (table["h_fine"] - table["h_coarse"]) * g, rtol=1e-14)
    assert np.all(table["h"][:, :, 0] == 1.0) and meta["y_max"] == 0.05 and meta["richardson_order"] == ci.ORDER
    assert np.all(table["h"][1, :, 1:] > 1.0)  # R_p = a0: finite strain stiffens, as the plates
    path = tmp_path / "t.npz"
    ci.write(path, table, meta)
    tab = ri.master_table(str(path))
    assert json.loads(json.dumps(tab.metadata))["mesh"] == 1
    x = ri.x_of_depth_ratio(0.025, 1.0)
    assert float(tab(np.array([x]), 0.5, 1.0)[0]) == pytest.approx(table["h"][1, 1, 2], rel=1e-12)
