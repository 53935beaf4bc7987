#!/usr/bin/env python3
"""docs/recognition.md's table of default training at a real study's size, from one run.

Generates a sliding study of a real one's shape (`palpus gen --slide-trials 50 --slide-s 7`: 20
surfaces x 50 trials, each sliding 7 s, a 2.2 kHz vibration channel packed 22 samples per row),
imports every trial with the options its README gives, trains each method with its default
options on trials 1-25 (`palpus recognize train --method M`, nothing else) and evaluates on
trials 26-50 (`palpus recognize eval`). Prints one Markdown row per method: the wall-clock
seconds of the training command (reading the 500 captures included), its peak memory, the
features it chose, and the evaluation's accuracy over windows.

    python3 scripts/study_training_time.py [--palpus target/release/palpus] [--threads N]

Run it on an idle machine: the seconds are wall-clock.
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


def main():
    p = cli_parser(__doc__)
    p.add_argument("--threads", type=int, default=None, help="palpus --threads (default: one per core)")
    a = p.parse_args()
    pool = [] if a.threads is None else ["--threads", str(a.threads)]
    with tempfile.TemporaryDirectory() as tmp:
        root = Path(tmp)
        start = time.perf_counter()
        palpus(a.palpus, "gen", "--out", str(root / "logs"), "--slide-trials", str(TRIALS),
               "--slide-s", str(SLIDE_S), "-q")
        generated = time.perf_counter() - start
        start = time.perf_counter()
        imported = import_sliding_study(a.palpus, root / "logs" / "multistream", root / "captures")
        import_s = time.perf_counter() - start
        train = [c for t, c in imported if t <= TRAIN_TRIALS]
        test = [c for t, c in imported if t > TRAIN_TRIALS]
        print(f"20 surfaces x {TRIALS} trials of {SLIDE_S} s generated in {generated:.1f} s, "
              f"imported in {import_s:.1f} s; training on {len(train)} captures, testing on {len(test)}",
              file=sys.stderr)
        print("| method (defaults) | features chosen | training [s] | peak memory [MB] | test accuracy |")
        print("|---|---|---|---|---|")
        for method in METHODS:
            model = root / f"{method}.json"
            said, seconds, peak_mb = timed(a.palpus, [*pool, "recognize", "train", "--method", method,
                                                      "--out", str(model), *train])
            found = re.search(r"trained \S+ over (\S+) features", said)
            features = found.group(1) if found else "?"
            evaluated = palpus(a.palpus, "recognize", "eval", str(model), *test)
            accuracy = re.search(r"accuracy ([\d.]+ %) over (\d+) decisions", evaluated)
            acc = f"{accuracy.group(1)} of {int(accuracy.group(2)):,} windows" if accuracy else "?"
            print(f"| {method} | {features} | {seconds:.1f} | {peak_mb:.0f} | {acc} |")
            sys.stdout.flush()


if __name__ == "__main__":
    main()
