"""Shared fakes for the tests (a helper module, not a test module: tests import it, pytest collects nothing here).

``fake_nominal_stress``: a small JAX fake of the lumped generalized-Maxwell law with the signature of
``reduced.spheroid.nominal_stress`` and a Fung-stiffened equilibrium
F_eq = C a0^2 (32/3) x^1.5 exp(4 alpha x), x = delta/(2 a0), A_mid = pi a0^2 (1 + x) [SI in, Pa out].
The ramp is integrated by the exact-for-linear-S recursion on 400 substeps; during the hold q decays
exactly as exp(-(t - t_r)/tau).

``static_compression``: the static FE compression of the 500 um ball (C = 200 Pa) to x = delta / (2 a0), shared
by the FE contact and spheroid tests.
"""

from __future__ import annotations

import jax.numpy as jnp

import tissuemech.reduced  # noqa: F401  (float64 on)


def fake_nominal_stress(t, *, radius, C, alpha, branches, displacement, ramp_time, equilibrium="fake"):
    t = jnp.asarray(t, dtype=jnp.float64)
    x_end = displacement / (2 * radius)

    def feq(x):
        return C * radius**2 * (32.0 / 3.0) * x**1.5 * jnp.exp(4.0 * alpha * x)

    n = 400
    s = jnp.linspace(0.0, 1.0, n + 1)
    f = feq(x_end * s)
    dt = ramp_time / n
    xt = jnp.clip(t / ramp_time, 0.0, 1.0)
    force = feq(x_end * xt)
    for beta, tau in branches:
        h = dt / tau
        a = jnp.exp(-h)
        g = beta * (-jnp.expm1(-h)) / h
        # q_{k+1} = a q_k + g (f_{k+1} - f_k): closed sum over the ramp nodes
        df = jnp.diff(f)
        k = jnp.arange(1, n + 1)
        qn = jnp.cumsum(df * a ** (-k)) * a**k
        qn = jnp.concatenate([jnp.zeros(1), qn]) * g
        q_ramp = jnp.interp(t, s * ramp_time, qn)
        q_hold = qn[-1] * jnp.exp(-(jnp.maximum(t, ramp_time) - ramp_time) / tau)
        force = force + jnp.where(t <= ramp_time, q_ramp, q_hold)
    return force / (jnp.pi * radius**2 * (1.0 + x_end * xt))


def static_compression(x, mesh, n=None, alpha=0.2, **kw):
    """``fem.spheroid.compress`` statically to x = delta / (2 a0) (a0 = 500 um, C = 200 Pa, no branches) on ``mesh``
    in ``n`` steps (None: the default)."""
    from tissuemech.fem.spheroid import compress

    a0 = 500e-6
    return compress(radius=a0, C=200.0, alpha=alpha, branches=(), displacement=2 * a0 * x, ramp_time=1.0,
                    end_time=1.0, mesh=mesh, static=True, n_static=n, **kw)  # fmt: skip
