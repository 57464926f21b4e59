"""compare.studies.accuracy: the Pareto front of (wall time, error)."""

import numpy as np
import pandas as pd
import pytest

from tissuemech.compare.plots.charts import time_convergence_chart
from tissuemech.compare.studies.accuracy import pareto, spheroid_time_convergence


def test_pareto_front_marks_non_dominated_rows():
    df = pd.DataFrame({"wall_time [s]": [1.0, 2.0, 0.5, 3.0, np.nan], "error": [1e-3, 1e-6, 1e-2, 1e-6, 1e-9]})
    assert pareto(df).tolist() == [True, True, True, False, False]


@pytest.mark.slow
def test_spheroid_time_convergence_quick_converges_and_adaptive_beats_its_fixed_peer():
    """Issue 35, quick study (level 0): fixed steps converge monotonically (each doubling divides the worst error
    by > 2.5), the lumped estimate is within a factor 2 of the FE's error, and the adaptive row is more accurate
    than the fixed run with as many ramp steps."""
    df = spheroid_time_convergence(quick=True)
    fx, ad = df[df.method == "FE fixed"], df[df.method == "FE adaptive"]
    e = fx.error.to_numpy(float)
    assert np.all(e[:-1] / e[1:] > 2.5), e
    ratio = fx["lumped estimate"].to_numpy(float) / e
    assert np.all((ratio > 0.5) & (ratio < 2.0)), ratio
    n_ad = int(ad.ramp_steps.iloc[0])
    e_fixed_same = np.interp(np.log(n_ad), np.log(fx.ramp_steps.to_numpy(float)), np.log(e))
    assert ad.error.iloc[0] < np.exp(e_fixed_same)
    fig = time_convergence_chart(df, title="t")
    assert len(fig.axes[0].lines) >= 5
