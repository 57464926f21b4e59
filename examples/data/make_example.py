"""Regenerate the SYNTHETIC example records of this folder (not measurements).

    python examples/data/make_example.py

Reduced model (``tissuemech.reduced.spheroid.nominal_stress``, FE-calibrated master table shipped
with the package), ball radius 500 um, 0.2 s ramp then hold to 1500 s, C = 150 Pa, alpha = 0.2,
beta = 0.4, tau = 200 s, two levels (total approach 50 and 200 um), white Gaussian noise of sd 1 %
of each record's peak stress (seed 2024).
"""

from pathlib import Path

import numpy as np

from tissuemech.reduced import spheroid

TRUTH = dict(C=150.0, alpha=0.2, beta=0.4, tau=200.0)
RADIUS, RAMP, NOISE, SEED = 500e-6, 0.2, 0.01, 2024
TIMES = np.concatenate([np.linspace(0.0, RAMP, 11)[1:], np.geomspace(0.3, 1500.0, 60)])


def main() -> None:
    rng = np.random.default_rng(SEED)
    here = Path(__file__).resolve().parent
    for um in (50, 200):
        y = np.asarray(
            spheroid.nominal_stress(
                TIMES,
                radius=RADIUS,
                C=TRUTH["C"],
                alpha=TRUTH["alpha"],
                branches=[(TRUTH["beta"], TRUTH["tau"])],
                displacement=um * 1e-6,
                ramp_time=RAMP,
            )
        )
        y = y + NOISE * y.max() * rng.standard_normal(y.shape)
        head = (
            "# SYNTHETIC example record (not a measurement), made by examples/data/make_example.py:\n"
            "# tissuemech reduced model, FE master table; radius 500 um, ramp 0.2 s, held to 1500 s;\n"
            "# C = 150 Pa, alpha = 0.2, beta = 0.4, tau = 200 s; noise sd 1 % of the peak stress.\n"
            f"# displacement_um: {um}\n"
            "time_s,stress_Pa\n"
        )
        body = "".join(f"{t:.6g},{s:.6g}\n" for t, s in zip(TIMES, y))
        (here / f"spheroid_{um}um.csv").write_text(head + body)


if __name__ == "__main__":
    main()
