"""compare.plots.scan: maps put FE spot-checks at their design coordinates, cells hold the right
averages, curves satisfy the model, parity points are the (FE, reduced) pairs, sensitivities are
the exact derivatives (finite differences, scaling laws)."""

from __future__ import annotations

import matplotlib

matplotlib.use("Agg")

import numpy as np
import pytest
from fakes import fake_nominal_stress

from tissuemech.compare import scan
from tissuemech.compare.plots import scan as sp


@pytest.fixture(scope="module")
def blastula_grid():
    """A grid blastula scan with two FE 'spot-checks' written in by hand (no FE needed here)."""
    df = scan.blastula(
        alpha=[1e-5, 0.1, 0.3], outer_radius=[60e-6, 75e-6], C=[150.0, 250.0], pressure=(0.0, 200.0), n=5
    )
    df["fe_inner_stretch [-]"] = np.nan
    df["deviation [-]"] = np.nan
    holds = np.nonzero(df["inner_stretch [-]"].notna().to_numpy() & (df["pressure [Pa]"] > 0).to_numpy())[0]
    for i, d in ((holds[5], 0.012), (holds[30], 0.0031)):
        df.loc[i, "fe_inner_stretch [-]"] = df.loc[i, "inner_stretch [-]"] * (1 + d)
        df.loc[i, "deviation [-]"] = d
    return df


@pytest.fixture(scope="module")
def spheroid_lhs():
    df = scan.spheroid(
        C=(100.0, 300.0),
        tau=(10.0, 1000.0),
        beta=(0.2, 1.5),
        n=60,
        design_method="lhs",
        model=fake_nominal_stress,
        equilibrium="fake",
        curves=True,
    )
    for c in ("fe_sigma_peak [Pa]", "fe_sigma_end [Pa]", "deviation [-]"):
        df[c] = np.nan
    for i in (4, 17, 33):
        df.loc[i, "fe_sigma_peak [Pa]"] = df.loc[i, "sigma_peak [Pa]"] / 1.01
        df.loc[i, "fe_sigma_end [Pa]"] = df.loc[i, "sigma_end [Pa]"] / 1.03
        df.loc[i, "deviation [-]"] = 0.03
    return df


def _by_gid(ax, gid):
    return [c for c in ax.collections if c.get_gid() == gid]


def test_map_puts_fe_checks_at_design_coordinates(blastula_grid, tmp_path):
    df = blastula_grid
    fig = sp.summary_map(df, "inner_stretch", "outer_radius", "pressure")
    ax = fig.axes[0]
    (pts,) = _by_gid(ax, "fe-checks")
    chk = df[df["deviation [-]"].notna()]
    # radii shown in um, pressure in Pa: each marker at its design point
    expected = np.column_stack([chk["outer_radius [m]"] * 1e6, chk["pressure [Pa]"]])
    assert np.allclose(pts.get_offsets(), expected, rtol=1e-12)
    labels = sorted(t.get_text() for t in ax.texts)
    assert labels == ["0.31%", "1.2%"]
    assert ax.get_xlabel() == "outer radius B (um)" and ax.get_ylabel() == "pressure p (Pa)"
    fig.savefig(tmp_path / "m.png")
    assert (tmp_path / "m.png").stat().st_size > 10_000


def test_map_cells_are_means_over_the_other_parameters(blastula_grid):
    df = blastula_grid
    fig = sp.summary_map(df, "inner_stretch", "alpha", "pressure")
    (mesh,) = _by_gid(fig.axes[0], "map")
    Z = np.ma.filled(mesh.get_array(), np.nan).reshape(5, 3)  # (pressure, alpha)
    want = df.groupby(["pressure [Pa]", "alpha [-]"])["inner_stretch [-]"].mean().unstack().to_numpy()
    assert np.allclose(Z, want, rtol=1e-13, equal_nan=True)
    # held fixed instead of averaged: the cells are the rows at that value
    fig = sp.summary_map(df, "inner_stretch", "alpha", "pressure", fixed={"C": 150.0, "outer_radius": 75e-6})
    (mesh,) = _by_gid(fig.axes[0], "map")
    sel = df[(df["C [Pa]"] == 150.0) & (df["outer_radius [m]"] == 75e-6)]
    want = sel.pivot(index="pressure [Pa]", columns="alpha [-]", values="inner_stretch [-]").to_numpy()
    assert np.allclose(np.ma.filled(mesh.get_array(), np.nan).reshape(5, 3), want, rtol=1e-13, equal_nan=True)
    assert "C = 150 Pa" in fig.axes[0].get_title()


def test_scattered_map_and_fe_points(spheroid_lhs):
    df = spheroid_lhs
    fig = sp.summary_maps(df, ["sigma_peak", "relaxed_fraction", "t_half"], "C", "tau")
    assert len([a for a in fig.axes if _by_gid(a, "map")]) == 3
    for ax in fig.axes:
        for pts in _by_gid(ax, "fe-checks"):
            chk = df[df["deviation [-]"].notna()]
            assert np.allclose(pts.get_offsets(), chk[["C [Pa]", "tau [s]"]].to_numpy(), rtol=1e-12)
    assert fig.axes[0].get_yscale() == "log"  # tau spans 100x
    with pytest.raises(ValueError, match="two different"):
        sp.summary_map(df, "t_half", "C", "C")
    with pytest.raises(ValueError, match="not a column"):
        sp.summary_map(df, "inner_stretch", "C", "tau")


def test_parity_points_are_fe_reduced_pairs(spheroid_lhs, blastula_grid):
    df = spheroid_lhs
    fig = sp.parity_plot(df)
    ax = fig.axes[0]
    chk = df[df["deviation [-]"].notna()]
    offsets = [c.get_offsets() for c in ax.collections]
    assert np.allclose(offsets[0], chk[["fe_sigma_peak [Pa]", "sigma_peak [Pa]"]].to_numpy())
    assert np.allclose(offsets[1], chk[["fe_sigma_end [Pa]", "sigma_end [Pa]"]].to_numpy())
    assert "(Pa)" in ax.get_xlabel() and "(Pa)" in ax.get_ylabel()
    fig = sp.parity_plot(blastula_grid)
    assert np.allclose(
        fig.axes[0].collections[0].get_offsets()[:, 1] / fig.axes[0].collections[0].get_offsets()[:, 0],
        1 / (1 + blastula_grid["deviation [-]"].dropna().to_numpy()),
    )
    with pytest.raises(ValueError, match="no FE spot-checks"):
        sp.parity_plot(df.drop(columns="deviation [-]"))
    # the colour scale covers the smallest deviation (it was clipped at 0.01 %, hiding 1e-5-level checks)
    tiny = blastula_grid.copy()
    tiny["deviation [-]"] = tiny["deviation [-]"] * 1e-4
    norm = sp.parity_plot(tiny).axes[0].collections[0].norm
    assert norm.vmin <= 100 * float(np.nanmin(np.abs(tiny["deviation [-]"]))) * (1 + 1e-9)


@pytest.mark.slow
def test_curve_bundles(spheroid_lhs, blastula_grid):
    from tissuemech.reduced import blastula as red

    fig = sp.curve_bundle(spheroid_lhs, "tau", max_curves=25)
    ax, ax_n = fig.axes[:2]
    assert len(ax.lines) == 25 and len(ax_n.lines) == 25
    assert max(ln.get_ydata().max() for ln in ax_n.lines) == pytest.approx(1.0)  # normalised by the peak
    assert ax.get_xscale() == "log" and "(s)" in ax.get_xlabel() and "(Pa)" in ax.get_ylabel()
    with pytest.raises(ValueError, match="curves=True"):
        sp.curve_bundle(spheroid_lhs.drop(columns="sigma [Pa]"), "tau")

    fig = sp.curve_bundle(blastula_grid, "alpha")
    ax = fig.axes[0]
    curves = [ln for ln in ax.lines if ln.get_linestyle() == "-"]
    assert len(curves) == 12  # the 3 x 2 x 2 (A, B, C, alpha) combinations
    # each curve is the exact shell: p(lambda_a) of reduced.blastula reproduces the plotted pressure
    combos = blastula_grid[["outer_radius [m]", "C [Pa]", "alpha [-]"]].drop_duplicates().to_numpy()
    for ln in curves:
        la, p = ln.get_xdata(), ln.get_ydata()
        ok = np.isfinite(la) & (p > 0)
        errs = [
            np.max(np.abs(np.asarray(red.pressure(la[ok], inner_radius=50e-6, outer_radius=B, C=C, alpha=a)) - p[ok]))
            for B, C, a in combos
        ]
        assert min(errs) < 1e-8
        # the curve ends at its limit point: no point of the re-stiffening branch beyond the limit stretch
        B, C, a = combos[int(np.argmin(errs))]
        lim = red.limit_point(inner_radius=50e-6, outer_radius=B, C=C, alpha=a)
        if lim is not None and np.isfinite(float(lim.pressure)):
            assert np.all(la[np.isfinite(la)] <= float(lim.inner_stretch) * (1 + 1e-9))


@pytest.mark.slow
def test_blastula_sensitivities_are_exact_derivatives(blastula_grid):
    from tissuemech.reduced import blastula as red

    df = blastula_grid
    sens = scan.sensitivities(df, n_points=1000, log=())
    assert set(sens["parameter"]) == {"outer_radius", "C", "alpha", "pressure"}
    g = sens[sens["quantity"] == "inner_stretch"].set_index("parameter")
    assert g["share [-]"].sum() == pytest.approx(1.0)
    # finite differences of the exact shell over the holding points, scaled to the scan ranges
    ok = df["inner_stretch [-]"].notna().to_numpy()  # holding points (p = 0 included: derivatives 0 there but in p)
    base = {k: df[scan.column(k)].to_numpy()[ok] for k in ("inner_radius", "outer_radius", "C", "alpha", "pressure")}

    def la(**kw):
        p = {**base, **kw}
        return np.asarray(red.inner_stretch_solve(p.pop("pressure"), **p)[0])

    ranges = {"outer_radius": 15e-6, "C": 100.0, "alpha": 0.3 - 1e-5, "pressure": 200.0}
    for k, span in ranges.items():
        h = 1e-6 * span
        fd = (la(**{k: base[k] + h}) - la(**{k: base[k] - h})) / (2 * h) * span
        assert g.loc[k, "mean_abs_dy_du"] == pytest.approx(np.mean(np.abs(fd)), rel=1e-5)
    assert g.loc["pressure", "direction"] == 1.0 and g.loc["C", "direction"] == -1.0
    lim = sens[sens["quantity"] == "p_limit"].set_index("parameter")
    assert lim.loc["pressure", "mean_abs_dy_du"] == 0.0  # the burst pressure does not depend on p
    # p_limit = C P(k, alpha): d p_limit / dC = p_limit / C (only alpha = 1e-5 has a limit point here)
    has = df["p_limit [Pa]"].notna()
    assert lim.loc["C", "points"] == has.sum() == 20
    want = np.mean(df.loc[has, "p_limit [Pa]"] / df.loc[has, "C [Pa]"]) * 100.0
    assert lim.loc["C", "mean_abs_dy_du"] == pytest.approx(want, rel=1e-10)


@pytest.mark.slow
def test_spheroid_sensitivities_scaling_laws():
    """Hertz: the stress is proportional to C (d ln sigma / d ln C = 1), the relaxed fraction and the
    half-relaxation time do not depend on C; after a fast ramp t_half - t_r ~ tau ln 2."""
    df = scan.spheroid(C=(100.0, 300.0), tau=(20.0, 100.0), n=3, equilibrium="hertz")
    sens = scan.sensitivities(df, equilibrium="hertz", log=())
    s = sens.set_index(["quantity", "parameter"])
    C = df["C [Pa]"].to_numpy()
    for q in ("sigma_peak", "sigma_end"):
        y = df[f"{q} [Pa]"].to_numpy()
        assert s.loc[(q, "C"), "mean_abs_dy_du"] == pytest.approx(np.mean(y / C) * 200.0, rel=1e-6)
    assert s.loc[("relaxed_fraction", "C"), "share [-]"] < 1e-9
    assert s.loc[("t_half", "C"), "share [-]"] < 1e-9
    assert s.loc[("t_half", "tau"), "mean_abs_dy_du"] == pytest.approx(np.log(2) * 80.0, rel=0.03)
    # tau << hold: fully relaxed at the end either way, but a longer tau relaxes less during the ramp
    # (higher peak), so the relaxed fraction grows with tau
    assert s.loc[("relaxed_fraction", "tau"), "direction"] == 1.0
    fig = sp.sensitivity_chart(sens)
    assert len(fig.axes[0].texts) == 8


def test_sensitivity_chart_and_labels(blastula_grid, tmp_path):
    sens = scan.sensitivities(blastula_grid, n_points=40)
    fig = sp.sensitivity_chart(sens)
    ax = fig.axes[0]
    assert [t.get_text() for t in ax.get_xticklabels()] == [
        "outer radius B (um)",
        "Fung stiffness C (Pa)",
        "Fung exponent alpha (-)",
        "pressure p (Pa)",
    ]
    texts = [t.get_text() for t in ax.texts]
    assert all(t.endswith("%") for t in texts) and len(texts) == 8
    fig.savefig(tmp_path / "s.png")
    assert sp.axis_label("t_half") == "half-relaxation time (s)" and sp.axis_label("radius") == "radius a0 (um)"


def test_blastula_bundle_ends_at_the_limit_point():
    """A low-alpha shell bursts at its limit point and re-stiffens far beyond it: the bundle draws the curve up to
    the limit stretch only (it drew fragments of the re-stiffening branch above the limit pressure)."""
    from tissuemech.reduced import blastula as red

    table = scan.blastula(alpha=[0.02], outer_radius=[75e-6], C=[200.0], pressure=(0.0, 1000.0), n=3)
    ax = sp.curve_bundle(table, "alpha").axes[0]
    lim = red.limit_point(inner_radius=50e-6, outer_radius=75e-6, C=200.0, alpha=0.02)
    assert lim is not None
    la = np.concatenate([ln.get_xdata() for ln in ax.lines if ln.get_linestyle() == "-"])
    assert np.isfinite(la).any() and np.nanmax(la) <= float(lim.inner_stretch) * (1 + 1e-9)
