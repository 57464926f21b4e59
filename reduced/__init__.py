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
"""

import jax

jax.config.update("jax_enable_x64", True)

__all__ = ["material"]
