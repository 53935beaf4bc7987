#!/usr/bin/env python3
"""docs/recognition-fusion.md's table of anytime decisions fused over friction and vibration, from one run.

Generates the multi-stream sliding study (`palpus gen --only multistream`: 20 surfaces x 10
trials, force, position and velocity at ~88 Hz and a 2.2 kHz vibration channel), imports every
trial as its README says, trains two SVMs over 0.25 s windows decided at their last sample on
trials 1-5 (one over Nakano's features, one over each window's vibration spectrum:
`--features vibration`), and evaluates on trials 6-10 each alone and the two fused
(`recognize eval --sequential --fuse`). Prints the fused recognizers' weights, then one
Markdown row per senses and threshold: windows named, named decisions right, the mean time to
the stable right surface and the slowest surface's mean, trials not ending named right, and
the posterior's calibration error.

Then the same for k-NNs over the same windows (at `--knn-thresholds`): each k-NN's raw vote
fractions (its file without the calibration and the fitted weight, as files were written before
them), its calibrated probabilities, and each fused with the other sense's SVM and k-NN.

    python3 scripts/fusion_table.py [--palpus target/release/palpus] [--thresholds 0.5,0.9,0.95]
        [--knn-thresholds 0.9]
"""

import json
import tempfile
from pathlib import Path

from palpus_cli import palpus, parser as cli_parser, sequential_table, sliding_study

TRAIN_TRIALS = 5


def main():
    parser = cli_parser(__doc__)
    parser.add_argument("--thresholds", default="0.5,0.9,0.95")
    parser.add_argument("--knn-thresholds", default="0.9")
    args = parser.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        root = Path(tmp)
        train, test = sliding_study(args.palpus, root, TRAIN_TRIALS)
        models = {}
        for method in ("svm", "knn"):
            for features in ("nakano", "vibration"):
                models[method, features] = str(root / f"{method}_{features}.json")
                trained = palpus(args.palpus, "recognize", "train", *train, "--method", method, "--features",
                                 features, "--window-s", "0.25", "--mirrored-end", "--out", models[method, features])
                if method == "knn":
                    calibration = next(line for line in trained.splitlines() if line.startswith("window probabilities"))
                    print(f"- k-NN over {features}: {calibration[len('window probabilities: '):]}")
                    raw = json.loads(Path(models[method, features]).read_text())
                    raw["body"].pop("calibration")
                    raw.pop("posterior_weight", None)
                    models["raw", features] = str(root / f"raw_{features}.json")
                    Path(models["raw", features]).write_text(json.dumps(raw))

        def evaluate(model, fuse=(), thresholds=args.thresholds):
            extra = [a for other in fuse for a in ("--fuse", other)]
            return json.loads(palpus(args.palpus, "recognize", "eval", model, *test, "--sequential",
                                     thresholds, *extra, "--json"))

        runs = [("Nakano's features", evaluate(models["svm", "nakano"])),
                ("vibration spectrum", evaluate(models["svm", "vibration"])),
                ("both, fused", evaluate(models["svm", "nakano"], [models["svm", "vibration"]]))]
        knn = lambda model, fuse=(): evaluate(model, fuse, args.knn_thresholds)
        knn_runs = [("k-NN, Nakano's features, raw votes", knn(models["raw", "nakano"])),
                    ("k-NN, Nakano's features, calibrated", knn(models["knn", "nakano"])),
                    ("k-NN, vibration spectrum, raw votes", knn(models["raw", "vibration"])),
                    ("k-NN, vibration spectrum, calibrated", knn(models["knn", "vibration"])),
                    ("k-NN friction + SVM vibration, fused",
                     knn(models["knn", "nakano"], [models["svm", "vibration"]])),
                    ("SVM friction + k-NN vibration, fused",
                     knn(models["svm", "nakano"], [models["knn", "vibration"]])),
                    ("k-NN friction + k-NN vibration, fused",
                     knn(models["knn", "nakano"], [models["knn", "vibration"]]))]
        print()
        for m in runs[-1][1]["fused"]:
            print(f"- {m['features']}: cross-validated accuracy {100 * m['accuracy']:.1f} %, "
                  f"reliability {m['reliability']:.3f}, weight {m['weight']:.3f}")
        sequential_table(runs, "senses")
        sequential_table(knn_runs, "recognizers")


if __name__ == "__main__":
    main()
