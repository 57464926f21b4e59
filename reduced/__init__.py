"""tissuemech.reduced: the fast half (JAX + diffrax, float64, SI units at the API).

Importing this package switches JAX to 64-bit floats; every model here is a pure function
that works under ``jax.jit``, ``jax.vmap`` and ``jax.grad``.

Modules
-------
material   Fung energy and its scalar derivatives (shared with ``fem``)
validation input checks with messages naming the quantity and unit (re-exported by ``material``)
blastula   exact thick incompressible shell: p(lambda_a), inverse, limit point, profiles
viscoshell the shell with generalized-Maxwell branches: inflation history under p(t)
spheroid   lumped generalized-Maxwell plate force of a compressed ball
indentation the same for a spherical probe on a ball resting on a plate (AFM)
oscillation the spheroid's dynamic stiffness (storage, loss) under a small sinusoidal approach
drop       the Young-Laplace liquid drop between plates (scipy, not JAX: one small solve per approach)
liquid     the lumped viscoelastic liquid with surface tension (drop plateau, elastocapillary instant)
"""

from __future__ import annotations

import importlib
import os
import sys
from typing import Any

# 64-bit floats in JAX, without importing JAX here (it costs ~1-3 s; a command that never evaluates a JAX model
# should not pay it): JAX reads JAX_ENABLE_X64 when it is first imported; if it is already imported, it is switched
if "jax" in sys.modules:
    sys.modules["jax"].config.update("jax_enable_x64", True)
else:
    os.environ["JAX_ENABLE_X64"] = "1"

__all__ = ["material", "validation", "blastula", "viscoshell", "spheroid", "indentation", "drop", "liquid", "interp"]


def __getattr__(name: str) -> Any:
    """The modules on first use (``tissuemech.reduced.spheroid`` after ``import tissuemech.reduced``)."""
    if name in __all__:
        return importlib.import_module(f"{__name__}.{name}")
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
