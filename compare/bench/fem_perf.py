"""FE close to the machine (issue 14): per-iteration time vs the practical floor, solvers, scaling.

``python -m tissuemech.compare.bench fem-perf [--quick] [--repeats N] [--only SECTION,...]`` prints (sections
per-iteration, one-pattern, orderings, solvers, scaling; all by default), every figure measured
in the same run (interleaved repeats, medians; the machine is shared, so only the ratios mean much):

1. the load (``os.getloadavg``) and the BLAS thread setting (threadpoolctl: limited to 1 thread, the FE
   gains nothing from a second BLAS thread on these small dense blocks);
2. per Newton iteration on both default meshes (blastula 4 x 8, 50-step sweep to 1 kPa; spheroid Fig. 10
   level 1) against the practical floor = a bare sparse factorisation of the same reduced tangent with the
   best ordering among the installed factorisations (SuperLU COLAMD, SuperLU symmetric mode with MMD on
   K + K^T ordering inside the call, or on K pre-permuted by the MMD or supervariable ordering computed once
   per pattern as ``symmetric_solve`` does, qdldl if installed; the orderings are compared in section 2c)
   + the element matmuls B^T A B at the rate numpy reaches. The ratio is
   what issue 14 targets (<= 1.5); since ``newton`` keeps factorisations (for the corrections after the
   residual has converged, and across steps: Broyden steps on an earlier factorisation, ``KeptFactor``),
   far fewer iterations factor than there are iterations, so the cheap steps dilute that ratio. Printed
   too: the wall time per factorisation over the floor, and the whole run's wall time over the floor of the
   iterations it took (LU x (best LU + elem) + iterations x a bare triangular solve + residual evaluations x
   their element matmuls F = B u_e and r_e = B^T P); and, in a second table, the same runs made by textbook
   Newton (``_textbook_newton``: a new tangent, factorisation and solve per iteration), interleaved, with the
   floor of THEIR iterations: what a zero-overhead implementation of plain Newton would take on the same problem,
   the per-iteration floor the issue measured (every iteration of the code it measured factored);
2b. the blastula 4x8 sweep with the one-pattern tangent (K_int - p K_p on the element pattern, cached
   free-dof gather, lazy tangent in ``newton``) against the separate assembly it replaced, interleaved: the
   speed-up and the largest difference of the answers;
2c. the fill-reducing orderings of ``symmetric_solve`` side by side (MMD on K + K^T, MMD on the
   supervariable quotient graph, reverse Cuthill-McKee): fill, flops and factorisation time;
3. the sparse direct solvers side by side on the default and fine tangents (bare factorisation and the
   ``symmetric_solve`` path, which reuses its ordering / symbolic analysis), pypardiso if installed;
4. wall time vs dofs (blastula meshes to ~2e4 dofs, 10-step sweep; spheroid levels, static 10 % curve),
   cold (first run on a mesh) and warm (min of repeats), the exponent fitted over the fine meshes (>= 1e3
   dofs) and between neighbouring meshes (issue 14 target <= 1.2); next to them each run's floor (the
   per-iteration section's run floor, timed on a tangent of that mesh) and its exponents: how fast any code
   that factors as often must grow.

FElupe side by side is the separate suite ``felupe`` (``compare/bench/felupe_side.py``).
"""

from __future__ import annotations

import argparse
import contextlib
import time

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from tissuemech.compare.bench.common import machine_line
from tissuemech.fem import blastula as fb
from tissuemech.fem import newton as nw
from tissuemech.fem import spheroid as fs
from tissuemech.fem.forms import Material

A, B, C = 50e-6, 75e-6, 200.0
FIG10 = dict(
    radius=500e-6, C=150.0, alpha=0.2, branches=[(0.4, 200.0)], displacement=50e-6, ramp_time=0.2, end_time=1500.0
)


def _med(f, n: int) -> float:
    ts = []
    for _ in range(n):
        t = time.perf_counter()
        f()
        ts.append(time.perf_counter() - t)
    return float(np.median(ts))


def _blastula_state(mesh, lam: float = 2.5):
    """(prob, x, K_ff) of the blastula at p = lam C on ``mesh`` (a mid-sweep tangent)."""
    prob = fb._setup(A, B, C, 0.2, 2.2e9, mesh)
    x = np.zeros(prob.free.size)
    for lv in np.linspace(lam / 10, lam, 10):
        x = prob.solve(lv, x, 1e-10, "bench").x
    _, K, _ = prob.rk(x, lam)
    return prob, x, K


def _spheroid_state(level: int = 1):
    """(prob, x, K_ff, r_ff) of the spheroid at 5 % plate displacement (contact on the top nodes)."""
    r = fs.compress(**{**FIG10, "mesh": level, "end_time": 0.2, "n_ramp": 2})
    m = r.mesh
    prob = fs._Problem(m, Material(1.0, 0.2, 2.2e9 / 150.0), [0.4], [200.0], 1e-10)
    x = np.zeros(prob.asm.ndof)
    x[: prob.asm.n_u] = (r.fields[-1].displacement / 500e-6).ravel()
    rr, K = prob.asm.internal(x, prob.mat)
    act = prob.plane.gap(x, 1.0 - 0.05) < 1e-9
    fr = np.setdiff1d(prob.free, prob.plane.dofs[act])
    return prob, x, K[fr][:, fr].tocsr(), fr


def _factorisations(K):
    """Bare factorisations of K (no solve, no refinement): name -> callable. "kept": on K pre-permuted by an
    ordering computed beforehand (once per pattern, as ``symmetric_factor`` does), so the ordering's own time
    is not in the factorisation's; the SuperLU rows order inside each call."""
    Kc = sp.csc_matrix(K)
    sym = dict(permc_spec="NATURAL", diag_pivot_thresh=0.0, options=dict(SymmetricMode=True))
    kept = {}  # K pre-permuted by an ordering computed once (what ``symmetric_factor`` does per pattern)
    for name, order in (("MMD(K+K^T)", nw._mmd), ("supervariable MMD", nw._supervariable_mmd)):
        p = order(K)
        kept[name] = sp.csc_matrix(K[p][:, p])
    out = {
        "SuperLU COLAMD": lambda: spla.splu(Kc),
        "SuperLU sym MMD(K+K^T)": lambda: spla.splu(
            Kc, permc_spec="MMD_AT_PLUS_A", diag_pivot_thresh=0.0, options=dict(SymmetricMode=True)
        ),
        "SuperLU sym, MMD(K+K^T) kept": lambda: spla.splu(kept["MMD(K+K^T)"], **sym),
        "SuperLU sym, supervariable MMD kept": lambda: spla.splu(kept["supervariable MMD"], **sym),
    }
    if "qdldl" in nw.available_backends():
        import qdldl

        U = sp.triu(Kc, format="csc")
        s = qdldl.Solver(U, upper=True)
        out["qdldl LDL^T (refactor)"] = lambda: (s.update(U, upper=True), s)[1]
    return out


def _bare_solve(factorise, n: int):
    """One bare triangular solve (no refinement) with the factors ``factorise()`` returns: a callable."""
    fac = factorise()
    b = np.cos(np.arange(n, dtype=float))
    return lambda: fac.solve(b)


def _elem_flops(asm, x, mat):
    """The element matmuls B^T (w A) B of one tangent (the flop floor of the assembly)."""
    from tissuemech.fem import constitutive as cm

    ne, nq, _, nd = asm.B.shape
    f = asm.f_at(x)
    _, Aw, _ = cm.total_stress(f, mat.C, mat.alpha, q=asm.q_at(x), weight=asm.w)
    return lambda: np.matmul(asm.Bt, np.matmul(Aw, asm.B).reshape(ne, nq * 5, nd))


def _residual_flops(asm, x):
    """The element matmuls of one residual evaluation: F = B u_e at the points and r_e = B^T (w P) (the flop
    floor of a residual pass, which every iteration, Broyden steps included, makes)."""
    ne, nq = asm.w.shape
    ue = np.ascontiguousarray(x[asm.edofs][:, :, None])
    P = np.cos(np.arange(ne * nq * 5, dtype=float)).reshape(ne, 1, nq * 5)
    return lambda: (np.matmul(asm._B2, ue), np.matmul(P, asm._B2))


def per_iteration(repeats: int) -> None:
    print("\n## Per Newton iteration vs the practical floor (median of interleaved repeats)")
    print("floor = fastest bare factorisation of the same reduced tangent + element matmuls B^T A B")
    ps = np.linspace(20.0, 1000.0, 50)
    kw = dict(inner_radius=A, outer_radius=B, C=C, alpha=0.2, pressures=ps)
    prob_b, xb, Kb = _blastula_state((4, 8))
    prob_s, xs, Ks, _ = _spheroid_state(1)
    fb.inflate(**kw)  # warm-up (plans, caches)
    fs.compress(**FIG10)
    cases = {
        "blastula 4x8 sweep (50 steps)": (lambda: fb.inflate(**kw), Kb, prob_b.asm, prob_b.full(xb), prob_b.mat),
        "spheroid Fig. 10 level 1": (lambda: fs.compress(**FIG10), Ks, prob_s.asm, xs, prob_s.mat),
    }
    residual = {  # one whole residual evaluation as Newton makes it (no tangent), on the same state
        "blastula 4x8 sweep (50 steps)": lambda: prob_b.rk(xb, 2.5, tangent=False),
        "spheroid Fig. 10 level 1": lambda: prob_s.asm.internal(xs, prob_s.mat, tangent=False),
    }
    rows = {k: dict(it=[], per_lu=[], lu={}, el=[], rel=[], res=[], sol=[], run=[], textbook=[]) for k in cases}
    its, lus, nres, work = {}, {}, {}, {}
    with _textbook_newton():
        for run, *_ in cases.values():
            run()  # warm-up
    for _ in range(repeats):
        for name, (run, K, asm, x, mat) in cases.items():
            with _textbook_newton():  # the same run as textbook Newton (interleaved with the shipped one)
                wall, work[name] = _counted_run(run)
            rows[name]["textbook"].append(wall)
            wall, (its[name], lus[name], nres[name]) = _counted_run(run)
            rows[name]["it"].append(wall / its[name])
            rows[name]["per_lu"].append(wall / max(lus[name], 1))
            facs = _factorisations(K)
            for fname, fac in facs.items():
                rows[name]["lu"].setdefault(fname, []).append(_med(fac, 5))
            rows[name]["el"].append(_med(_elem_flops(asm, x, mat), 5))
            rows[name]["rel"].append(_med(_residual_flops(asm, x), 5))
            rows[name]["res"].append(_med(residual[name], 20))
            best = min(facs, key=lambda k: rows[name]["lu"][k][-1])
            rows[name]["sol"].append(_med(_bare_solve(facs[best], K.shape[0]), 5))
            rows[name]["run"].append(wall)
    print("(iters: Newton iterations, the quasi-Newton steps on a kept factorisation included; LU: factorisations;")
    print(" ratio: ms/iter over the floor of a factorised iteration (LU + elem), which the cheap steps now dilute;")
    print(" ratio/LU: wall per factorisation over that floor; run: the whole run's wall over ITS floor,")
    print(
        " LU x (best LU + elem) + iters x (bare solve) + res x (res elem): the unavoidable sparse and element work of"
    )
    print(" the iterations it took; res: residual evaluations, res elem: their element matmuls F = B u_e, r_e = B^T P,")
    print(
        " res ms: one whole residual evaluation of this code (kinematics, constitutive law, follower load, assembly))"
    )
    print(
        f"{'case':32s} {'dofs':>6s} {'iters':>5s} {'LU':>4s} {'res':>4s} {'ms/iter':>8s} {'ms/LU':>7s} "
        f"{'best LU ms':>10s} {'elem ms':>8s} {'res elem ms':>11s} {'res ms':>7s} {'solve ms':>8s} {'ratio':>6s} {'ratio/LU':>8s} "
        f"{'run':>6s}  best LU"
    )
    textbook = []
    for name, (_, K, *_r) in cases.items():
        d = rows[name]
        lu = {k: float(np.median(v)) for k, v in d["lu"].items()}
        best = min(lu, key=lu.get)
        it, el, per_lu = float(np.median(d["it"])), float(np.median(d["el"])), float(np.median(d["per_lu"]))
        sol, run, rel = float(np.median(d["sol"])), float(np.median(d["run"])), float(np.median(d["rel"]))
        res_ms = 1e3 * float(np.median(d["res"]))
        floor = lu[best] + el
        run_floor = lus[name] * floor + its[name] * sol + nres[name] * rel
        print(
            f"{name:32s} {K.shape[0]:6d} {its[name]:5d} {lus[name]:4d} {nres[name]:4d} {1e3 * it:8.2f} "
            f"{1e3 * per_lu:7.2f} {1e3 * lu[best]:10.2f} {1e3 * el:8.2f} {1e3 * rel:11.3f} {res_ms:7.3f} {1e3 * sol:8.3f} "
            f"{it / floor:6.2f} {per_lu / floor:8.2f} {run / run_floor:6.2f}  {best}"
        )
        print("    factorisations (ms): " + ", ".join(f"{k} {1e3 * v:.2f}" for k, v in lu.items()))
        t_its, t_lu, t_res = work[name]
        tb = t_lu * floor + t_its * sol + t_res * rel
        textbook.append(
            f"{name:32s} {t_its:5d} {t_lu:4d} {t_res:4d} {1e3 * tb:8.1f} {1e3 * float(np.median(d['textbook'])):11.1f} "
            f"{1e3 * run:10.1f} {float(np.median(d['textbook'])) / tb:9.2f} {run / tb:9.2f}"
        )
    print("\n## The same runs against a textbook Newton at the floor (median of the same interleaved repeats)")
    print("(textbook: newton without the kept factorisation, its Broyden steps and the correction on the previous")
    print(" factorisation: a new tangent, factorisation and solve per iteration, line search, tolerances, predictors")
    print(" and fitted meshes unchanged; its floor: its iters, LU and res priced as the run floor above, i.e. what an")
    print(" implementation of textbook Newton with zero overhead would take; shipped/floor <= 1.5 is issue 14's")
    print(" per-iteration target for iterations that each factor, as the issue measured them)")
    print(
        f"{'case':32s} {'iters':>5s} {'LU':>4s} {'res':>4s} {'floor ms':>8s} {'textbook ms':>11s} {'shipped ms':>10s} "
        f"{'tb/floor':>9s} {'shipped/floor':>9s}"
    )
    print("\n".join(textbook))
    print(f"symmetric_solve backend in use: {nw.backend()} (available: {', '.join(nw.available_backends())})")


def _rk_separate(self, uf, p, tangent=True, iso_scale: float = 1.0, extra_S=None):
    """The blastula residual/tangent as it was before issue 14's one-pattern path: internal + follower
    assembled separately, a scipy sparse sum and a fancy slice K[free][:, free], the tangent always eager."""
    u = self.full(uf)
    ri, Ki = self.asm.internal(u, self.mat, extra_S=extra_S, iso_scale=iso_scale, tangent=bool(tangent))
    fp, Kp = self.asm.follower_pressure(u, 1.0, self.inner, tangent=bool(tangent))
    r = (ri - p * fp)[self.free]
    if not tangent:
        return r, None, -fp[self.free]
    return r, (Ki - p * Kp).tocsr()[self.free][:, self.free], -fp[self.free]


def one_pattern(repeats: int) -> None:
    """Blastula 4x8 sweep: the one-pattern + lazy-tangent path vs the separate assembly, same run."""
    print("\n## Blastula 4x8 sweep: one pattern + cached free-dof gather + lazy tangent vs separate (same run)")
    ps = np.linspace(20.0, 1000.0, 50)
    kw = dict(inner_radius=A, outer_radius=B, C=C, alpha=0.2, pressures=ps)
    new_rk = fb._Problem.rk
    walls: dict = {"separate": [], "one pattern": []}
    out = {}
    for _ in range(repeats + 2):
        for name, rk in (("separate", _rk_separate), ("one pattern", new_rk)):
            fb._Problem.rk = rk  # type: ignore[method-assign]
            try:
                t = time.perf_counter()
                res = fb.inflate(**kw)
                walls[name].append(time.perf_counter() - t)
            finally:
                fb._Problem.rk = new_rk  # type: ignore[method-assign]
            out[name] = (int(np.sum(res.newton_iterations)), np.asarray(res.inner_stretch))
    w0, w1 = float(np.median(walls["separate"])), float(np.median(walls["one pattern"]))
    (i0, s0), (i1, s1) = out["separate"], out["one pattern"]
    print(
        f"separate {1e3 * w0 / i0:.2f} ms/iter, one pattern {1e3 * w1 / i1:.2f} ms/iter ({i0} / {i1} iterations): "
        f"{w0 / w1:.2f}x; max |inner stretch difference| {np.max(np.abs(s1 - s0)):.1e}"
    )


def solvers(repeats: int, quick: bool) -> None:
    print("\n## Sparse direct solvers on the reduced tangents (ms, median; solve paths include refinement)")
    mats = {"blastula 4x8": _blastula_state((4, 8))[2], "spheroid L1": _spheroid_state(1)[2]}
    if not quick:
        mats["blastula 16x32"] = _blastula_state((16, 32))[2]
    try:
        import pypardiso
    except ImportError:
        pypardiso = None
    print(
        f"{'matrix':16s} {'n':>6s} "
        + "".join(f"{h:>14s}" for h in ("COLAMD", "symMMD", "qdldl", "solve:superlu", "solve:qdldl", "pardiso"))
    )
    for name, K in mats.items():
        b = np.cos(np.arange(K.shape[0]))
        fac = _factorisations(K)
        cols = [fac["SuperLU COLAMD"], fac["SuperLU sym MMD(K+K^T)"], fac.get("qdldl LDL^T (refactor)")]
        old = nw._BACKEND[0]
        paths = []
        for be in ("superlu", "qdldl"):
            if be in nw.available_backends():
                paths.append(lambda be=be: (nw.set_backend(be), nw.symmetric_solve(K, b)))
            else:
                paths.append(None)
        if pypardiso is not None:
            ps = pypardiso.PyPardisoSolver(mtype=1)
            paths.append(lambda: ps.solve(K, b))
        else:
            paths.append(None)
        out = []
        for f in cols + paths:
            out.append(None if f is None else (f(), _med(f, repeats + 2))[1])
        nw._BACKEND[0] = old
        print(f"{name:16s} {K.shape[0]:6d} " + "".join(f"{'-' if v is None else f'{1e3 * v:.2f}':>14s}" for v in out))


def orderings(repeats: int, quick: bool) -> None:
    """Fill-reducing orderings of ``symmetric_solve`` (SuperLU symmetric mode, NATURAL on P K P^T, the
    ordering computed once per pattern): nnz(L + U), the factorisation flop count sum_j |L_j| |U_j| and the
    factorisation time (median of interleaved repeats) per ordering, on the default and fine tangents."""
    print("\n## Fill-reducing orderings (SuperLU symmetric mode on P K P^T; ms: median of interleaved repeats)")
    from scipy.sparse import csgraph

    mats = {
        "blastula 4x8": lambda: _blastula_state((4, 8))[2],
        "blastula 16x32": lambda: _blastula_state((16, 32))[2],
        "spheroid L1": lambda: _spheroid_state(1)[2],
        "spheroid L2": lambda: _spheroid_state(2)[2],
    }
    if not quick:
        mats["blastula 24x48"] = lambda: _blastula_state((24, 48))[2]
        mats["spheroid L3"] = lambda: _spheroid_state(3)[2]

    def rcm(K):
        G = sp.csr_matrix(K, copy=True)
        G.data[:] = 1.0
        return np.asarray(csgraph.reverse_cuthill_mckee((G + G.T).tocsr(), symmetric_mode=True))

    orders = {"MMD(K+K^T)": nw._mmd, "supervariable MMD": nw._supervariable_mmd, "RCM": rcm}
    print(f"{'matrix':16s} {'n':>6s}  " + "".join(f"{k:>36s}" for k in orders))
    print(f"{'':16s} {'':6s}  " + "".join(f"{'nnz(L+U)  flops  order ms  LU ms':>36s}" for _ in orders))
    for name, make in mats.items():
        K = make()
        rows, Ks = {}, {}
        for k, order in orders.items():
            t = time.perf_counter()
            p = order(K)
            to = time.perf_counter() - t
            Ks[k] = sp.csc_matrix(K[p][:, p])
            lu = spla.splu(Ks[k], permc_spec="NATURAL", diag_pivot_thresh=0.0, options=dict(SymmetricMode=True))
            fl = float(np.sum(np.diff(lu.L.indptr).astype(float) * np.bincount(lu.U.indices, minlength=K.shape[0])))
            rows[k] = [lu.L.nnz + lu.U.nnz, fl, to, []]
        for _ in range(max(repeats, 3) + 2):
            for k, Kp in Ks.items():
                t = time.perf_counter()
                spla.splu(Kp, permc_spec="NATURAL", diag_pivot_thresh=0.0, options=dict(SymmetricMode=True))
                rows[k][3].append(time.perf_counter() - t)
        cells = [f"{f:9d} {fl:8.2e} {1e3 * to:7.1f} {1e3 * np.median(ts):7.2f}" for f, fl, to, ts in rows.values()]
        print(f"{name:16s} {K.shape[0]:6d}  " + "".join(f"{c:>36s}" for c in cells))
    print("blastula solves with the supervariable ordering, the spheroid with MMD(K+K^T) (fewer flops on each)")


def _counted_run(run) -> tuple[float, tuple[int, int, int]]:
    """(wall s, (Newton iterations, SuperLU factorisations, residual evaluations)) of one run."""
    with _count_lu() as count, _count_residuals() as count_r:
        t = time.perf_counter()
        res = run()
        wall = time.perf_counter() - t
    return wall, (int(np.sum(res.newton_iterations)), count.n, count_r.n)


def _slope(d, t) -> float:
    return float(np.polyfit(np.log(d), np.log(t), 1)[0])


class _Count:
    """Counts the calls of ``module.name`` while active (the attribute is wrapped, then restored)."""

    def __init__(self, module, name: str):
        self._module, self._name, self.n = module, name, 0

    def __enter__(self):
        self._orig = getattr(self._module, self._name)

        def counted(*a, **k):
            self.n += 1
            return self._orig(*a, **k)

        setattr(self._module, self._name, counted)
        return self

    def __exit__(self, *exc):
        setattr(self._module, self._name, self._orig)


def _count_lu() -> _Count:
    """Counts the SuperLU factorisations (``scipy.sparse.linalg.splu`` calls) while active: the reported
    iterations leave out the passes of failed attempts (cut steps, the spheroid's contact-edge search)."""
    return _Count(spla, "splu")


def _count_residuals() -> _Count:
    """Counts the residual evaluations (``Assembler._residual``, the B^T P pass of ``internal`` and
    ``internal_follower``) while active; the output fields' stress passes are not residuals."""
    from tissuemech.fem.forms import Assembler

    return _Count(Assembler, "_residual")


@contextlib.contextmanager
def _textbook_newton():
    """Textbook Newton inside (one new tangent, factorisation and solve per iteration): ``newton`` without the
    factorisation kept across steps, its Broyden steps or the correction with the previous factorisation once
    the residual has converged; line search, tolerances, predictors and fitted meshes unchanged (the FE
    modules' ``newton`` and ``newton._chord_step`` are replaced while active, then restored)."""
    from tissuemech.fem import contact

    orig, chord = nw.newton, nw._chord_step

    def textbook(fun, x0, **kw):
        return orig(fun, x0, **{**kw, "keep": None})

    mods = [m for m in (fb, fs, contact) if getattr(m, "newton", None) is orig]
    for m in mods:
        m.newton = textbook
    nw._chord_step = lambda *a, **k: None
    try:
        yield
    finally:
        for m in mods:
            m.newton = orig
        nw._chord_step = chord


def _exponents(label: str, d, cold, warm, floor=None) -> None:
    """Print the fitted wall ~ dofs^k (least squares over all points) and the local exponents between
    neighbouring meshes, for the cold (first) and warm (min of repeats) runs and (given) their floors."""
    d = np.asarray(d, dtype=float)
    series = [("cold", cold), ("warm", warm)] + ([] if floor is None else [("floor", floor)])
    for name, t in series:
        t = np.asarray(t, dtype=float)
        local = np.diff(np.log(t)) / np.diff(np.log(d))
        what = "the floor" if name == "floor" else "wall"
        print(
            f"{label} exponent ({name}, {d.size} meshes, {d.min():.0f}-{d.max():.0f} dofs): {what} ~ dofs^"
            f"{_slope(d, t):.2f}; between neighbours: " + ", ".join(f"{v:.2f}" for v in local)
        )


def _run_floor(state, lu: int, iters: int, res: int) -> tuple[float, str]:
    """(seconds, best factorisation) of the floor of a run that took ``lu`` factorisations, ``iters``
    iterations and ``res`` residual evaluations on the mesh of ``state`` = (K, asm, x, mat): LU x (best bare
    LU + tangent element matmuls) + iters x (bare solve) + res x (residual element matmuls), each timed here
    (median of 3); the per-iteration section's run floor on any mesh."""
    K, asm, x, mat = state
    facs = _factorisations(K)
    t = {k: _med(f, 3) for k, f in facs.items()}
    best = min(t, key=t.get)
    el, rel = _med(_elem_flops(asm, x, mat), 3), _med(_residual_flops(asm, x), 3)
    sol = _med(_bare_solve(facs[best], K.shape[0]), 3)
    return lu * (t[best] + el) + iters * sol + res * rel, best


def scaling(quick: bool, repeats: int = 2) -> None:
    """Wall time against dofs. Each mesh runs once cold (its setup, sparsity pattern and solver plan are new)
    and then ``repeats`` times warm (min taken: the box is shared, the min is the least disturbed run); the
    exponent is fitted over all fine meshes (>= 1e3 dofs) and given between neighbours too (a two-point fit on
    a noisy machine moved by +-0.3 between runs: issue 14's third pass). Next to it the same exponents of each
    run's floor (``_run_floor``: the bare factorisations, solves and element matmuls of the iterations the run
    took, timed on a tangent of that mesh): how fast any code that factors as often must grow."""
    print("\n## Wall time vs dofs (blastula: 10 equal steps to 1 kPa; spheroid: static curve to 10 %, 5 steps)")
    print("(iterations: those of the accepted states; LU: every SuperLU factorisation, failed attempts included;")
    print(
        f" res: residual evaluations; cold: the first run on the mesh; warm: min of {repeats} more (spheroid level 4: one);"
    )
    print(" floor: LU x (best bare LU + element matmuls) + iterations x bare solve + res x residual element matmuls,")
    print(" timed on a tangent of the same mesh; warm/floor: how far above it the run is)")
    meshes = [(4, 8), (8, 16), (16, 32), (24, 48)] + ([] if quick else [(32, 64)])
    ps = np.linspace(100.0, 1000.0, 10)
    d, cold, warm, floor = [], [], [], []

    def row(label: str, n: int, w: float, ws: list, its: int, lu: int, res: int, state) -> None:
        fl, best = _run_floor(state, lu, its, res)
        d.append(n)
        cold.append(w)
        warm.append(min(ws))
        floor.append(fl)
        print(
            f"{label:25s} dofs {n:6d}  cold {w:8.3f} s  warm {min(ws):8.3f} s  {its:4d} iterations  {lu:3d} LU  "
            f"{res:4d} res  floor {fl:7.3f} s  warm/floor {min(ws) / fl:5.2f}  ({best})"
        )

    for m in meshes:
        kw = dict(inner_radius=A, outer_radius=B, C=C, alpha=0.2, pressures=ps, mesh=m)
        with _count_lu() as lu, _count_residuals() as nres:
            t0 = time.perf_counter()
            r = fb.inflate(**kw)
            w = time.perf_counter() - t0
        ws = []
        for _ in range(repeats):
            t0 = time.perf_counter()
            fb.inflate(**kw)
            ws.append(time.perf_counter() - t0)
        prob, x, K = _blastula_state(m)
        state = (K, prob.asm, prob.full(x), prob.mat)
        row(f"blastula {m}", prob.free.size, w, ws, int(r.newton_iterations.sum()), lu.n, nres.n, state)
    k = np.array(d) >= 1000
    if k.sum() >= 2:
        _exponents("blastula", np.array(d)[k], np.array(cold)[k], np.array(warm)[k], np.array(floor)[k])
    d, cold, warm, floor = [], [], [], []
    for lev in [1, 2, 3] + ([] if quick else [4]):
        kw = {**FIG10, "mesh": lev, "static": True, "displacement": 100e-6, "n_static": 5}
        with _count_lu() as lu, _count_residuals() as nres:
            t0 = time.perf_counter()
            r = fs.compress(**kw)
            w = time.perf_counter() - t0
        ws = []
        for _ in range(repeats if lev < 4 else 1):  # level 4 (~8 s a run) once
            t0 = time.perf_counter()
            fs.compress(**kw)
            ws.append(time.perf_counter() - t0)
        n = 2 * r.mesh.basis.N + 3 * r.mesh.mesh.nelements
        prob, x, K, _ = _spheroid_state(lev)
        state = (K, prob.asm, x, prob.mat)
        row(f"spheroid level {lev}", n, w, ws, int(r.newton_iterations.sum()), lu.n, nres.n, state)
    _exponents("spheroid", d, cold, warm, floor)
    if len(d) > 3:  # level 4 (4e4 dofs) is past the range (to 2e4 dofs): the fit without it as well
        _exponents("spheroid levels 1-3", d[:3], cold[:3], warm[:3], floor[:3])


SECTIONS = ("per-iteration", "one-pattern", "orderings", "solvers", "scaling")


def main(argv: list[str] | None = None) -> None:
    ap = argparse.ArgumentParser(prog="python -m tissuemech.compare.bench fem-perf")
    ap.add_argument("--quick", action="store_true", help="fewer repeats, no finest meshes")
    ap.add_argument("--repeats", type=int, default=None, help="interleaved repeats (default 3, quick 1)")
    ap.add_argument(
        "--only",
        default="",
        help=f"comma-separated sections to run (default all): {', '.join(SECTIONS)}",
    )
    a = ap.parse_args(argv)
    only = [x for x in a.only.split(",") if x]
    bad = [x for x in only if x not in SECTIONS]
    if bad:
        ap.error(f"unknown section(s) {bad}; choose from {', '.join(SECTIONS)}")
    run = set(only or SECTIONS)
    repeats = a.repeats or (1 if a.quick else 3)
    print("# fem-perf (issue 14)")
    print(machine_line())
    try:
        from threadpoolctl import threadpool_limits

        limiter = threadpool_limits(limits=1, user_api="blas")
        print("BLAS threads: limited to 1 (threadpoolctl)")
    except ImportError:
        limiter = None
        print("BLAS threads: threadpoolctl not installed; set OMP_NUM_THREADS=1 OPENBLAS_NUM_THREADS=1 yourself")
    try:
        if "per-iteration" in run:
            per_iteration(repeats)
        if "one-pattern" in run:
            one_pattern(repeats)
        if "orderings" in run:
            orderings(repeats, a.quick)
        if "solvers" in run:
            solvers(repeats, a.quick)
        if "scaling" in run:
            scaling(a.quick, max(repeats, 2))
    finally:
        if limiter is not None:
            limiter.restore_original_limits()
    print(
        "\nFElupe side by side: python -m tissuemech.compare.bench felupe [--quick] (needs pip install felupe; "
        "same-run ratios at the same or better error)"
    )


if __name__ == "__main__":
    main()
