"""What the table scripts share: running `palpus` and their common `--palpus` option."""

import argparse
import subprocess


def palpus(binary, *args):
    """Runs `binary` with `args` (failing on a non-zero exit) and returns its stdout."""
    out = subprocess.run([binary, *args], check=True, capture_output=True, text=True)
    return out.stdout


def parser(doc):
    """An argument parser described by `doc`'s first line, with `--palpus` (the binary)."""
    p = argparse.ArgumentParser(description=doc.splitlines()[0])
    p.add_argument("--palpus", default="target/release/palpus")
    return p
