#!/usr/bin/env python3
"""docs/recognition-anytime.md's table of the anytime recognizer's change test, from one run.

Generates Nakano's surfaces (`palpus gen --only nakano`) and the two-patch strokes from each
surface onto the next (`palpus gen --two-patch`), trains an SVM over 0.25 s windows on run 0,
and evaluates it at threshold 0.9 with each likelihood ratio of the change test (0: none) on
the single-surface runs 1-2 and on the two-patch strokes. Prints one Markdown row per ratio:
named decisions right and the mean and slowest time to the stable right surface on single
surfaces; on the two-patch strokes, named decisions right (against the surface under the tool),
the mean and slowest time from the seam to the stable new surface, and strokes not followed.

    python3 scripts/change_test_table.py [--palpus target/release/palpus] [--odds 0,9,99,999]
        [--mirrored-end]

With `--mirrored-end` the SVM is trained to decide each window at its last sample.
"""

import json
import tempfile
from pathlib import Path

from palpus_cli import palpus, parser as cli_parser


def main():
    parser = cli_parser(__doc__)
    parser.add_argument("--odds", default="0,9,99,999")
    parser.add_argument("--mirrored-end", action="store_true")
    args = parser.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        root = Path(tmp)
        palpus(args.palpus, "gen", "--out", str(root), "--only", "nakano", "-q")
        palpus(args.palpus, "gen", "--out", str(root), "--two-patch", "-q")
        runs = sorted((root / "nakano").glob("*.csv"))
        train = [str(p) for p in runs if p.stem.endswith("run0")]
        test = [str(p) for p in runs if not p.stem.endswith("run0")]
        two_patch = [str(p) for p in sorted((root / "nakano_two_patch").glob("*.csv"))]
        model = str(root / "svm.json")
        palpus(args.palpus, "recognize", "train", *train, "--method", "svm", "--features", "nakano",
               "--window-s", "0.25", "--out", model, *(["--mirrored-end"] if args.mirrored_end else []))

        def row(odds, captures):
            out = palpus(args.palpus, "recognize", "eval", model, *captures, "--sequential", "0.9",
                         "--change-odds", odds, "--json")
            return json.loads(out)["rows"][0]

        def secs(v):
            return "-" if v is None else f"{v:.2f} s"

        print("| change test | single: named right | stable right (mean) | slowest surface "
              "| two-patch: named right | new surface named after the seam (mean) | slowest | not followed |")
        print("|---|---|---|---|---|---|---|---|")
        for odds in args.odds.split(","):
            s, t = row(odds, test), row(odds, two_patch)
            worst = s["worst_surface"]
            print(f"| {'none' if float(odds) == 0 else odds + ':1'} "
                  f"| {100 * s['correct'] / s['decided']:.1f} % | {secs(s['time_to_stable_correct_s'])} "
                  f"| {secs(worst[1] if worst else None)} "
                  f"| {100 * t['correct'] / t['decided']:.1f} % | {secs(t['change_followed_s'])} "
                  f"| {secs(t['slowest_change_s'])} | {t['changes_not_followed']} of {t['changes']} |")


if __name__ == "__main__":
    main()
