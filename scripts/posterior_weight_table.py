#!/usr/bin/env python3
"""docs/recognition-anytime.md's table of the posterior's weight fitted on held-out recordings against hop / window.

Two sets, each recognizer trained twice on the same captures: as `recognize train` does by
default (the weight fitted on the recordings held out of training) and with `--no-weight-fit`
(every window weighing hop / window). Each is then evaluated on recordings it never saw.

- The scene `surfaces_nakano`: its SVM trained as the scene's header says, on captures made
  through the simulated device on tracks 10, 60 and 110 mm into each patch, and evaluated on
  tracks 35 and 85 mm in (`--sequential` at `--thresholds`); then the same over windows of fixed
  time (the header's command without its three travel options), and over travel with each
  window's height spectrum after Nakano's features (`--features nakano-spectrum`, its bands
  reaching 25 mm/s; the weight fitted only). Last, decided over a memory of
  `SHORT_MEMORY_S` instead of the default 3 s: the over-travel SVM whose weight was fitted over
  3 s against the same trained with `--weight-fit-memory-s` set to that memory (threshold 0.9).
- The multi-stream sliding study (as `scripts/fusion_table.py`): SVMs over Nakano's features
  and over the vibration spectrum on trials 1-5, evaluated on trials 6-10 alone and fused, at
  threshold 0.9.

Prints each fit as `recognize train` reports it, then one Markdown row per recognizer, weight
and threshold: windows named, named decisions right, the mean time to the stable right surface
and the slowest surface's, strokes not ending named right, flips per second, the posterior's
Brier score and its calibration error.

    python3 scripts/posterior_weight_table.py [--palpus target/release/palpus]
        [--thresholds 0.5,0.8,0.9,0.95]
"""

import json
import tempfile
from pathlib import Path

from palpus_cli import (SCENE_TEST_TRACKS_MM, SCENE_TRAIN_TRACKS_MM, fixed_time, palpus, parser as cli_parser,
                        scene_captures, scene_training, sequential_table, sliding_study, train_reporting_fit,
                        with_height_spectrum)

TRAIN_TRIALS = 5
# A memory other than the default's (3 s), for the rows that show what fitting at the memory used
# is worth.
SHORT_MEMORY_S = "1"


def train_both(binary, captures, options, out):
    """Trains with the weight fitted and without; returns {label: model path}."""
    out.mkdir()
    models = {}
    for label, extra in (("fitted", []), ("hop / window", ["--no-weight-fit"])):
        path = str(out / f"{len(models)}.json")
        print(f"- {label}: {train_reporting_fit(binary, captures, options + extra, path)}")
        models[label] = path
    return models


def evaluate(binary, model, captures, thresholds, fuse=(), memory_s=None):
    extra = [a for other in fuse for a in ("--fuse", other)]
    if memory_s is not None:
        extra += ["--memory-s", memory_s]
    return json.loads(palpus(binary, "recognize", "eval", model, *captures, "--sequential", thresholds,
                             *extra, "--json"))


def main():
    parser = cli_parser(__doc__)
    parser.add_argument("--thresholds", default="0.5,0.8,0.9,0.95")
    args = parser.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        root = Path(tmp)
        surfaces, options = scene_training()
        sets = {name: scene_captures(args.palpus, surfaces, tracks, root / name)
                for name, tracks in (("train", SCENE_TRAIN_TRACKS_MM), ("test", SCENE_TEST_TRACKS_MM))}
        runs = []
        for windows, opts in (("over travel", options), ("over fixed time", fixed_time(options))):
            print(f"scene surfaces_nakano, windows {windows}, trained on tracks {SCENE_TRAIN_TRACKS_MM} mm, "
                  f"tested on {SCENE_TEST_TRACKS_MM} mm:")
            scene = train_both(args.palpus, sets["train"], opts, root / windows.replace(" ", "_"))
            runs += [(f"scene SVM {windows}, {label}", evaluate(args.palpus, m, sets["test"], args.thresholds))
                     for label, m in scene.items()]
            if windows == "over travel":
                over_travel = scene["fitted"]
                print("scene surfaces_nakano, windows over travel, Nakano's features and the height's spectrum:")
                spectrum = str(root / "height_spectrum.json")
                print("- " + train_reporting_fit(args.palpus, sets["train"], with_height_spectrum(options), spectrum))
                runs.append(("scene SVM over travel, height spectrum, fitted",
                             evaluate(args.palpus, spectrum, sets["test"], args.thresholds)))

        print(f"scene surfaces_nakano, windows over travel, the weight fitted over {SHORT_MEMORY_S} s:")
        short = str(root / "short_memory.json")
        print("- " + train_reporting_fit(args.palpus, sets["train"], options + ["--weight-fit-memory-s", SHORT_MEMORY_S], short))
        runs += [(f"scene SVM over travel, decided over {SHORT_MEMORY_S} s, fitted over {fitted_s} s",
                  evaluate(args.palpus, m, sets["test"], "0.9", memory_s=SHORT_MEMORY_S))
                 for fitted_s, m in (("3", over_travel), (SHORT_MEMORY_S, short))]

        train, test = sliding_study(args.palpus, root / "study", TRAIN_TRIALS)
        study = {}
        for features in ("nakano", "vibration"):
            print(f"sliding study, SVM over {features} on trials 1-{TRAIN_TRIALS}:")
            study[features] = train_both(args.palpus, train, ["--method", "svm", "--features", features,
                                                              "--window-s", "0.25", "--mirrored-end"],
                                         root / features)
        for label in ("fitted", "hop / window"):
            nakano, vibration = study["nakano"][label], study["vibration"][label]
            runs += [(f"study, Nakano's features, {label}", evaluate(args.palpus, nakano, test, "0.9")),
                     (f"study, vibration, {label}", evaluate(args.palpus, vibration, test, "0.9")),
                     (f"study, fused, {label}", evaluate(args.palpus, nakano, test, "0.9", [vibration]))]
        sequential_table(runs, "recognizer, weight", "not ending right", scores=True)


if __name__ == "__main__":
    main()
