#!/usr/bin/env python3
"""docs/needle.md's table of the phase-aware needle model against its baselines, from one run.

Generates the held-out captures (a second tissue, strokes of varying speed) with `palpus gen`,
identifies `--model needle-phases` on each training capture with `--json`, and prints one
Markdown row per (training, held-out) pair: the held-out AISE of the phase model and of every
baseline; of the punctures the detector measured where the tissue really gave way (its
metadata's rupture depths, ±1 mm), how many the model renders within 1 mm and 10 % of the
peak; and how many drops the detector took for punctures where the tissue had none.

    python3 scripts/needle_phases_table.py [--palpus target/release/palpus]
"""

import json
import sys
import tempfile
from pathlib import Path

from palpus_cli import palpus, parser as cli_parser


def truth_ruptures(capture):
    """Per insertion, the depths at which the simulated tissue gave way (metadata line)."""
    with open(capture) as f:
        meta = dict(t.split("=", 1) for t in f.readline().split() if "=" in t)
    out = {}
    for key, value in meta.items():
        if key.startswith("truth.insertion.") and key.endswith(".puncture_depths_m"):
            out[int(key.split(".")[2])] = [float(d) for d in value.split(";") if d]
    return out


def main():
    parser = cli_parser(__doc__)
    args = parser.parse_args()
    tmp = Path(tempfile.mkdtemp(prefix="needle-phases-"))

    def gen(name, *options):
        folder = tmp / name
        palpus(args.palpus, "gen", "--out", str(folder), "-q", *options)
        return folder / "li_bi"

    liver = Path("assets/captures/li_bi")
    liver_varying = gen("liver-varying", "--needle-speed", "varying", "--seed", "4")
    phantom = gen("phantom", "--needle-tissue", "phantom", "--seed", "1")
    phantom_2 = gen("phantom-2", "--needle-tissue", "phantom", "--seed", "2")
    phantom_varying = gen("phantom-varying", "--needle-tissue", "phantom", "--needle-speed", "varying", "--seed", "3")
    pairs = [
        ("liver", liver / "needle_train.csv", "liver, committed test", liver / "needle_test.csv"),
        ("liver", liver / "needle_train.csv", "liver, varying speed (seed 4)", liver_varying / "needle_test.csv"),
        ("phantom (seed 1)", phantom / "needle_train.csv", "phantom (seed 2)", phantom_2 / "needle_test.csv"),
        ("phantom (seed 1)", phantom / "needle_train.csv", "phantom, varying speed (seed 3)", phantom_varying / "needle_test.csv"),
    ]
    print("| trained on | held out | layers | phases | Okamura piecewise | smooth ε-SVR | RBF network | Fc·sgn(v)+c·v+k·d | measured ruptures within 1 mm and 10 % | detector drops at no rupture |")
    print("|---|---|---|---|---|---|---|---|---|---|")
    for train_name, train, test_name, test in pairs:
        r = json.loads(palpus(args.palpus, "identify", str(train), "--model", "needle-phases", "--test", str(test), "--json", "-q"))
        m = r["metrics"]
        truth = truth_ruptures(test)
        good = real = spurious = 0
        for p in r["punctures"]:
            if not any(abs(t - p["measured_depth_m"]) < 1e-3 for t in truth.get(p["stroke"], [])):
                spurious += 1
                continue
            real += 1
            d, f = p["predicted_depth_m"], p["predicted_peak_force_n"]
            if d is not None and abs(d - p["measured_depth_m"]) < 1e-3 and abs(f / p["measured_peak_force_n"] - 1) < 0.10:
                good += 1
        layers = r["n_layers"]
        print(
            f"| {train_name} | {test_name} | {layers} | {m['svr']['aise']:.3e} | {m['okamura_piecewise']['aise']:.3e} | "
            f"{m['smooth_svr']['aise']:.3e} | {m['rbf_network']['aise']:.3e} | {m['coulomb_viscous_stiffness']['aise']:.3e} | "
            f"{good} of {real} | {spurious} |"
        )
    return 0


if __name__ == "__main__":
    sys.exit(main())
