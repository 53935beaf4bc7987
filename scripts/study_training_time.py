#!/usr/bin/env python3
"""docs/recognition.md's tables of default training at a real study's size, from one run.

Generates a sliding study of a real one's shape (`palpus gen --slide-trials 50 --slide-s 7`: 20
surfaces x 50 trials, each sliding 7 s, a 2.2 kHz vibration channel packed 22 samples per row),
imports every trial with the options its README gives, trains each method with its default
options on trials 1-25 (`palpus recognize train --method M`, nothing else: the features, cell
scaling, band and window are chosen on the training captures) and evaluates on trials 26-50
(`palpus recognize eval`). Prints one Markdown row per method: the wall-clock seconds of the
training command (reading the 500 captures and the search included), its peak memory, what it
chose, its accuracy over test decisions, and the best of the hand-picked choices below trained
on the same captures and evaluated on the same test (each named in full, without the search or
the posterior weight's fit, which does not change a window's decision). Then the table the
default SVM chose from, as `train` printed it.

    python3 scripts/study_training_time.py [--palpus target/release/palpus] [--threads N]
        [--captures DIR]

--captures reuses a study imported by an earlier run (DIR/mat01_trial01.csv, ...) instead of
generating one. Run it on an idle machine: the seconds are wall-clock.
"""

import re
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from palpus_cli import import_sliding_study, palpus, parser as cli_parser

TRIALS = 50
SLIDE_S = 7
TRAIN_TRIALS = 25
METHODS = ("som", "knn", "svm")


# Runs a command and reports on stderr's last line its own children's peak resident memory
# (KiB): this script's children include the generator and the imports, the wrapper's only the
# one command.
PEAK_WRAPPER = (
    "import resource, subprocess, sys\n"
    "r = subprocess.run(sys.argv[1:])\n"
    "print(resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss, file=sys.stderr)\n"
    "sys.exit(r.returncode)\n"
)


def timed(binary, args):
    """Runs `binary args`, returning (stdout + stderr, wall seconds, its peak resident MB)."""
    start = time.perf_counter()
    out = subprocess.run([sys.executable, "-c", PEAK_WRAPPER, binary, *args], capture_output=True, text=True)
    seconds = time.perf_counter() - start
    if out.returncode != 0:
        raise SystemExit(f"{binary} {' '.join(args)} exited with {out.returncode}:\n{out.stderr}")
    said, _, peak_kib = out.stderr.rstrip("\n").rpartition("\n")
    return out.stdout + said, seconds, int(peak_kib) / 1024


# Hand-picked choices: every option the search varies, named (window 3 s unless said).
FIXED = ["--cells", "mean", "--bands", "paper", "--window-s", "3", "--search-budget-s", "0", "--no-weight-fit"]
HAND_PICKED = {
    "nakano": ["--features", "nakano", *FIXED],
    "both": ["--features", "both", *FIXED],
    "both, unit-sum": ["--features", "both", *FIXED[2:], "--cells", "unit-sum"],
    "both, nyquist": ["--features", "both", "--cells", "mean", "--bands", "nyquist", *FIXED[4:]],
    "vibration": ["--features", "vibration", *FIXED],
    "nakano-spectrum": ["--features", "nakano-spectrum", *FIXED],
    "spectral (whole trials)": ["--features", "spectral", *FIXED],
}
# The SOM takes neither spectrum alone.
SOM_TAKES = ("nakano", "both", "both, unit-sum", "both, nyquist", "spectral (whole trials)")


def accuracy(binary, model, test):
    """`palpus recognize eval MODEL TEST`: (accuracy in %, decisions, what they are)."""
    evaluated = palpus(binary, "recognize", "eval", str(model), *test)
    found = re.search(r"accuracy ([\d.]+) % over (\d+) decisions", evaluated)
    if not found:
        raise SystemExit(f"no accuracy in:\n{evaluated}")
    decisions = int(found.group(2))
    return float(found.group(1)), decisions, ("trials" if decisions == len(test) else "windows")


def study(binary, root):
    """Generates and imports the study under `root`; returns its (trial, capture) pairs."""
    start = time.perf_counter()
    palpus(binary, "gen", "--out", str(root / "logs"), "--slide-trials", str(TRIALS), "--slide-s", str(SLIDE_S),
           "-q")
    generated = time.perf_counter() - start
    start = time.perf_counter()
    imported = import_sliding_study(binary, root / "logs" / "multistream", root / "captures")
    print(f"20 surfaces x {TRIALS} trials of {SLIDE_S} s generated in {generated:.1f} s, imported in "
          f"{time.perf_counter() - start:.1f} s", file=sys.stderr)
    return imported


def main():
    p = cli_parser(__doc__)
    p.add_argument("--threads", type=int, default=None, help="palpus --threads (default: one per core)")
    p.add_argument("--captures", type=Path, default=None, help="a study imported by an earlier run")
    a = p.parse_args()
    pool = [] if a.threads is None else ["--threads", str(a.threads)]
    with tempfile.TemporaryDirectory() as tmp:
        root = Path(tmp)
        if a.captures is None:
            imported = study(a.palpus, root)
        else:
            imported = [(int(re.search(r"trial(\d+)", c.name).group(1)), str(c))
                        for c in sorted(a.captures.glob("mat*_trial*.csv"))]
        train = [c for t, c in imported if t <= TRAIN_TRIALS]
        test = [c for t, c in imported if t > TRAIN_TRIALS]
        print(f"training on {len(train)} captures, testing on {len(test)}", file=sys.stderr)
        print("| method | chosen on the training captures | training [s] | peak memory [MB] | test accuracy "
              "| best hand-picked | its test accuracy |")
        print("|---|---|---|---|---|---|---|")
        tables = {}
        for method in METHODS:
            model = root / f"{method}.json"
            said, seconds, peak_mb = timed(a.palpus, [*pool, "recognize", "train", "--method", method,
                                                      "--out", str(model), *train])
            found = re.search(r"^ +[\d.]+% +\d+ +[\d.]+ +(.*?) +<- chosen$", said, re.M)
            chosen = found.group(1) if found else "?"
            tables[method] = "\n".join(line for line in said.splitlines()
                                        if line.startswith("chosen by") or line.startswith("  "))
            acc, decisions, unit = accuracy(a.palpus, model, test)
            best = None
            for name, options in HAND_PICKED.items():
                if method == "som" and name not in SOM_TAKES:
                    continue
                fixed = root / f"{method}-fixed.json"
                palpus(a.palpus, *pool, "recognize", "train", "--method", method, *options, "--out", str(fixed),
                       *train)
                got = accuracy(a.palpus, fixed, test)
                print(f"  {method} {name}: {got[0]} % of {got[1]} {got[2]}", file=sys.stderr)
                if best is None or got[0] > best[1][0]:
                    best = (name, got)
            name, (best_acc, best_n, best_unit) = best
            print(f"| {method} | {chosen} | {seconds:.1f} | {peak_mb:.0f} "
                  f"| {acc:.1f} % of {decisions:,} {unit} | {name} | {best_acc:.1f} % of {best_n:,} {best_unit} |")
            sys.stdout.flush()
        print()
        print("The default SVM chose from (as `palpus recognize train --method svm` printed it):")
        print()
        print("```")
        print(tables["svm"])
        print("```")


if __name__ == "__main__":
    main()
