#!/usr/bin/env python3
"""docs/recognition-anytime.md's table of anytime recognition when the tool rests on the surface mid-stroke, from one run.

Generates Nakano's surfaces (`palpus gen --only nakano`), trains the two SVMs of
`scripts/speed_table.py` on run 0 (0.25 s windows decided at their last sample: one over windows
of fixed time, one over travel), and copies runs 1-2 with the tool held still for `--pause-s`
from `--at-s` into the stroke (the sample there repeated, its velocities zero, the rest of the
stroke later by the pause). Evaluates both SVMs at threshold 0.9 on the strokes as rubbed and
as paused, and prints one Markdown row each: named decisions right, the calibration error, the
mean time to the stable right surface and the slowest surface's mean, strokes not ending named
right, and flips of the named surface per second.

A hand that holds a tool still still trembles: the last rows pause again with the resting tool's
tangential position swaying by `--tremor-um` micrometres at 9 Hz around where it stopped, read by
the capture's encoder (its `sensor.encoder_quantum_m`); everything else is held as without it.

    python3 scripts/pause_table.py [--palpus target/release/palpus] [--at-s 3] [--pause-s 2] [--tremor-um 30]
"""

import json
import math
import tempfile
from pathlib import Path

from palpus_cli import palpus, parser as cli_parser
from speed_table import OVER_TRAVEL


TREMOR_HZ = 9.0


def paused(src, dst, at_s, pause_s, tremor_m=0.0):
    """Writes `src` (a capture) to `dst` with the tool at rest for `pause_s` from `at_s`, its
    tangential position swaying by `tremor_m` at `TREMOR_HZ` through the capture's encoder."""
    lines = Path(src).read_text().splitlines()
    header = [l for l in lines if l.startswith("#")]
    body = [l for l in lines if not l.startswith("#")]
    names, rows = body[0].split(","), [r.split(",") for r in body[1:]]
    rate_hz = float(next(w for l in header for w in l.split() if w.startswith("rate_hz=")).split("=")[1])
    at = next(i for i, r in enumerate(rows) if float(r[0]) >= at_s)
    time_digits = max(len(r[0].split(".")[1]) if "." in r[0] else 0 for r in rows)
    t = lambda v: f"{v:.{time_digits}f}"
    quantum = float(next(w for l in header for w in l.split()
                         if w.startswith("sensor.encoder_quantum_m=")).split("=")[1])
    x = names.index("tangential_position_m")
    still = []
    for k in range(1, round(pause_s * rate_hz) + 1):
        r = list(rows[at])
        r[0] = t(float(rows[at][0]) + k / rate_hz)
        for i, n in enumerate(names):
            if n.endswith("_velocity_mps"):
                r[i] = "0.0"
        if tremor_m > 0.0:
            sway = tremor_m * math.sin(2.0 * math.pi * TREMOR_HZ * k / rate_hz)
            r[x] = repr(round((float(rows[at][x]) + sway) / quantum) * quantum)
        still.append(r)
    later = [[t(float(r[0]) + pause_s), *r[1:]] for r in rows[at + 1:]]
    out = header + [body[0]] + [",".join(r) for r in rows[: at + 1] + still + later]
    Path(dst).write_text("\n".join(out) + "\n")


def main():
    parser = cli_parser(__doc__)
    parser.add_argument("--at-s", type=float, default=3.0)
    parser.add_argument("--pause-s", type=float, default=2.0)
    parser.add_argument("--tremor-um", type=float, default=30.0)
    args = parser.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        root = Path(tmp)
        palpus(args.palpus, "gen", "--out", str(root / "protocol"), "--only", "nakano", "-q")
        captures = sorted((root / "protocol" / "nakano").glob("*.csv"))
        train = [str(p) for p in captures if p.stem.endswith("run0")]
        test = [p for p in captures if not p.stem.endswith("run0")]
        pause = f"at rest {args.pause_s:g} s from {args.at_s:g} s"
        variants = [("as rubbed", [str(p) for p in test])]
        for label, tremor_m in [(pause, 0.0), (f"{pause}, {args.tremor_um:g} µm tremor", 1e-6 * args.tremor_um)]:
            out = root / f"paused_{len(variants)}"
            out.mkdir()
            for p in test:
                paused(p, out / p.name, args.at_s, args.pause_s, tremor_m)
            variants.append((label, [str(out / p.name) for p in test]))
        print("| windows | strokes | named right | calibration error | stable right (mean) | slowest surface "
              "| strokes not ending right | flips/s |")
        print("|---|---|---|---|---|---|---|---|")
        for name, label, extra in [("time", "fixed time", []), ("travel", "over travel", OVER_TRAVEL)]:
            model = str(root / f"{name}.json")
            palpus(args.palpus, "recognize", "train", *train, "--method", "svm", "--features", "nakano",
                   "--window-s", "0.25", "--mirrored-end", *extra, "--out", model)
            for strokes, files in variants:
                e = json.loads(palpus(args.palpus, "recognize", "eval", model, *files,
                                      "--sequential", "0.9", "--json"))
                s = e["rows"][0]
                worst = s["worst_surface"]
                secs = lambda v: "-" if v is None else f"{v:.2f} s"
                print(f"| {label} | {strokes} | {100 * s['correct'] / s['decided']:.1f} % "
                      f"| {100 * s['calibration']['ece']:.1f} % | {secs(s['time_to_stable_correct_s'])} "
                      f"| {secs(worst[1] if worst else None)} ({worst[0] if worst else '-'}) "
                      f"| {s['not_stable']} of {len(files)} | {s['flips_per_s']:.3f} |")


if __name__ == "__main__":
    main()
