"""``python -m tissuemech.compare.bench scan-kernel``: relaxation curves for scans against the arithmetic limit
(issue 40, item 2).

Side by side in one run, ``--curves`` curves (default 1e5) x 200 output times (``compare.scan.default_times``:
a 0.2 s ramp and a hold to 1500 s), random parameters (C 100-400 Pa, beta 0.1-2, tau 1-1000 s, approach 5-30 % of
the diameter, a0 = 500 um), Hertz law, plate force:

* the scan layer's kernel: ``reduced.spheroid.force`` (method ``Quadrature()``), ``jax.vmap``-ed and jitted over
  chunks of ``compare.scan.CHUNK`` curves, on a CPU in blocks of ``compare.scan.BLOCK`` inside a chunk
  (``compare.scan.vmap_in_blocks``: what ``compare.scan.spheroid`` runs), after a warm-up;
* a hand-written vectorised NumPy evaluation of the same closed form: F_eq(t) + beta k tau^1.5 (sqrt(X) - D(sqrt(X)))
  e^{-(t - t_e)/tau} with X = t_e / tau, t_e = min(t, t_r), D Dawson's integral (``scipy.special.dawsn``), the
  same chunks.

Prints curves/s of each, the ratio, the largest relative difference between the two, and the peak memory growth
per chunk (flat in the number of curves: both run chunk by chunk).
"""

from __future__ import annotations

import argparse
import os
import sys
import time
from collections.abc import Sequence

import numpy as np

__all__ = ["closed_form", "main"]

A0, TR, END = 500e-6, 0.2, 1500.0


def closed_form(t: np.ndarray, C: np.ndarray, beta: np.ndarray, tau: np.ndarray, X_app: np.ndarray) -> np.ndarray:
    """Plate force (N), curves x times, of the Hertz-law lumped model (one branch), ramp-and-hold, in NumPy: the ramp
    integral at the ramp's output times and once at its end, exponentials in the hold."""
    from scipy.special import dawsn

    def ramp_integral(te: np.ndarray, tau_: np.ndarray) -> np.ndarray:  # int_0^te e^{-(te-s)/tau} sqrt(s) ds
        X = te / tau_
        sx = np.sqrt(X)
        # small X: sqrt(X) - D(sqrt(X)) = (2/3) X^1.5 - (4/15) X^2.5 + ..., summed without cancellation
        series = sx * X * (2.0 / 3.0 - X * (4.0 / 15.0 - X * (8.0 / 105.0 - X * 16.0 / 945.0)))
        return tau_**1.5 * np.where(X < 1e-2, series, sx - dawsn(sx))

    ramp = t <= TR
    scale = C * A0**2
    k = (scale * 16.0 * np.sqrt(X_app / TR) * X_app / TR)[:, None]  # dF_eq/ds = k sqrt(s)
    tau_ = tau[:, None]
    out = np.empty((C.size, t.size))
    tr_ = t[ramp][None, :]
    out[:, ramp] = scale[:, None] * (32.0 / 3.0) * (X_app[:, None] * tr_ / TR) ** 1.5
    out[:, ramp] += beta[:, None] * k * ramp_integral(tr_, tau_)
    q_end = beta[:, None] * k * ramp_integral(np.full((1, 1), TR), tau_)  # (n, 1)
    f_end = (scale * (32.0 / 3.0) * X_app**1.5)[:, None]
    out[:, ~ramp] = f_end + q_end * np.exp(-(t[~ramp][None, :] - TR) / tau_)
    return out


def main(argv: Sequence[str] | None = None) -> int:
    import jax
    import jax.numpy as jnp

    from tissuemech.compare.bench.common import machine_line
    from tissuemech.compare.scan import CHUNK, default_times, vmap_in_blocks
    from tissuemech.reduced import spheroid

    ap = argparse.ArgumentParser(
        prog="python -m tissuemech.compare.bench scan-kernel", description=__doc__.split("\n")[0]
    )
    ap.add_argument("--curves", type=float, default=1e5, help="curves (default 1e5)")
    ap.add_argument("--quick", action="store_true", help="1e4 curves")
    ap.add_argument(
        "--chunk", type=int, default=None,
        help=f"curves per compiled call (default {CHUNK} on a CPU, the scan layer's; 2**18 on a GPU)",
    )  # fmt: skip
    ap.add_argument(
        "--reference-curves", type=float, default=1e6,
        help="curves of the NumPy closed form (and, on a GPU, of the same kernel on this machine's CPU): the first "
        "ones of the same draw, timed alone, their rate compared (default 1e6, or all curves if fewer)",
    )  # fmt: skip
    a = ap.parse_args(list(argv or []))
    n = int(1e4 if a.quick else a.curves)
    backend = jax.default_backend()
    chunk = a.chunk or (CHUNK if backend == "cpu" else 2**18)
    n_ref = min(n, int(a.reference_curves))
    print(machine_line())
    print(f"JAX {jax.__version__}, backend {backend}: {', '.join(str(d.device_kind) for d in jax.devices())}")
    t = np.asarray(default_times(TR, END))
    rng = np.random.default_rng(0)
    C = rng.uniform(100, 400, n)
    beta = rng.uniform(0.1, 2.0, n)
    tau = np.exp(rng.uniform(np.log(1.0), np.log(1000.0), n))
    X_app = rng.uniform(0.05, 0.3, n)

    def kernel(C, beta, tau, X):
        one = lambda c, b, ta, x: spheroid.force(
            jnp.asarray(t), radius=A0, C=c, alpha=0.2, branches=[(b, ta)], displacement=2 * A0 * x, ramp_time=TR,
            equilibrium="hertz",
        )  # fmt: skip
        return vmap_in_blocks(lambda a: one(*a), (C, beta, tau, X))  # as the scan layer

    def run(fn, m: int, size: int, device=None, to_host: bool = True) -> tuple[float, float, np.ndarray]:
        """Curves 0..m in chunks of ``size`` (the last one padded: one compiled shape), each chunk's forces
        brought back to the host (what a scan keeps) unless ``to_host`` is False (then only the reference curves'
        chunks are); returns (seconds, 0, the first n_ref curves' forces). Memory stays flat: only the reference
        curves are kept."""
        kept = []
        t0 = time.perf_counter()
        for i in range(0, m, size):
            s = slice(i, min(i + size, m))
            args = (C[s], beta[s], tau[s], X_app[s])
            pad = size - (s.stop - s.start)
            if pad and device is not None:
                args = tuple(np.concatenate([v, np.repeat(v[-1:], pad)]) for v in args)
            if device is not None:
                args = tuple(jax.device_put(v, device) for v in args)
            res = jax.block_until_ready(fn(*args))
            if not to_host and s.start >= n_ref:
                continue
            out = np.asarray(res)[: s.stop - s.start]
            if s.start < n_ref:
                kept.append(out[: max(0, min(s.stop, n_ref) - s.start)])
        return time.perf_counter() - t0, 0.0, np.concatenate(kept)

    dev = jax.devices()[0]
    chunk_jax = jax.jit(kernel)
    jax.block_until_ready(chunk_jax(*(jax.device_put(v[:1].repeat(chunk), dev) for v in (C, beta, tau, X_app))))
    w_jax, _, F_jax = run(chunk_jax, n, chunk, dev)
    w_np, _, F_np = run(lambda C, beta, tau, X: closed_form(t, C, beta, tau, X), n_ref, CHUNK)
    diff = float(np.max(np.abs(F_jax[:, 1:] / F_np[:, 1:] - 1.0)))
    r_jax, r_np = n / w_jax, n_ref / w_np
    print(f"{n} curves x {t.size} times, chunks of {chunk} ({backend}), Hertz law, one branch; forces to the host")
    print(
        f"scan kernel (jit(vmap(spheroid.force)) in blocks, quadrature, {backend}): {w_jax:.3f} s, {r_jax:.3g} curves/s"
    )
    print(f"NumPy closed form (Dawson's integral), {n_ref} curves, one core: {w_np:.3f} s, {r_np:.3g} curves/s")
    print(
        f"ratio scan kernel / NumPy (time per curve): {r_np / r_jax:.3g}x (target <= 3x); "
        f"largest |F_jax / F_numpy - 1| = {diff:.2e} (first {n_ref} curves)"
    )
    if backend != "cpu":  # the kernel alone, its forces left on the device but the reference curves'
        w_dev, _, _ = run(chunk_jax, n, chunk, dev, to_host=False)
        print(
            f"scan kernel, forces left on the {backend} (only the first {n_ref} curves' brought back): "
            f"{w_dev:.3f} s, {n / w_dev:.3g} curves/s ({w_jax / w_dev:.2f}x the rate with every force to the host)"
        )
    if backend != "cpu":  # the same kernel on this machine's CPU: the GPU's speed-up over it
        cpu = jax.devices("cpu")[0]
        chunk_cpu = jax.jit(kernel)  # runs where its inputs are committed (run puts them on the CPU)
        with jax.default_device(cpu):
            jax.block_until_ready(chunk_cpu(*(jax.device_put(v[:CHUNK], cpu) for v in (C, beta, tau, X_app))))
            w_cpu, _, F_cpu = run(chunk_cpu, n_ref, CHUNK, cpu)
        r_cpu = n_ref / w_cpu
        d_cpu = float(np.max(np.abs(F_jax[:, 1:] / F_cpu[:, 1:] - 1.0)))
        print(
            f"same kernel on this machine's CPU ({os.cpu_count()} cores, chunks of {CHUNK}), {n_ref} curves: "
            f"{w_cpu:.3f} s, {r_cpu:.3g} curves/s; {backend} / CPU = {r_jax / r_cpu:.3g}x; "
            f"largest |F_{backend} / F_cpu - 1| = {d_cpu:.2e}"
        )
    return 0


if __name__ == "__main__":
    raise SystemExit(main(sys.argv[1:]))
