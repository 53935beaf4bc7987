"""What the table scripts share: running `palpus` and their common `--palpus` option."""

import argparse
import re
import subprocess
from pathlib import Path


def palpus(binary, *args):
    """Runs `binary` with `args` (failing on a non-zero exit) and returns its stdout."""
    out = subprocess.run([binary, *args], check=True, capture_output=True, text=True)
    return out.stdout


def parser(doc):
    """An argument parser described by `doc`'s first line, with `--palpus` (the binary)."""
    p = argparse.ArgumentParser(description=doc.splitlines()[0])
    p.add_argument("--palpus", default="target/release/palpus")
    return p


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
