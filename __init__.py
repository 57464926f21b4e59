"""tissuemech: mechanics of developing tissue, fast enough for parameter scans, accurate enough to trust.

Two halves and the layer where they meet (SI units at every public function: m, Pa, s, N):

- :mod:`tissuemech.reduced`: JAX + diffrax reduced-order models (exact thick shell, viscoelastic
  shell, lumped generalized-Maxwell spheroid). Importing it switches JAX to float64.
- :mod:`tissuemech.fem`: scikit-fem axisymmetric finite-strain FE (mixed u-p, exact rigid-plate
  contact, viscoelastic internal variables).
- :mod:`tissuemech.compare`: calibration, scans, fits, studies, figures, the report and the CLI.

The main entry points are imported lazily (``tissuemech.reduced`` pulls in JAX, ``tissuemech.fem``
scikit-fem), so ``import tissuemech`` stays cheap::

    import tissuemech
    tissuemech.__version__
    tissuemech.reduced.blastula.pressure(...)
"""

from __future__ import annotations

import importlib
from importlib.metadata import PackageNotFoundError, version
from typing import Any

try:
    __version__ = version("tissuemech")
except PackageNotFoundError:  # running from a checkout that is not installed
    __version__ = "0.3.0"

__all__ = ["__version__", "compare", "fem", "reduced"]


def __getattr__(name: str) -> Any:
    if name in ("reduced", "fem", "compare"):
        return importlib.import_module(f"{__name__}.{name}")
    raise AttributeError(f"module 'tissuemech' has no attribute {name!r}")
