"""The figure of ``tissuemech fit``: the records, the fitted model and the residuals."""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np

from tissuemech.compare.plots import pyplot as _plt

__all__ = ["fit_figure", "protocol_figure", "fe_fit_figure", "tension_fit_figure"]

UM = 1e-6
DISPLAY_SAMPLES = 4000  # records longer than this are drawn as bin means (compare.fit.compress.bin_record)


def fit_figure(
    records: Sequence[tuple], result: Any, *, radius: float, ramp_time: float, equilibrium: Any, midplane: Any
):
    """Data and model (top, symlog time axis) and residuals (bottom) of a fit; ``records`` as fitted (time s,
    nominal stress Pa, displacement m; records longer than :data:`DISPLAY_SAMPLES` are drawn as bin means),
    ``result`` its :class:`~tissuemech.compare.fit.FitResult`, the keywords those of the model (SI). Returns the
    figure (nothing is shown or saved here)."""
    from tissuemech.reduced import spheroid

    plt = _plt()
    p = result.params
    bn = [n for n in result.names if n.startswith("beta")]
    tn = [n for n in result.names if n.startswith("tau")]
    branches = [(p[b], p[t]) for b, t in zip(bn, tn)]
    fig, (ax, axr) = plt.subplots(2, 1, figsize=(7, 6), sharex=True, gridspec_kw={"height_ratios": [3, 1.3]})
    for j, (t, y, d) in enumerate(records):
        what = "data"
        if np.size(t) > DISPLAY_SAMPLES:  # a dense record: its bin means (cheap to draw, the noise averaged)
            from tissuemech.compare.fit.compress import bin_record

            b = bin_record(t, y, ramp_time, DISPLAY_SAMPLES // 2)
            t, y, what = b.time, b.stress, f"data ({b.count.size} bin means)"
        kw = dict(radius=radius, C=p["C"], alpha=p["alpha"], branches=branches, displacement=d)
        kw.update(ramp_time=ramp_time, equilibrium=equilibrium, midplane=midplane)
        tt = np.unique(np.concatenate([np.linspace(0, max(t.max(), 1e-9), 400), t]))
        m_dense = np.asarray(spheroid.nominal_stress(tt, **kw))  # one evaluation (one compiled shape): t is in tt
        m = m_dense[np.searchsorted(tt, t)]
        if result.model_error_factors:
            m_dense = m_dense * result.model_error_factors[j]
            m = m * result.model_error_factors[j]
        line = ax.plot(t, y, ".", ms=3, label=f"{what}, {d / UM:.4g} um")[0]
        ax.plot(tt, m_dense, "-", color=line.get_color(), lw=1.2, label=f"model, {d / UM:.4g} um")
        axr.plot(t, y - m, ".", ms=3, color=line.get_color())
    ax.set_xscale("symlog", linthresh=max(ramp_time, 1e-6))
    ax.set_ylabel("nominal stress F / A_mid (Pa)")
    txt = ", ".join(f"{n} = {p[n]:.4g}" for n in result.names)
    ax.set_title("tissuemech fit: " + txt, fontsize=8)
    ax.legend(fontsize=7, ncol=2)
    axr.axhline(0.0, color="k", lw=0.6)
    axr.set_ylabel("residual (Pa)")
    axr.set_xlabel("time (s)")
    fig.tight_layout()
    return fig


def protocol_figure(records: Sequence[Any], result: Any, *, radius: float, ramp_time: float, equilibrium: Any):
    """Data and model (top) and residuals (bottom) of every record of a
    :func:`~tissuemech.compare.fit.protocols.records_fit` (one column per record: nominal stress in Pa, approach in
    um or force in uN against time in s). Returns the figure (nothing is shown or saved here)."""
    from tissuemech.compare.fit.protocols import predict, protocol_of

    plt = _plt()
    n = len(records)
    fig, axes = plt.subplots(
        2, n, figsize=(4.2 * n, 6), squeeze=False, sharex="col", gridspec_kw={"height_ratios": [3, 1.3]}
    )
    for j, rec in enumerate(records):
        kind = protocol_of(rec)
        t = np.asarray(rec[0])
        y = np.asarray(rec[1] if kind != "history" else rec[2])
        label, unit, k = {
            "relaxation": ("nominal stress", "Pa", 1.0),
            "creep": ("approach", "um", 1e6),
            "history": ("force", "uN", 1e6),
        }[kind]
        tt = np.unique(np.concatenate([np.linspace(0.0, max(float(t.max()), 1e-9), 400)[1:], t]))
        if kind == "history":
            tt = tt[tt >= t.min()]
        kw = dict(radius=radius, ramp_time=ramp_time, equilibrium=equilibrium)
        m = predict(rec, result.params, **kw)
        m_dense = predict(rec, result.params, times=tt, **kw)
        if result.model_error_factors:
            m, m_dense = m * result.model_error_factors[j], m_dense * result.model_error_factors[j]
        ax, axr = axes[0, j], axes[1, j]
        ax.plot(t, k * y, ".", ms=3, label="data")
        ax.plot(tt, k * m_dense, "-", lw=1.2, label="model")
        axr.plot(t, k * (y - m), ".", ms=3)
        axr.axhline(0.0, color="k", lw=0.6)
        ax.set_xscale("symlog", linthresh=max(ramp_time, 1e-6))
        ax.set_title(f"record {j + 1}: {kind}", fontsize=9)
        ax.set_ylabel(f"{label} ({unit})")
        axr.set_ylabel(f"residual ({unit})")
        axr.set_xlabel("time (s)")
        ax.legend(fontsize=7)
    txt = ", ".join(f"{nm} = {result.params[nm]:.4g}" for nm in result.names)
    fig.suptitle("tissuemech fit: " + txt, fontsize=8)
    fig.tight_layout()
    return fig


def fe_fit_figure(records: Sequence[tuple], result: Any, *, ramp_time: float):
    """Data and model (top, symlog time axis) and residuals (bottom) of an FE-in-the-loop fit
    (:func:`~tissuemech.compare.fit.fe_relaxation`): ``records`` as fitted (time s, nominal stress Pa, displacement
    m), ``result`` its :class:`~tissuemech.compare.fit.FEFitResult` (the model lines are its FE step curves, the
    residuals its model at the records' times). Returns the figure (nothing is shown or saved here)."""
    plt = _plt()
    p = result.params
    fig, (ax, axr) = plt.subplots(2, 1, figsize=(7, 6), sharex=True, gridspec_kw={"height_ratios": [3, 1.3]})
    for (t, y, d), m, (tt, ss) in zip(records, result.model, result.curves):
        line = ax.plot(t, y, ".", ms=3, label=f"data, {d / UM:.4g} um")[0]
        ax.plot(tt, ss, "-", color=line.get_color(), lw=1.2, label=f"FE model, {d / UM:.4g} um")
        axr.plot(t, np.asarray(y) - m, ".", ms=3, color=line.get_color())
    ax.set_xscale("symlog", linthresh=max(ramp_time, 1e-6))
    ax.set_ylabel("nominal stress F / A_mid (Pa)")
    txt = ", ".join(f"{n} = {p[n]:.4g}" for n in result.names)
    ax.set_title(f"tissuemech fit --model fe (mesh {result.mesh}): " + txt, fontsize=8)
    ax.legend(fontsize=7, ncol=2)
    axr.axhline(0.0, color="k", lw=0.6)
    axr.set_ylabel("residual (Pa)")
    axr.set_xlabel("time (s)")
    fig.tight_layout()
    return fig


def tension_fit_figure(records: Sequence[tuple], result: Any, *, radius: float, ramp_time: float):
    """Data and the elastocapillary model (top, log time) and residuals (bottom) of a surface-tension fit
    (``compare.fit.tension.TensionFit``; records as fitted: time s, nominal stress Pa, displacement m). Returns the
    figure."""
    from tissuemech.reduced import spheroid

    p = result.params
    taus = sorted(k for k in p if k.startswith("tau"))
    br = [(p["beta" + k[3:]], p[k]) for k in taus]
    plt = _plt()
    fig, (ax, axr) = plt.subplots(2, 1, figsize=(6.4, 6.0), sharex=True, gridspec_kw=dict(height_ratios=(3, 1)))
    for k, (t, y, d) in enumerate(records):
        m = np.asarray(spheroid.nominal_stress(t, radius=radius, C=p["C"], alpha=p["alpha"], branches=br,
                                               displacement=d, ramp_time=ramp_time, surface_tension=p["gamma"],
                                               midplane=getattr(result, "midplane", "fem")))  # fmt: skip
        ax.plot(t, y, ".", ms=3, color=f"C{k}", label=f"record {k + 1}: delta = {d / UM:.3g} um")
        ax.plot(t, m, "-", color=f"C{k}")
        axr.plot(t, y - m, ".", ms=3, color=f"C{k}")
    lo, hi = result.intervals["gamma"]
    ax.set_title(f"gamma = {p['gamma'] * 1e3:.4g} mN/m (95 %: {lo * 1e3:.4g} to {hi * 1e3:.4g}), C = {p['C']:.4g} Pa")
    ax.set_ylabel("nominal stress (Pa)")
    axr.set_ylabel("residual (Pa)")
    axr.set_xlabel("time (s)")
    ax.set_xscale("log")
    ax.legend(fontsize=8)
    fig.tight_layout()
    return fig
