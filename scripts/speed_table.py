#!/usr/bin/env python3
"""docs/recognition-anytime.md's table of anytime recognition at other rubbing speeds, from one run.

Generates Nakano's surfaces rubbed at 2, 5 and 20 mm/s (`palpus gen --only nakano`,
`--rub-speed-mps`) and the two-patch strokes at each speed (`--two-patch`), trains three SVMs over
0.25 s windows decided at their last sample on run 0 at 5 mm/s: one over windows of fixed time,
one with the friction filtered over travel, the roughness filters following the speed down to
2 mm/s and windows over travel, and the same over travel with each window's height spectrum
after Nakano's features (`--features nakano-spectrum`, its bands reaching the fastest speed
rubbed with a quarter to spare: `--fastest-speed-mps`). Evaluates each at threshold 0.9 on
runs 1-2 and on the two-patch strokes at each speed. Prints one Markdown row per speed and SVM: named decisions right, the
calibration error, the mean time to the stable right surface and the slowest surface's mean,
each with the tool's path by then (through the play), strokes not ending named right, and on the
two-patch strokes the mean and slowest time from the seam to the stable new surface, with the path
since the seam, and the strokes not followed.

    python3 scripts/speed_table.py [--palpus target/release/palpus] [--speeds 0.002,0.005,0.02]
"""

import json
import tempfile
from pathlib import Path

from palpus_cli import palpus, parser as cli_parser

OVER_TRAVEL = ["--friction-over-travel", "--slowest-speed-mps", "0.002", "--windows-over-travel"]


def main():
    parser = cli_parser(__doc__)
    parser.add_argument("--speeds", default="0.002,0.005,0.02")
    args = parser.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        root = Path(tmp)
        palpus(args.palpus, "gen", "--out", str(root / "protocol"), "--only", "nakano", "-q")
        train = [str(p) for p in sorted((root / "protocol" / "nakano").glob("*run0.csv"))]
        fastest = 1.25 * max(float(s) for s in args.speeds.split(","))
        spectrum = ["--features", "nakano-spectrum", "--fastest-speed-mps", f"{fastest:g}"]
        kinds = [("time", "fixed time", ["--features", "nakano"]),
                 ("travel", "over travel", ["--features", "nakano", *OVER_TRAVEL]),
                 ("spectrum", "over travel, height spectrum", [*spectrum, *OVER_TRAVEL])]
        models = {}
        for name, _, extra in kinds:
            models[name] = str(root / f"{name}.json")
            palpus(args.palpus, "recognize", "train", *train, "--method", "svm",
                   "--window-s", "0.25", "--mirrored-end", *extra, "--out", models[name])

        def row(model, captures):
            out = palpus(args.palpus, "recognize", "eval", model, *captures, "--sequential", "0.9", "--json")
            e = json.loads(out)
            return e["rows"][0], e["rows"][0]["calibration"]["ece"]

        def secs(v):
            return "-" if v is None else f"{v:.2f} s"

        def at(v, m):
            """A time and the path by then."""
            return secs(v) if m is None else f"{secs(v)}, {1e3 * m:.1f} mm"

        def slowest(s):
            """The slowest surface's mean time and path, and the surface; the surface with the
            longest path too where that is another."""
            worst, farthest = s["worst_surface"], s["worst_surface_travel"]
            if not worst:
                return "-"
            if not farthest:
                return f"{secs(worst[1])} ({worst[0]})"
            if farthest[0] != worst[0]:
                return f"{secs(worst[1])} ({worst[0]}); {1e3 * farthest[1]:.1f} mm ({farthest[0]})"
            return f"{at(worst[1], farthest[1])} ({worst[0]})"

        print("| speed | windows | named right | calibration error | stable right (mean) | slowest surface "
              "| strokes not ending right | two-patch: new surface after the seam (mean) | slowest | not followed |")
        print("|---|---|---|---|---|---|---|---|---|---|")
        for speed in args.speeds.split(","):
            out = root / speed
            palpus(args.palpus, "gen", "--out", str(out), "--rub-speed-mps", speed, "-q")
            palpus(args.palpus, "gen", "--out", str(out), "--two-patch", "--rub-speed-mps", speed, "-q")
            test = [str(p) for p in sorted((out / "nakano").glob("*.csv")) if not p.stem.endswith("run0")]
            two_patch = [str(p) for p in sorted((out / "nakano_two_patch").glob("*.csv"))
                         if not p.stem.endswith("run0")]
            for name, label, _ in kinds:
                (s, ece), (t, _) = row(models[name], test), row(models[name], two_patch)
                print(f"| {1e3 * float(speed):g} mm/s | {label} "
                      f"| {100 * s['correct'] / s['decided']:.1f} % | {100 * ece:.1f} % "
                      f"| {at(s['time_to_stable_correct_s'], s['travel_to_stable_correct_m'])} "
                      f"| {slowest(s)} "
                      f"| {s['not_stable']} of {len(test)} "
                      f"| {at(t['change_followed_s'], t['change_followed_m'])} "
                      f"| {at(t['slowest_change_s'], t['slowest_change_m'])} "
                      f"| {t['changes_not_followed']} of {t['changes']} |")


if __name__ == "__main__":
    main()
