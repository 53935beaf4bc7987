#!/usr/bin/env python3
"""The needle's ε-SVR fit against scikit-learn's libsvm at growing n, on the same samples.

Run from the repository root after `cargo build --release --locked` (needs numpy and
scikit-learn; the project's tests do not):

    python3 scripts/bench_svr_scale.py                       # n = 350 … 30000
    python3 scripts/bench_svr_scale.py --sizes 100000 --libsvm-max 30000
    python3 scripts/bench_svr_scale.py --threads 1 --capture assets/captures/li_bi/needle_train.csv \
        --sizes 350,500,1000 --csv out/svr_scale_li_bi.csv

`--capture` sweeps another insertion capture instead of the generated one, `--data` a regression
table (`scripts/friedman1.py`) with `--c`, `--gamma` and `--epsilon`; `--threads 1` runs
our solvers on one thread, as libsvm runs; `--csv` also writes the table's rows as CSV.

It writes a needle capture logged at 1 kHz with the speeds inserted twice
(`palpus gen --seed 7 --needle-rate-hz 1000 --needle-rounds 2`, ~150 000 samples in tissue), then
for each n runs `palpus bench svr-scale` in its own process (so its peak memory is that fit's),
which picks n in-tissue samples spread evenly, scales them to the unit box as identification
does, fits with the needle's defaults (C = 100, γ = 30, ε = 0.02) and dumps the training set
with its predictions. scikit-learn's SVR (kernel='rbf', same C, γ, ε, tol=1e-3 — its default —,
default cache_size, one thread) fits the same dump. The table: n, our seconds, libsvm's,
libsvm / ours, our peak resident memory, support vectors (ours, libsvm's), our certified
relative duality gap, and the largest difference of the two models' predictions on the
training inputs (libsvm stops at a KKT violation of 1e-3, so a few 1e-3 N is expected).

A fit that takes under a second is timed fifteen times, on both sides in the same way: three
rounds that alternate the two sides, each round five fits in one process, and the fastest of
all kept (as Python's timeit advises). At n = 350 both take milliseconds; single-timed runs
moved the ratio between 4.0× and 7.3×, and five fits of one side in a row could all fall in one
slow spell of a virtual machine's scheduling (ours 18–30 ms for the same 10-iteration fit), so
the rounds spread each side's fits over the other's. Our memory column is always the peak of a
process that made one fit.
"""
import argparse
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

os.environ.setdefault("OMP_NUM_THREADS", "1")
import numpy as np  # noqa: E402
from sklearn.svm import SVR  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]


# Our fits' --c, --gamma, --epsilon, as main() reads them (libsvm gets the same).
HYPER = []

REPEAT_BELOW_S = 1.0
REPEATS = 5
ROUNDS = 3


def paired(palpus, source, n, dump, budget_s, threads, c, gamma, eps, with_libsvm=True):
    """Our fit of n samples and libsvm's of the same dump, each timed as the module says.

    Returns (ours, libsvm): libsvm's is None when not asked for, and ours carries "error" (and
    libsvm's is None) when our fit failed."""
    o = ours_run(palpus, source, [n], dump, budget_s, threads)[0]
    if "error" in o:
        return o, None
    path = dump / f"svr_scale_n{o['n']}.csv"
    lib = libsvm(path, c, gamma, eps, 1) if with_libsvm else None
    for _ in range(ROUNDS):
        if o["s"] < REPEAT_BELOW_S:
            # The memory column stays the single fit's own process peak.
            runs = [r for r in ours_run(palpus, source, [n] * REPEATS, dump, budget_s, threads)
                    if "error" not in r]
            o = dict(min([o, *runs], key=lambda r: r["s"]), mb=o["mb"])
        if lib is not None and lib["s"] < REPEAT_BELOW_S:
            again = libsvm(path, c, gamma, eps, REPEATS)
            lib = dict(lib, s=min(lib["s"], again["s"]))
    return o, lib


def ours_run(palpus, source, sizes, dump, budget_s, threads):
    pool = ["--threads", str(threads)] if threads else []
    run = subprocess.run(
        [palpus, *pool, "bench", "svr-scale", *source, "--sizes", ",".join(map(str, sizes)),
         "--dump", str(dump), "--budget-s", str(budget_s), *HYPER],
        capture_output=True, text=True,
    )
    if run.returncode != 0:
        return [{"n": sizes[0], "error": (run.stderr.strip().splitlines() or ["failed"])[-1]}]
    # n, seconds, solver (may hold spaces), iterations, SVs, gap, peak MB: one line per size.
    rows = []
    for line in run.stdout.splitlines()[-len(sizes):]:
        f = line.split()
        rows.append({"n": int(f[0]), "s": float(f[1]), "solver": " ".join(f[2:-4]), "iterations": int(f[-4]),
                     "svs": int(f[-3]), "gap": float(f[-2]), "mb": float(f[-1])})
    return rows


def libsvm(path, c, gamma, eps, repeats):
    """scikit-learn's SVR on a dump: the fastest of `repeats` fits in this process."""
    d = np.loadtxt(path, delimiter=",", skiprows=1)
    x, y = d[:, :-2], d[:, -2]
    m = SVR(kernel="rbf", C=c, gamma=gamma, epsilon=eps, tol=1e-3)
    dt = float("inf")
    for _ in range(repeats):
        t = time.perf_counter()
        m.fit(x, y)
        dt = min(dt, time.perf_counter() - t)
    diff = float(np.abs(m.predict(x) - d[:, -1]).max())
    return {"s": dt, "svs": len(m.support_), "diff": diff, "iterations": int(m.n_iter_)}


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--sizes", default="350,1000,3000,8000,30000")
    ap.add_argument("--libsvm-max", type=int, default=10**9, help="skip libsvm above this n")
    ap.add_argument("--palpus", default=str(ROOT / "target/release/palpus"))
    ap.add_argument("--work", default=None, help="folder for the capture and dumps (default: temporary)")
    ap.add_argument("--budget-s", type=float, default=600.0)
    ap.add_argument("--capture", default=None, help="insertion capture to sweep (default: the generated 1 kHz log)")
    ap.add_argument("--data", default=None, help="a regression table instead (scripts/friedman1.py)")
    ap.add_argument("--c", type=float, default=100.0)
    ap.add_argument("--gamma", type=float, default=30.0)
    ap.add_argument("--epsilon", type=float, default=0.02)
    ap.add_argument("--threads", type=int, default=None, help="our solvers' threads (default: one per core)")
    ap.add_argument("--csv", default=None, help="also write the rows here")
    a = ap.parse_args()
    work = Path(a.work or tempfile.mkdtemp(prefix="svr_scale_"))
    capture = Path(a.capture) if a.capture else work / "li_bi/needle_train.csv"
    source = ["--data", a.data] if a.data else ["--capture", str(capture)]
    HYPER[:] = ["--c", str(a.c), "--gamma", str(a.gamma), "--epsilon", str(a.epsilon)]
    rows = []
    if not a.data and not capture.exists():
        subprocess.run([a.palpus, "gen", "--seed", "7", "--out", str(work), "--needle-rate-hz", "1000",
                        "--needle-rounds", "2", "-q"], check=True)
    print(f"{'n':>7} {'ours s':>9} {'libsvm s':>9} {'ratio':>7} {'peak MB':>8} {'SVs':>13} "
          f"{'our gap':>8} {'max |Δf| N':>11}  solver")
    for n in [int(s) for s in a.sizes.split(",")]:
        o, lib = paired(a.palpus, source, n, work, a.budget_s, a.threads, a.c, a.gamma, a.epsilon,
                        with_libsvm=n <= a.libsvm_max)
        if "error" in o:
            print(f"{n:>7} ours failed: {o['error']}", flush=True)
            continue
        if lib is not None:
            row = (f"{lib['s']:>9.3f} {lib['s'] / o['s']:>6.2f}× {o['mb']:>8.0f} "
                   f"{o['svs']:>6}/{lib['svs']:<6} {o['gap']:>8.0e} {lib['diff']:>11.1e}")
        else:
            row = f"{'skipped':>9} {'':>7} {o['mb']:>8.0f} {o['svs']:>6}/{'':<6} {o['gap']:>8.0e} {'':>11}"
        print(f"{o['n']:>7} {o['s']:>9.3f} {row}  {o['solver']}", flush=True)
        rows.append([o["n"], o["s"], lib["s"] if lib else "", o["mb"], o["svs"], lib["svs"] if lib else "",
                     o["gap"], lib["diff"] if lib else "", o["solver"]])
    if a.csv:
        Path(a.csv).parent.mkdir(parents=True, exist_ok=True)
        with open(a.csv, "w") as out:
            out.write("n,ours_s,libsvm_s,our_peak_mb,our_svs,libsvm_svs,our_gap,max_abs_diff_n,our_solver\n")
            for r in rows:
                out.write(",".join(str(v) for v in r) + "\n")


if __name__ == "__main__":
    sys.exit(main())
