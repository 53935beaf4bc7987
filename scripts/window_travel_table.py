#!/usr/bin/env python3
"""docs/recognition-anytime.md's table of what one window over a few millimetres of stroke can tell, per surface.

The scene `surfaces_nakano`'s SVM (its header's options) is trained with windows spanning 1.25,
2.5 and 5 mm of travel (`--window-s` 0.25, 0.5 and 1 at 5 mm/s), over Nakano's features and over
Nakano's features followed by the height's spectrum (`--features nakano-spectrum`, its bands
reaching 25 mm/s), on the scene's training tracks (10, 60 and 110 mm into each patch), and each
window of the tracks it never saw (35 and 85 mm) is named on its own, with no posterior over
windows. A window's share named right is what that much surface tells the SVM; 5 mm is more
than the scene's stroke covers in its first second (it starts from rest). The weight of a
window in the posterior plays no part here, so it is not fitted (`--no-weight-fit`).

Prints one Markdown row per window and feature set: the share of windows named right on each
surface and on all.

    python3 scripts/window_travel_table.py [--palpus target/release/palpus]
"""

import json
import tempfile
from pathlib import Path

from palpus_cli import (SCENE_TEST_TRACKS_MM, SCENE_TRAIN_TRACKS_MM, palpus, parser as cli_parser, scene_captures,
                        scene_training, with_height_spectrum)

# Window lengths at the scene's 5 mm/s, s, and the travel each spans, mm.
WINDOWS = (("0.25", 1.25), ("0.5", 2.5), ("1", 5.0))


def with_window(options, window_s):
    """`options` with `--window-s` set to `window_s`."""
    if "--window-s" not in options:
        raise SystemExit(f"expected --window-s in {options}")
    out = list(options)
    out[out.index("--window-s") + 1] = window_s
    return out


def main():
    args = cli_parser(__doc__).parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        root = Path(tmp)
        surfaces, options = scene_training()
        train = scene_captures(args.palpus, surfaces, SCENE_TRAIN_TRACKS_MM, root / "train")
        test = scene_captures(args.palpus, surfaces, SCENE_TEST_TRACKS_MM, root / "test")
        rows = []
        for label, opts in (("Nakano's features", options), ("+ height spectrum", with_height_spectrum(options))):
            for window_s, travel_mm in WINDOWS:
                model = str(root / f"{len(rows)}.json")
                palpus(args.palpus, "recognize", "train", *train, *with_window(opts, window_s), "--no-weight-fit",
                       "--out", model)
                e = json.loads(palpus(args.palpus, "recognize", "eval", model, *test, "--json"))
                per_class = e["per_class"]
                cells = [f"{100 * per_class[s]:.1f} %" for s in surfaces]
                rows.append(f"| {travel_mm:g} mm | {label} | " + " | ".join(cells) + f" | {100 * e['accuracy']:.1f} % |")
        print("| window | features | " + " | ".join(surfaces) + " | all |")
        print("|---|---|" + "---|" * len(surfaces) + "---|")
        for row in rows:
            print(row)


if __name__ == "__main__":
    main()
