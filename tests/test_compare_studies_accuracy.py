"""compare.studies.accuracy: the Pareto front of (wall time, error)."""

import numpy as np
import pandas as pd

from tissuemech.compare.studies.accuracy import pareto


def test_pareto_front_marks_non_dominated_rows():
    df = pd.DataFrame({"wall_time [s]": [1.0, 2.0, 0.5, 3.0, np.nan], "error": [1e-3, 1e-6, 1e-2, 1e-6, 1e-9]})
    assert pareto(df).tolist() == [True, True, True, False, False]
