#!/usr/bin/env python3
"""docs/recognition-anytime.md's table of how soon `palpus run scenes/surfaces_nakano.toml` names each surface.

Captures the scene's training tracks as its header says, trains its SVM four ways on them (the
header's command; the same without the three options that read windows over travel; each with
and without `--no-weight-fit`; and the header's command over `--features nakano-spectrum`, its
bands reaching 25 mm/s), runs the scene headless with each in place of the committed file
(a copy of the scene in a temporary folder, its paths made absolute), and prints, per surface in
the scene's order, the time from the stroke's start to the surface named right for good and the
tool's path by then (through the play), then
each model's named and undecided decisions. The first column's model is the committed one
(`assets/models/nakano_svm.json`), retrained: the script says whether the two differ (but for
the captures' folders).

    python3 scripts/scene_table.py [--palpus target/release/palpus] [--threshold 0.9]
"""

import json
import re
import tempfile
from pathlib import Path

from palpus_cli import SCENE, SCENE_TRAIN_TRACKS_MM, fixed_time, palpus, parser as cli_parser, scene_captures, \
    scene_training, train_reporting_fit, with_height_spectrum

COMMITTED = SCENE.parent.parent / "assets" / "models" / "nakano_svm.json"


def without_paths(node):
    """A recognizer file's JSON with each capture's path cut to its file name."""
    if isinstance(node, dict):
        return {k: Path(v).name if k == "path" and isinstance(v, str) else without_paths(v) for k, v in node.items()}
    if isinstance(node, list):
        return [without_paths(v) for v in node]
    return node


def scene_with(model, threshold, out):
    """A copy of the scene in `out` deciding with `model` at `threshold`."""
    text = SCENE.read_text().replace('"../', f'"{SCENE.parent.parent}/')
    text, files = re.subn(r'^file = "[^"]*"', f'file = "{model}"', text, flags=re.M)
    text, thresholds = re.subn(r"^threshold = .*$", f"threshold = {threshold}", text, flags=re.M)
    if files != 1 or thresholds != 1:
        raise SystemExit(f"{SCENE}: expected one recognizer file and one threshold")
    path = out / SCENE.name
    path.write_text(text)
    return path


def main():
    parser = cli_parser(__doc__)
    parser.add_argument("--threshold", default="0.9")
    args = parser.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        root = Path(tmp)
        surfaces, options = scene_training()
        captures = scene_captures(args.palpus, surfaces, SCENE_TRAIN_TRACKS_MM, root / "train")
        columns = [("over travel, fitted", options), ("fixed time, fitted", fixed_time(options)),
                   ("over travel, hop / window", options + ["--no-weight-fit"]),
                   ("fixed time, hop / window", fixed_time(options) + ["--no-weight-fit"]),
                   ("over travel, height spectrum, fitted", with_height_spectrum(options))]
        timing, totals = {}, []
        for i, (label, opts) in enumerate(columns):
            model = root / f"{i}.json"
            print(f"- {label}: {train_reporting_fit(args.palpus, captures, opts, model)}")
            if i == 0:
                same = without_paths(json.loads(model.read_text())) == without_paths(json.loads(COMMITTED.read_text()))
                print(f"  {'the same as' if same else 'DIFFERS from'} {COMMITTED.name}, but for where the captures lay")
            out = root / f"run{i}"
            out.mkdir()
            palpus(args.palpus, "run", str(scene_with(model, args.threshold, out)), "--headless", "--unpaced",
                   "--report", str(out / "report"))
            report = json.loads((out / "report" / "report.json").read_text())
            for t in report["recognition_timing"]:
                timing.setdefault(t["object"], []).append((t["stable_right_after_s"], t["stable_right_after_m"]))
            named = sum(1 for r in report["recognition"] if r["label"] is not None)
            right = report["recognition_accuracy"]
            totals.append(f"{label}: {100 * right:.1f} % of {named:,} named decisions right, "
                          f"{len(report['recognition']) - named:,} undecided")
        print(f"\nthreshold {args.threshold}\n")
        print("| surface | " + " | ".join(label for label, _ in columns) + " |")
        print("|---" * (len(columns) + 1) + "|")
        def cell(t_s, m):
            return "never" if t_s is None else f"{t_s:.2f} s, {1e3 * m:.1f} mm"

        for surface, times in timing.items():
            print(f"| {surface} | " + " | ".join(cell(*t) for t in times) + " |")
        means = []
        for i in range(len(columns)):
            column = [t[i] for t in timing.values()]
            if any(t_s is None for t_s, _ in column):
                means.append("-")
            else:
                means.append(cell(*(sum(v) / len(column) for v in zip(*column))))
        print("| mean | " + " | ".join(means) + " |")
        print()
        for line in totals:
            print(line)


if __name__ == "__main__":
    main()
