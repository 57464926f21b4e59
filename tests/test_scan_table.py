"""compare.scan.table: unit-labelled column names of a scan table."""

import numpy as np
import pandas as pd
import pytest

from tissuemech.compare import scan


def test_column_and_unit():
    assert scan.column("C") == "C [Pa]" and scan.column("alpha") == "alpha [-]" and scan.column("tau") == "tau [s]"
    assert scan.unit_of("radius") == "m" and scan.unit_words("beta") == "dimensionless"
    assert scan.split_column("sigma_peak [Pa]") == ("sigma_peak", "Pa") and scan.split_column("batch_id") == (
        "batch_id",
        "",
    )
    with pytest.raises(ValueError, match="'E' is not a quantity of a scan table"):
        scan.column("E")


def test_scene_and_varied_parameters():
    t = scan.blastula(alpha=[0.1, 0.2], pressure=10.0, n=1)
    assert scan.scene_of(t) == "blastula" and scan.parameters_of(t) == scan.BLASTULA_PARAMS
    assert scan.varied_parameters(t) == ["alpha"]
    with pytest.raises(ValueError, match="not a scan table"):
        scan.scene_of(pd.DataFrame({"x [m]": [1.0]}))


def test_log_sampling_guess():
    assert scan.is_log_sampled(np.geomspace(1.0, 1000.0, 50), "tau", None)
    assert not scan.is_log_sampled(np.linspace(1.0, 1000.0, 50), "tau", None)
    assert scan.is_log_sampled(np.linspace(1.0, 2.0, 5), "tau", ("tau",))
