"""Former home of the scan figures and sensitivities: an alias of ``compare.plots.scan`` (figures) and of
``compare.scan`` (``sensitivities``, ``scene_of``, ``varied_parameters``)."""

from tissuemech.compare.plots.scan import (
    BLASTULA_SUMMARIES,
    SPHEROID_SUMMARIES,
    axis_label,
    curve_bundle,
    display_values,
    parity_plot,
    sensitivity_chart,
    summary_map,
    summary_maps,
)
from tissuemech.compare.scan import scene_of, sensitivities, varied_parameters

__all__ = [
    "SPHEROID_SUMMARIES",
    "BLASTULA_SUMMARIES",
    "scene_of",
    "varied_parameters",
    "axis_label",
    "display_values",
    "summary_map",
    "summary_maps",
    "curve_bundle",
    "parity_plot",
    "sensitivities",
    "sensitivity_chart",
]
