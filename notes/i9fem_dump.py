"""Before/after check of the fem refactor (issue 9, branch i9fem): dump every number of six FE runs.

    python notes/i9fem_dump.py dump OUT.npz          # on one commit (about 7 s)
    python notes/i9fem_dump.py compare A.npz B.npz   # arrays that differ, with their max relative change

Runs: inflate (load, default mesh, 3 pressures; arc-length to a/A = 2, coarse, neo-Hookean), creep (two
branches, coarse), compress (static fitted coarse to 20 %, relaxation fitted coarse, a ball_section mesh).
Every result array and every stored field is dumped; wall times are left out.
"""

import sys

import numpy as np


def _runs():
    from tissuemech.fem.blastula import creep, inflate
    from tissuemech.fem.mesh import ball_section
    from tissuemech.fem.spheroid import compress

    A, B, C, a0 = 50e-6, 75e-6, 200.0, 500e-6
    shell = dict(inner_radius=A, outer_radius=B, C=C)
    ball = dict(radius=a0, C=150.0, alpha=0.2)
    return {
        "load": lambda: inflate(**shell, alpha=0.2, pressures=[200.0, 500.0, 1000.0], store_fields=True),
        "arc": lambda: inflate(
            **shell,
            alpha=0.0,
            pressures=None,
            method="arclength",
            max_inner_stretch=2.0,
            mesh="coarse",
            store_fields=True,
        ),
        "creep": lambda: creep(
            **shell,
            alpha=0.2,
            branches=[(0.5, 1.0), (0.3, 10.0)],
            pressure=150.0,
            ramp_time=1.0,
            end_time=30.0,
            mesh="coarse",
            n_hold=10,
            times=[5.0],
            store_fields=True,
        ),
        "static": lambda: compress(
            **ball, displacement=0.2 * a0, ramp_time=1.0, end_time=1.0, static=True, mesh="coarse", field_times="all"
        ),
        "relax": lambda: compress(
            **ball,
            branches=[(0.4, 200.0)],
            displacement=0.1 * a0,
            ramp_time=0.2,
            end_time=100.0,
            mesh="coarse",
            field_times="all",
            n_hold=8,
        ),
        "axi": lambda: compress(
            **ball,
            branches=[(0.4, 2.0)],
            displacement=0.06 * a0,
            ramp_time=0.2,
            end_time=5.0,
            mesh=ball_section(a0, 4, 3),
            field_times=[1.0],
            n_hold=5,
        ),
    }


def dump(path: str) -> None:
    out = {}
    for name, run in _runs().items():
        r = run()
        for k, v in vars(r).items():
            if k in ("wall_time", "mesh", "parameters", "method", "static") or v is None:
                continue
            if k == "fields":
                for i, fld in enumerate(v or []):
                    out.update(
                        {f"{name}.fields{i}.{kk}": np.asarray(vv) for kk, vv in vars(fld).items() if vv is not None}
                    )
            else:
                out[f"{name}.{k}"] = np.asarray(v)
        print(name, "done", flush=True)
    np.savez(path, **out)


def compare(a_path: str, b_path: str) -> None:
    a, b = np.load(a_path), np.load(b_path)
    common = sorted(set(a) & set(b))
    print("only in the first:", sorted(set(a) - set(b)), "only in the second:", sorted(set(b) - set(a)))
    bad = 0
    for k in common:
        x, y = a[k], b[k]
        if x.shape != y.shape:
            print("SHAPE", k, x.shape, y.shape)
            bad += 1
        elif not np.array_equal(x, y):
            rel = np.max(np.abs(x - y) / np.maximum(np.abs(x), 1e-300)) if x.dtype.kind == "f" else "int"
            print("DIFF", k, rel)
            bad += 1
    print(f"compared {len(common)} arrays; {bad} differ")


if __name__ == "__main__":
    {"dump": dump, "compare": compare}[sys.argv[1]](*sys.argv[2:])
