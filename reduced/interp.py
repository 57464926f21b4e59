r"""Smooth, differentiable interpolation of tabulated curves (JAX): natural cubic splines as weights.

A natural cubic spline through values y_i at knots k_i is *linear* in the values: s(x) = w(x) . y.
``spline_weights(knots, x)`` returns that weight vector (C^2 in x, so dF/dx exists everywhere and
jax.grad / jax.jvp work), which makes 1-D and tensor-product 2-D tables one matrix product:

    s(x)        = w(x) . y                      (``Spline1D``)
    s(x, alpha) = w_alpha(alpha) . Y . w_x(x)   (``Spline2D``, Y of shape (n_alpha, n_x))

Beyond the end knots the spline continues linearly (natural end conditions); callers decide
whether that is allowed (``reduced.spheroid`` refuses points outside its calibrated range in eager
calls).
"""

from __future__ import annotations

from typing import Any

import jax
import jax.numpy as jnp
import numpy as np

__all__ = ["second_derivative_map", "spline_weights", "spline_eval", "Spline1D", "Spline2D"]


def _interval(k: jnp.ndarray, x: jnp.ndarray) -> jnp.ndarray:
    """Index i of the knot interval [k_i, k_i+1] holding x (clamped to the end intervals). A count of
    comparisons, not a binary search: for the few dozen knots of a table it is faster, and it stays
    cheap when vmapped over batches of different x (a batched searchsorted is not)."""
    return jnp.sum(x[..., None] >= k[1:-1], axis=-1)


def second_derivative_map(knots: np.ndarray, ends: str = "natural") -> np.ndarray:
    """Matrix L (n, n) with M = L y the knot second derivatives of the cubic spline through y.

    ``ends``: "natural" (M = 0 at both ends) or "extrapolated" (M linear over the two end intervals: no
    spurious flattening where the curve still bends at the ends; needs >= 4 knots, else natural)."""
    if ends not in ("natural", "extrapolated"):
        raise ValueError(f"spline ends must be 'natural' or 'extrapolated', got {ends!r}")
    k = np.asarray(knots, dtype=float)
    n = k.size
    if n < 2 or np.any(np.diff(k) <= 0):
        raise ValueError("spline knots must be at least 2 strictly increasing numbers")
    if n == 2:
        return np.zeros((2, 2))
    h = np.diff(k)
    A = np.zeros((n, n))
    B = np.zeros((n, n))
    A[0, 0] = A[-1, -1] = 1.0
    if ends == "extrapolated" and n >= 4:  # M_0 = M_1 + (M_1 - M_2) h_0 / h_1, likewise at the far end
        A[0, 1], A[0, 2] = -(1 + h[0] / h[1]), h[0] / h[1]
        A[-1, -2], A[-1, -3] = -(1 + h[-1] / h[-2]), h[-1] / h[-2]
    for i in range(1, n - 1):
        A[i, i - 1], A[i, i], A[i, i + 1] = h[i - 1] / 6, (h[i - 1] + h[i]) / 3, h[i] / 6
        B[i, i - 1], B[i, i], B[i, i + 1] = 1 / h[i - 1], -1 / h[i - 1] - 1 / h[i], 1 / h[i]
    return np.linalg.solve(A, B)


def spline_weights(knots: np.ndarray, L: np.ndarray, x: Any) -> jnp.ndarray:
    """Weights w(x) (..., n) of the natural cubic spline: s(x) = w(x) @ y (``L`` from
    :func:`second_derivative_map`): the spline of the unit vectors, whose second derivatives are L."""
    n = np.shape(knots)[0]
    return spline_eval(knots, jnp.eye(n), jnp.asarray(L), x)


def spline_eval(knots: np.ndarray, y: Any, M: Any, x: Any) -> jnp.ndarray:
    """Natural cubic spline through ``y`` (n, ...) with knot second derivatives ``M`` (= L y), at ``x``:
    four gathered values per point (cheap inside ODE right-hand sides); linear beyond the ends.
    Result shape: x.shape + y.shape[1:]."""
    k = jnp.asarray(knots)
    x = jnp.asarray(x, dtype=jnp.float64)
    y, M = jnp.asarray(y), jnp.asarray(M)
    i = _interval(k, x)
    x0, x1 = k[i], k[i + 1]
    h = x1 - x0
    xc = jnp.clip(x, k[0], k[-1])
    e = lambda v: v.reshape(v.shape + (1,) * (y.ndim - 1))
    a, b, h = e((x1 - xc) / h), e((xc - x0) / h), e(h)
    y0, y1, M0, M1 = y[i], y[i + 1], M[i], M[i + 1]
    s = a * y0 + b * y1 + ((a**3 - a) * M0 + (b**3 - b) * M1) * h**2 / 6
    slope = (y1 - y0) / h + (-(3 * a**2 - 1) * M0 + (3 * b**2 - 1) * M1) * h / 6
    return s + slope * e(x - xc)  # linear continuation outside [k_0, k_-1] (slope of the end segment there)


class Spline1D:
    """s(x) through (knots, values), natural cubic; callable on JAX arrays (jit/vmap/grad)."""

    def __init__(self, knots: np.ndarray, values: np.ndarray, ends: str = "natural"):
        self.knots = np.asarray(knots, dtype=float)
        self.values = np.asarray(values, dtype=float)
        if self.values.shape != self.knots.shape:
            raise ValueError(f"table: {self.knots.size} knots but values of shape {self.values.shape}")
        if not np.all(np.isfinite(self.values)):
            raise ValueError("table values must be finite numbers")
        self.L = second_derivative_map(self.knots, ends)
        self.M = self.L @ self.values

    def __call__(self, x: Any) -> jnp.ndarray:
        return spline_eval(self.knots, jnp.asarray(self.values), jnp.asarray(self.M), x)


class Spline2D:
    """s(x, alpha) on a tensor grid: values (n_alpha, n_x); natural cubic in each direction."""

    def __init__(self, x_knots: np.ndarray, alpha_knots: np.ndarray, values: np.ndarray, ends: str = "natural"):
        self.x = np.asarray(x_knots, dtype=float)
        self.alpha = np.asarray(alpha_knots, dtype=float)
        self.values = np.asarray(values, dtype=float)
        if self.values.shape != (self.alpha.size, self.x.size):
            raise ValueError(
                f"table values need shape (n_alpha, n_x) = ({self.alpha.size}, {self.x.size}); got {self.values.shape}"
            )
        self.Lx = second_derivative_map(self.x, ends)
        self.Mx = self.values @ self.Lx.T  # knot second derivatives in x of every alpha row
        self.La = second_derivative_map(self.alpha, ends) if self.alpha.size > 1 else None

    def at(self, alpha: Any) -> tuple[jnp.ndarray, jnp.ndarray]:
        """(values, x-second-derivatives) of the 1-D spline in x at this alpha (a spline in alpha of
        the rows: linear in the rows, so the x-spline of the interpolated row is exact)."""
        if self.La is None:
            return jnp.asarray(self.values[0]), jnp.asarray(self.Mx[0])
        wa = spline_weights(self.alpha, self.La, alpha)  # (n_alpha,)
        return wa @ jnp.asarray(self.values), wa @ jnp.asarray(self.Mx)

    def curve(self, alpha: Any):
        """x -> s(x, alpha) for one (possibly traced) alpha, with the alpha work done once."""
        y, M = self.at(alpha)
        return lambda x: spline_eval(self.x, y, M, x)

    def __call__(self, x: Any, alpha: Any) -> jnp.ndarray:
        x = jnp.asarray(x, dtype=jnp.float64)
        alpha = jnp.asarray(alpha, dtype=jnp.float64)
        shape = jnp.broadcast_shapes(x.shape, alpha.shape)
        xs, als = jnp.broadcast_to(x, shape).reshape(-1), jnp.broadcast_to(alpha, shape).reshape(-1)
        return jax.vmap(lambda xi, ai: self.curve(ai)(xi))(xs, als).reshape(shape)
