#!/usr/bin/env python3
"""docs/svr-scaling.md's sweep: the ε-SVR's fit time against n on five problems, ours beside libsvm's.

Run from the repository root after `cargo build --release --locked`, on an idle machine (needs
numpy and scikit-learn; the project's tests do not):

    python3 scripts/svr_scale_sweep.py [--sizes 30] [--threads 1] [--out docs]

For each problem, 30 sizes spaced evenly on a log scale from 350 to 30,000 (to a capture's
in-tissue samples where it has fewer); each size is fitted by `palpus bench svr-scale` in its
own process and by scikit-learn's libsvm on the same samples (scripts/bench_svr_scale.py: the
fastest of fifteen fits below a second, in three rounds that alternate the two sides). The problems:

- `li_bi 100 Hz`: the committed needle capture the main job identifies from (7,514 samples in
  tissue), the needle's C = 100, γ = 30, ε = 0.02 N;
- `needle 1 kHz`: `palpus gen --seed 7 --needle-rate-hz 1000 --needle-rounds 2`, same settings;
- `needle 1 kHz, varying speed`: the same log with each stroke's speed varying ±60 % within it
  (`--needle-speed varying`): many speeds, so the kernel over (depth, speed) is far from the
  low rank of a few constant speeds;
- `friedman1 p=5`, `friedman1 p=10`: Friedman #1 (scripts/friedman1.py, noise σ = 1), C = 10,
  γ = 1, ε = 0.5 on inputs scaled to the unit box.

Ours run on --threads threads (1 by default: libsvm is single-threaded). Writes
OUT/svr_scale_sweep.csv (one row per fit: problem, n, our and libsvm's seconds, our peak memory,
support vectors, our certified gap, the two models' largest prediction difference, our solver's
path, and each solver's iterations: ours are SMO's pair steps or the interior point's Newton
steps, libsvm's its pair steps) and draws OUT/svr_scale_sweep.png with `palpus bench
svr-scale-plot`, which also prints the per-problem summary (worst and median ratio, worst
spike).
"""

import argparse
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
import bench_svr_scale as bench  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
NEEDLE = (100.0, 30.0, 0.02)
FRIEDMAN = (10.0, 1.0, 0.5)
COLUMNS = ("problem,n,ours_s,libsvm_s,our_peak_mb,our_svs,libsvm_svs,our_gap,max_abs_diff,our_solver,"
           "our_iterations,libsvm_iterations")


def problems(palpus, work):
    """(name, `bench svr-scale` source arguments, (C, γ, ε), most samples) of each problem."""
    logs = {}
    for name, extra in (("constant", []), ("varying", ["--needle-speed", "varying"])):
        out = work / f"needle_{name}"
        subprocess.run([palpus, "gen", "--seed", "7", "--out", str(out), "--needle-rate-hz", "1000",
                        "--needle-rounds", "2", *extra, "-q"], check=True)
        logs[name] = out / "li_bi" / "needle_train.csv"
    tables = {}
    for p in (5, 10):
        tables[p] = work / f"friedman1_{p}.csv"
        subprocess.run([sys.executable, str(ROOT / "scripts" / "friedman1.py"), "--inputs", str(p), "--rows",
                        "30000", "--out", str(tables[p])], check=True)
    return [
        ("li_bi 100 Hz", ["--capture", str(ROOT / "assets/captures/li_bi/needle_train.csv")], NEEDLE, 7514),
        ("needle 1 kHz", ["--capture", str(logs["constant"])], NEEDLE, None),
        ("needle 1 kHz, varying speed", ["--capture", str(logs["varying"])], NEEDLE, None),
        ("friedman1 p=5", ["--data", str(tables[5])], FRIEDMAN, None),
        ("friedman1 p=10", ["--data", str(tables[10])], FRIEDMAN, None),
    ]


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--sizes", type=int, default=30, help="sizes per problem")
    ap.add_argument("--largest", type=int, default=30000)
    ap.add_argument("--threads", type=int, default=1, help="our solvers' threads")
    ap.add_argument("--palpus", default=str(ROOT / "target/release/palpus"))
    ap.add_argument("--out", default=str(ROOT / "docs"))
    ap.add_argument("--only", default=None, help="the problems whose name contains this")
    a = ap.parse_args()
    out = Path(a.out)
    out.mkdir(parents=True, exist_ok=True)
    csv = out / "svr_scale_sweep.csv"
    with tempfile.TemporaryDirectory(prefix="svr_sweep_") as tmp:
        work = Path(tmp)
        rows = []
        for name, source, (c, gamma, eps), most in problems(a.palpus, work):
            if a.only and a.only not in name:
                continue
            bench.HYPER[:] = ["--c", str(c), "--gamma", str(gamma), "--epsilon", str(eps)]
            top = min(a.largest, most) if most else a.largest
            sizes = sorted({int(round(n)) for n in np.geomspace(350, top, a.sizes)})
            for n in sizes:
                dump = work / "dump"
                dump.mkdir(exist_ok=True)
                o, lib = bench.paired(a.palpus, source, n, dump, 600.0, a.threads, c, gamma, eps)
                if "error" in o:
                    print(f"{name} n={n}: ours failed: {o['error']}", file=sys.stderr, flush=True)
                    continue
                print(f"{name} n={o['n']}: ours {o['s']:.3f} s ({o['solver']}), libsvm {lib['s']:.3f} s",
                      file=sys.stderr, flush=True)
                rows.append([f'"{name}"', o["n"], o["s"], lib["s"], o["mb"], o["svs"], lib["svs"], o["gap"],
                             lib["diff"], f'"{o["solver"]}"', o["iterations"], lib["iterations"]])
                for f in dump.iterdir():
                    f.unlink()
    with open(csv, "w") as f:
        f.write(COLUMNS + "\n")
        for r in rows:
            f.write(",".join(str(v) for v in r) + "\n")
    subprocess.run([a.palpus, "bench", "svr-scale-plot", str(csv), "--out", str(out / "svr_scale_sweep.png")],
                   check=True)


if __name__ == "__main__":
    sys.exit(main())
