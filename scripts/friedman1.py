"""Friedman #1, the standard multi-input regression benchmark of the SVR literature, as a CSV for `palpus bench svr-scale --data`.

    python3 scripts/friedman1.py --inputs 5 --rows 30000 --out out/friedman1_5.csv
    python3 scripts/friedman1.py --inputs 10 --rows 30000 --out out/friedman1_10.csv

Inputs x1 … xp independent and uniform on [0, 1] (p = 5, or 10 with five that do not matter);
target y = 10 sin(π x1 x2) + 20 (x3 − 0.5)² + 10 x4 + 5 x5 + e, e ~ N(0, σ²), σ = 1 (Friedman,
Ann. Statist. 19(1), 1991; as in Drucker et al., NIPS 1997, and scikit-learn's
make_friedman1). Seeded, so one seed gives the same rows on every machine with this numpy.
"""

import argparse
from pathlib import Path

import numpy as np


def main():
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--inputs", type=int, default=5, help="p ≥ 5")
    p.add_argument("--rows", type=int, default=30000)
    p.add_argument("--noise", type=float, default=1.0, help="σ of the noise")
    p.add_argument("--seed", type=int, default=1)
    p.add_argument("--out", required=True)
    a = p.parse_args()
    if a.inputs < 5:
        raise SystemExit("--inputs: Friedman #1 needs at least 5")
    rng = np.random.default_rng(a.seed)
    x = rng.uniform(size=(a.rows, a.inputs))
    y = (10 * np.sin(np.pi * x[:, 0] * x[:, 1]) + 20 * (x[:, 2] - 0.5) ** 2 + 10 * x[:, 3] + 5 * x[:, 4]
         + a.noise * rng.standard_normal(a.rows))
    Path(a.out).parent.mkdir(parents=True, exist_ok=True)
    header = ",".join([f"x{k}" for k in range(a.inputs)] + ["y"])
    np.savetxt(a.out, np.column_stack([x, y]), delimiter=",", header=header, comments="", fmt="%.17g")


if __name__ == "__main__":
    main()
