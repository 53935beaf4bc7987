#!/usr/bin/env python3
"""docs/recognition.md's table of default training on studies with a real rig's faults, from one run.

For each rig -- as modelled, and with each fault `palpus gen --rig-effect` simulates (the
vibration sensor's mount ringing at a fixed 160 Hz, the force sensor's offset drifting, a
vibration channel of noise only) -- and for a study with unequal recordings per class (surfaces
11-20 with 8 training trials where 1-10 have 25), generates a sliding study of a real one's shape
(20 surfaces, 7 s slides at 2.2 kHz; trials 1-25 train, 26-35 test), imports every trial with the
options its README gives, and for each method:

- trains it with its default options (`palpus recognize train --method M`: the features, cell
  scaling, band and window chosen on the training captures), timing the whole command and its
  peak memory, and evaluates it on the test trials;
- trains each hand-picked choice below, every option named (no search, no posterior weight fit,
  which does not change a window's decision), and evaluates it the same way;

and computes an independent reference with scikit-learn: per trial, the vibration's log power in
8 Hz bands up to 200 Hz and 10 wider ones up to its Nyquist frequency (Welch), its level, the
friction's mean, spread and ratio to the normal force, and the height's spread after a 2.5 mm
high-pass, standardised, into an RBF SVC whose C and gamma are
cross-validated grouped by trial (5 folds), scored on the test trials (one decision per trial).

Prints one Markdown row per rig and method.

    python3 scripts/rig_effects_study.py [--palpus target/release/palpus] [--rigs none,resonance,...]

Run it on an idle machine: the seconds are wall-clock. It takes about 40 minutes on 2 cores.
"""

import re
import sys
import tempfile
from pathlib import Path

import numpy as np
from scipy.signal import welch
from sklearn.model_selection import GridSearchCV, GroupKFold
from sklearn.pipeline import make_pipeline
from sklearn.preprocessing import StandardScaler
from sklearn.svm import SVC

from palpus_cli import HAND_PICKED, SOM_TAKES, accuracy, import_sliding_study, palpus, parser as cli_parser, timed

TRIALS = 35
SLIDE_S = 7
TRAIN_TRIALS = 25
# Unequal recordings: surfaces past this one keep only FEW training trials.
UNEQUAL_FROM = 11
FEW = 8
RIGS = ("none", "resonance", "drift", "noise-only", "unequal")
METHODS = ("som", "knn", "svm")
# The hand-picked choices tried on every rig (palpus_cli.HAND_PICKED but nakano-spectrum).
PICKED = ("nakano", "both", "both, unit-sum", "both, nyquist", "vibration", "spectral (whole trials)")


def trains(rig, surface, trial):
    """Whether trial `trial` (from 1) of surface `surface` (from 1) is a training trial."""
    if rig == "unequal" and surface >= UNEQUAL_FROM:
        return trial <= FEW
    return trial <= TRAIN_TRIALS


def trial_features(path):
    """The reference's per-trial features of one imported capture."""
    with open(path) as f:
        f.readline()
        names = f.readline().strip().split(",")
        values = np.loadtxt(f, delimiter=",")
    data = {name: values[:, i] for i, name in enumerate(names)}
    rate = 2200.0
    vibration = data["vibration_mps2"]
    f, pxx = welch(vibration - vibration.mean(), fs=rate, nperseg=1024)
    # 8 Hz bands up to 200 Hz, where sliding textures ring, and 10 wide ones up to Nyquist.
    edges = np.concatenate([np.linspace(0.0, 200.0, 26), np.linspace(200.0, rate / 2, 11)[1:]])
    bands = [np.log(pxx[(f >= lo) & (f < hi)].sum() + 1e-30) for lo, hi in zip(edges[:-1], edges[1:])]
    x = data["tangential_position_m"]
    moving = np.abs(np.gradient(x)) * rate > 0.005
    friction = data["friction_force_n"][moving] if moving.any() else data["friction_force_n"]
    height = data["normal_position_m"][moving] if moving.any() else data["normal_position_m"]
    # A 2.5 mm high-pass of the height over travel, roughly: the height less its moving mean.
    span = max(1, int(round(0.0025 / max(np.median(np.abs(np.gradient(x))), 1e-9))))
    kernel = np.ones(min(span, len(height))) / min(span, len(height))
    relief = height - np.convolve(height, kernel, mode="same")
    normal = data["normal_force_n"][moving] if moving.any() else data["normal_force_n"]
    return [*bands, np.log(vibration.std() + 1e-12), friction.mean(), friction.std(),
            friction.mean() / max(normal.mean(), 1e-9), np.log(relief.std() + 1e-12)]


def sklearn_reference(train, test):
    """Accuracy (%) of the reference on the test trials, and its test trial count."""
    def xy(captures):
        xs, ys, groups = [], [], []
        for surface, trial, path in captures:
            xs.append(trial_features(path))
            ys.append(surface)
            groups.append(trial)
        return np.array(xs), np.array(ys), np.array(groups)

    x, y, groups = xy(train)
    grid = GridSearchCV(
        make_pipeline(StandardScaler(), SVC(kernel="rbf")),
        {"svc__C": [1, 10, 100, 1000], "svc__gamma": ["scale", 0.01, 0.1]},
        cv=GroupKFold(n_splits=5),
    )
    grid.fit(x, y, groups=groups)
    tx, ty, _ = xy(test)
    return 100.0 * (grid.predict(tx) == ty).mean(), len(ty)


def main():
    p = cli_parser(__doc__)
    p.add_argument("--rigs", default=",".join(RIGS), help="which of " + ", ".join(RIGS))
    a = p.parse_args()
    print("| rig | method | chosen on the training captures | training [s] | peak memory [MB] | test accuracy "
          "| best hand-picked | its test accuracy | scikit-learn reference (per trial) |")
    print("|---|---|---|---|---|---|---|---|---|")
    for rig in a.rigs.split(","):
        with tempfile.TemporaryDirectory() as tmp:
            root = Path(tmp)
            effect = [] if rig in ("none", "unequal") else ["--rig-effect", rig]
            palpus(a.palpus, "gen", "--out", str(root / "logs"), "--slide-trials", str(TRIALS), "--slide-s",
                   str(SLIDE_S), *effect, "-q")
            imported = import_sliding_study(a.palpus, root / "logs" / "multistream", root / "captures")
            every = [(int(re.search(r"mat(\d+)", c).group(1)), t, c) for t, c in imported]
            train = [(s, t, c) for s, t, c in every if trains(rig, s, t)]
            test = [(s, t, c) for s, t, c in every if t > TRAIN_TRIALS]
            train_paths, test_paths = [c for *_, c in train], [c for *_, c in test]
            print(f"{rig}: training on {len(train)} captures, testing on {len(test)}", file=sys.stderr)
            reference, reference_n = sklearn_reference(train, test)
            for method in METHODS:
                model = root / f"{method}.json"
                said, seconds, peak_mb = timed(a.palpus, ["recognize", "train", "--method", method, "--out",
                                                          str(model), *train_paths])
                found = re.search(r"^ +[\d.]+% +\d+ +[\d.]+ +(.*?) +<- chosen$", said, re.M)
                chosen = found.group(1) if found else "?"
                acc, decisions, unit = accuracy(a.palpus, model, test_paths)
                best = None
                for name in PICKED:
                    if method == "som" and name not in SOM_TAKES:
                        continue
                    fixed = root / f"{method}-fixed.json"
                    palpus(a.palpus, "recognize", "train", "--method", method, *HAND_PICKED[name], "--out",
                           str(fixed), *train_paths)
                    got = accuracy(a.palpus, fixed, test_paths)
                    print(f"  {rig} {method} {name}: {got[0]} % of {got[1]} {got[2]}", file=sys.stderr)
                    if best is None or got[0] > best[1][0]:
                        best = (name, got)
                name, (best_acc, best_n, best_unit) = best
                print(f"| {rig} | {method} | {chosen} | {seconds:.1f} | {peak_mb:.0f} | {acc:.1f} % of {decisions:,} "
                      f"{unit} | {name} | {best_acc:.1f} % of {best_n:,} {best_unit} | {reference:.1f} % of "
                      f"{reference_n} trials |")
                sys.stdout.flush()


if __name__ == "__main__":
    main()
