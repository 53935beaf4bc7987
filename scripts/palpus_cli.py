"""What the table scripts share: running `palpus` and their common `--palpus` option."""

import argparse
import re
import subprocess
import sys
import time
from pathlib import Path


def palpus(binary, *args):
    """Runs `binary` with `args` and returns its stdout; a non-zero exit stops the script with
    the command and what it said on stderr."""
    out = subprocess.run([binary, *args], capture_output=True, text=True)
    if out.returncode != 0:
        raise SystemExit(f"{binary} {' '.join(args)} exited with {out.returncode}:\n{out.stderr}")
    return out.stdout


def train_reporting_fit(binary, captures, options, out):
    """`palpus recognize train CAPTURES OPTIONS --out OUT`; returns the line that says how each
    window weighs in the posterior (fitted on held-out recordings, or hop / window and why)."""
    trained = palpus(binary, "recognize", "train", *captures, *options, "--out", str(out))
    return next(line for line in trained.splitlines() if line.startswith("posterior weight"))


def parser(doc):
    """An argument parser described by `doc`'s first line, with `--palpus` (the binary)."""
    p = argparse.ArgumentParser(description=doc.splitlines()[0])
    p.add_argument("--palpus", default="target/release/palpus")
    return p


SCENE = Path(__file__).resolve().parent.parent / "scenes" / "surfaces_nakano.toml"
# The tracks into each patch the scene's recognizer is trained on, as its header says.
SCENE_TRAIN_TRACKS_MM = (10, 60, 110)
# Tracks the scene's recognizer never saw, where the table scripts test it.
SCENE_TEST_TRACKS_MM = (35, 85)


def scene_training():
    """The scene's surfaces and the options its header trains its SVM with."""
    text = SCENE.read_text()
    surfaces = re.findall(r'^surface = "([^"]+)"', text, re.M)
    header = " ".join(line.lstrip("#").strip().rstrip("\\") for line in text.splitlines() if line.startswith("#"))
    found = re.search(r"palpus recognize train \S+ (--method .*?) --out", header)
    if not surfaces or not found:
        raise SystemExit(f"{SCENE} names no surfaces or no training command")
    return surfaces, found.group(1).split()


# The fastest stroke the spectra of the scene's windows read, m/s: five times its plan's 5 mm/s.
SCENE_FASTEST_SPEED_MPS = "0.025"


def with_height_spectrum(options):
    """The scene's training options over Nakano's features followed by each window's height
    spectrum, its bands reaching SCENE_FASTEST_SPEED_MPS."""
    if "nakano" not in options:
        raise SystemExit(f"expected --features nakano in {options}")
    return [("nakano-spectrum" if o == "nakano" else o) for o in options] + \
        ["--fastest-speed-mps", SCENE_FASTEST_SPEED_MPS]


def fixed_time(options):
    """The scene's training options without the three that read windows over travel (as
    docs/recognition-anytime.md's fixed-time column of the scene's times)."""
    out, skip = [], 0
    for o in options:
        if skip:
            skip -= 1
        elif o in ("--windows-over-travel", "--friction-over-travel"):
            pass
        elif o == "--slowest-speed-mps":
            skip = 1
        else:
            out.append(o)
    return out


def scene_captures(binary, surfaces, tracks_mm, out):
    """Rubs each surface through the simulated device on each track as the scene header's
    `palpus capture` does; returns the paths in the order the header's shell glob gives them
    (the weight fit's folds follow it)."""
    out.mkdir()
    paths = []
    for s in surfaces:
        for o in tracks_mm:
            path = str(out / f"{s}_{o}.csv")
            palpus(binary, "capture", "--device", "sim", "--protocol", "rubbing", "--surface", s,
                   "--track-offset-mm", str(o), "--unpaced", "-q", "--out", path)
            paths.append(path)
    return sorted(paths)


def import_sliding_study(binary, logs, out, keep=lambda surface, trial: True):
    """Imports the trials of a generated sliding study (`palpus gen --only multistream`) in
    folder `logs` that `keep(surface, trial)` accepts, each as one capture under `out`, with the
    options the set's README.md gives (so that this stays in step with it). Returns
    `(trial, capture path)` pairs, trials counted from 1."""
    readme = (Path(logs) / "README.md").read_text()

    def one(pattern):
        found = re.search(pattern, readme)
        if not found:
            raise SystemExit(f"the set's README.md has no {pattern}")
        return found.group(1)

    options = ["--kind", "rubbing", "--rate-hz", one(r"--rate-hz (\d+)"), "--repeated-time", "mean",
               "--unroll", one(r"--unroll '([^']+)'"), "--map", one(r"--map '([^']+)'")]
    Path(out).mkdir(parents=True, exist_ok=True)
    imported = []
    for force in sorted(Path(logs).glob("*_force.csv")):
        stem = force.name[: -len("_force.csv")]
        surface, trial = re.fullmatch(r"(mat\d+)_trial(\d+)", stem).groups()
        if not keep(surface, int(trial)):
            continue
        capture = Path(out) / f"{stem}.csv"
        streams = [str(Path(logs) / f"{stem}_{s}.csv") for s in ("force", "position", "velocity", "vibration")]
        palpus(binary, "import", *streams, *options, "--meta", f"surface={surface}",
               "--meta", f"trial={int(trial)}", "--out", str(capture))
        imported.append((int(trial), str(capture)))
    return imported


def sliding_study(binary, root, train_trials):
    """Generates the multi-stream sliding study under folder `root` (`palpus gen --only
    multistream`) and imports every trial ([`import_sliding_study`]): returns the captures of
    trials 1 to `train_trials`, and those of the rest."""
    palpus(binary, "gen", "--out", str(Path(root) / "logs"), "--only", "multistream", "-q")
    train, test = [], []
    for trial, capture in import_sliding_study(binary, Path(root) / "logs" / "multistream", Path(root) / "captures"):
        (train if trial <= train_trials else test).append(capture)
    return train, test

def sequential_table(runs, first, not_ending="trials not ending right", scores=False):
    """Prints one Markdown row per `(name, evaluation)` of `runs` and threshold, from `recognize
    eval --sequential --json`: windows named, named decisions right, the mean time to the stable
    right surface and the slowest surface's, strokes not ending named right (the column called
    `not_ending`), with `scores` flips per second and the posterior's Brier score, and its
    calibration error. `first` heads the column of names."""
    extra = " flips/s | Brier |" if scores else ""
    print()
    print(f"| {first} | threshold | windows named | named right | stable right (mean) | slowest surface "
          f"| {not_ending} |{extra} calibration error |")
    print("|---|---|---|---|---|---|---|" + ("---|---|" if scores else "") + "---|")
    for name, e in runs:
        for r in e["rows"]:
            worst = r["worst_surface"]
            stable = r["time_to_stable_correct_s"]
            cells = (f" {r['flips_per_s']:.3f} | {r['calibration']['brier']:.3f} |" if scores else "")
            print(f"| {name} | {r['threshold']:g} | {100 * r['decided'] / e['steps']:.1f} % "
                  f"| {100 * r['correct'] / max(r['decided'], 1):.1f} % "
                  f"| {'-' if stable is None else f'{stable:.2f} s'} "
                  f"| {f'{worst[1]:.2f} s ({worst[0]})' if worst else '-'} "
                  f"| {r['not_stable']} of {e['captures']} |{cells} {100 * r['calibration']['ece']:.1f} % |")


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
