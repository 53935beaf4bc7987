#!/usr/bin/env python3
"""docs/recognition-fusion.md's table of vibration recognition at sliding speeds it was not trained at, from one run.

Generates the multi-stream sliding study (`palpus gen --only multistream --slide-speed-mps V`:
20 surfaces x 10 trials, a 2.2 kHz vibration channel) at the study's 25 mm/s and at each test
speed; each trial crosses the same strip of its surface at every speed. Trains SVMs over
0.25 s windows decided at their last sample on trials 1-5 at 25 mm/s, and evaluates each on
trials 6-10 at every speed (`recognize eval --sequential 0.9`):

- the window's vibration spectrum in bands of hertz (`--features vibration`), and over travel
  (`--windows-over-travel --travel-speed-mps 0.025`: windows of 6.25 mm, bands in cycles per
  metre that are 0-200 Hz at 25 mm/s), each with mean bands and with their shape alone
  (`--cells unit-sum`);
- Nakano's features over the same windows, for reference;
- the spectrum in hertz and the shape over travel again, trained on trials 1-5 at the other
  test speeds (12.5 and 50 mm/s by default), so that 25 mm/s is a speed between those trained.

Prints one Markdown row per recognizer and test speed: windows named, named decisions right,
the mean time to the stable right surface and the slowest surface's mean, trials not ending
named right, and the posterior's calibration error.

    python3 scripts/vibration_speed_table.py [--palpus target/release/palpus] [--speeds 0.0125,0.025,0.05]
"""

import json
import sys
import tempfile
from pathlib import Path

from palpus_cli import import_sliding_study, palpus, parser as cli_parser

TRAIN_SPEED_MPS = 0.025
TRAIN_TRIALS = 5
THRESHOLD = "0.9"
WINDOWS = ["--window-s", "0.25", "--mirrored-end"]
OVER_TRAVEL = ["--windows-over-travel", "--travel-speed-mps", str(TRAIN_SPEED_MPS)]
# (name, options, trained at the other test speeds instead of 25 mm/s)
RECOGNIZERS = [
    ("vibration, bands in Hz", ["--features", "vibration"], False),
    ("vibration, bands in Hz, shape", ["--features", "vibration", "--cells", "unit-sum"], False),
    ("vibration over travel", ["--features", "vibration", *OVER_TRAVEL], False),
    ("vibration over travel, shape", ["--features", "vibration", "--cells", "unit-sum", *OVER_TRAVEL], False),
    ("Nakano's features over travel", ["--features", "nakano", *OVER_TRAVEL], False),
    ("vibration, bands in Hz, trained at the others", ["--features", "vibration"], True),
    ("vibration over travel, shape, trained at the others",
     ["--features", "vibration", "--cells", "unit-sum", *OVER_TRAVEL], True),
]


def main():
    parser = cli_parser(__doc__)
    parser.add_argument("--speeds", default="0.0125,0.025,0.05")
    args = parser.parse_args()
    speeds = [float(s) for s in args.speeds.split(",")]
    with tempfile.TemporaryDirectory() as tmp:
        root = Path(tmp)
        train, test = {}, {}
        for speed in sorted(set(speeds) | {TRAIN_SPEED_MPS}):
            logs = root / f"logs_{speed}"
            print(f"generating and importing the study at {1e3 * speed:g} mm/s", file=sys.stderr, flush=True)
            palpus(args.palpus, "gen", "--out", str(logs), "--slide-speed-mps", str(speed), "-q")
            for trial, capture in import_sliding_study(args.palpus, logs / "multistream",
                                                       root / f"captures_{speed}"):
                (train if trial <= TRAIN_TRIALS else test).setdefault(speed, []).append(capture)
        print("| recognizer | test speed | windows named | named right | stable right (mean) "
              "| slowest surface | trials not ending right | calibration error |")
        print("|---|---|---|---|---|---|---|---|")
        for k, (name, options, others) in enumerate(RECOGNIZERS):
            model = str(root / f"model{k}.json")
            print(f"training and evaluating: {name}", file=sys.stderr, flush=True)
            trained = ([c for v in speeds if v != TRAIN_SPEED_MPS for c in train[v]] if others
                       else train[TRAIN_SPEED_MPS])
            palpus(args.palpus, "recognize", "train", *trained, "--method", "svm", *WINDOWS, *options,
                   "--out", model)
            for speed in speeds:
                e = json.loads(palpus(args.palpus, "recognize", "eval", model, *test[speed],
                                      "--sequential", THRESHOLD, "--json"))
                r = e["rows"][0]
                worst = r["worst_surface"]
                stable = r["time_to_stable_correct_s"]
                print(f"| {name} | {1e3 * speed:g} mm/s | {100 * r['decided'] / e['steps']:.1f} % "
                      f"| {100 * r['correct'] / max(r['decided'], 1):.1f} % "
                      f"| {'-' if stable is None else f'{stable:.2f} s'} "
                      f"| {f'{worst[1]:.2f} s ({worst[0]})' if worst else '-'} "
                      f"| {r['not_stable']} of {e['captures']} | {100 * r['calibration']['ece']:.1f} % |",
                      flush=True)


if __name__ == "__main__":
    main()
