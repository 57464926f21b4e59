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
import importlib.abc
import sys
from importlib.metadata import PackageNotFoundError, version
from typing import Any

try:
    __version__ = version("tissuemech")
except PackageNotFoundError:  # running from a checkout that is not installed
    __version__ = "0.3.0"

__all__ = ["__version__", "compare", "fem", "reduced"]

_SUBPACKAGES = ("reduced", "fem", "compare")


class _ShippedOnly(importlib.abc.MetaPathFinder):
    """Only the shipped subpackages import as ``tissuemech.*``. The package's folder is the repository root
    (pyproject maps it), so without this an editable install would also expose ``tissuemech.tests``,
    ``tissuemech.docs``, ``tissuemech.build``... (the wheel holds nothing else, so there it changes nothing)."""

    def find_spec(self, fullname: str, path: Any = None, target: Any = None) -> None:
        head, _, rest = fullname.partition(".")
        if head == __name__ and rest and "." not in rest and rest not in _SUBPACKAGES:
            raise ModuleNotFoundError(
                f"No module named {fullname!r} (tissuemech ships {', '.join(_SUBPACKAGES)})", name=fullname
            )
        return None


if not any(type(f).__name__ == "_ShippedOnly" for f in sys.meta_path):
    sys.meta_path.insert(0, _ShippedOnly())


def __getattr__(name: str) -> Any:
    if name in _SUBPACKAGES:
        return importlib.import_module(f"{__name__}.{name}")
    raise AttributeError(f"module 'tissuemech' has no attribute {name!r}")
