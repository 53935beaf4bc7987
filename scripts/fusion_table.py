#!/usr/bin/env python3
"""README's table of anytime decisions fused over friction and vibration, from one run.

Generates the multi-stream sliding study (`palpus gen --only multistream`: 20 surfaces x 10
trials, force, position and velocity at ~88 Hz and a 2.2 kHz vibration channel), imports every
trial as its README says, trains two SVMs over 0.25 s windows decided at their last sample on
trials 1-5 (one over Nakano's features, one over each window's vibration spectrum:
`--features vibration`), and evaluates on trials 6-10 each alone and the two fused
(`recognize eval --sequential --fuse`). Prints the fused recognizers' weights, then one
Markdown row per senses and threshold: windows named, named decisions right, the mean time to
the stable right surface and the slowest surface's mean, trials not ending named right, and
the posterior's calibration error.

    python3 scripts/fusion_table.py [--palpus target/release/palpus] [--thresholds 0.5,0.9,0.95]
"""

import json
import tempfile
from pathlib import Path

from palpus_cli import import_sliding_study, palpus, parser as cli_parser

TRAIN_TRIALS = 5


def main():
    parser = cli_parser(__doc__)
    parser.add_argument("--thresholds", default="0.5,0.9,0.95")
    args = parser.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        root = Path(tmp)
        palpus(args.palpus, "gen", "--out", str(root / "logs"), "--only", "multistream", "-q")
        train, test = [], []
        for trial, capture in import_sliding_study(args.palpus, root / "logs" / "multistream", root / "captures"):
            (train if trial <= TRAIN_TRIALS else test).append(capture)
        models = {}
        for features in ("nakano", "vibration"):
            models[features] = str(root / f"{features}.json")
            palpus(args.palpus, "recognize", "train", *train, "--method", "svm", "--features", features,
                   "--window-s", "0.25", "--mirrored-end", "--out", models[features])

        def evaluate(model, fuse=()):
            extra = [a for other in fuse for a in ("--fuse", other)]
            return json.loads(palpus(args.palpus, "recognize", "eval", model, *test, "--sequential",
                                     args.thresholds, *extra, "--json"))

        runs = [("Nakano's features", evaluate(models["nakano"])),
                ("vibration spectrum", evaluate(models["vibration"])),
                ("both, fused", evaluate(models["nakano"], [models["vibration"]]))]
        for m in runs[-1][1]["fused"]:
            print(f"- {m['features']}: cross-validated accuracy {100 * m['accuracy']:.1f} %, "
                  f"reliability {m['reliability']:.3f}, weight {m['weight']:.3f}")
        print()
        print("| senses | threshold | windows named | named right | stable right (mean) | slowest surface "
              "| trials not ending right | calibration error |")
        print("|---|---|---|---|---|---|---|---|")
        for name, e in runs:
            for r in e["rows"]:
                worst = r["worst_surface"]
                stable = r["time_to_stable_correct_s"]
                print(f"| {name} | {r['threshold']:g} | {100 * r['decided'] / e['steps']:.1f} % "
                      f"| {100 * r['correct'] / max(r['decided'], 1):.1f} % "
                      f"| {'-' if stable is None else f'{stable:.2f} s'} "
                      f"| {f'{worst[1]:.2f} s ({worst[0]})' if worst else '-'} "
                      f"| {r['not_stable']} of {e['captures']} | {100 * e['calibration']['ece']:.1f} % |")


if __name__ == "__main__":
    main()
