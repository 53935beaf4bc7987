"""Runs a needle scene's scripted trainee at several stopping depths, each attempt scored against the scene's goal and stored in a fresh history, and prints the Markdown table of docs/training.md; then `palpus history` draws their learning curve into out/training/SCENE_learning_curve.png.

    python3 scripts/training_table.py                    # the liver (the default scene)
    python3 scripts/training_table.py --scene epidural_lumbar
"""

import json
import tempfile
from pathlib import Path

from palpus_cli import palpus, parser

# Per scene: (hand stops at, extra --set values) for each attempt.
ATTEMPTS = {
    "needle_liver": [
        ("0.030", []),
        ("0.028", []),
        ("0.026", []),
        ("0.026", ["task.goal.max_force_n=1.5"]),
        ("0.024", []),
    ],
    "epidural_lumbar": [
        ("0.042", []),
        ("0.043", []),
        ("0.044", []),
        ("0.045", []),
        ("0.046", []),
        ("0.048", []),
        ("0.052", []),
    ],
}


def main():
    p = parser(__doc__)
    p.add_argument("--scene", default="needle_liver", choices=sorted(ATTEMPTS))
    args = p.parse_args()
    scene = Path(__file__).resolve().parent.parent / "scenes" / f"{args.scene}.toml"
    with tempfile.TemporaryDirectory() as tmp:
        history = Path(tmp) / "history.sqlite"
        print("| attempt | hand stops at | result | why | overshoot | peak force | time to target | SPARC |")
        print("|---|---|---|---|---|---|---|---|")
        for n, (depth, extra) in enumerate(ATTEMPTS[args.scene], 1):
            report = Path(tmp) / f"report{n}"
            sets = [a for s in [f"task.depth_m={depth}", *extra] for a in ("--set", s)]
            palpus(args.palpus, "run", str(scene), "--headless", "--unpaced", "--trainee", "ana", "--history",
                   str(history), *sets, "--report", str(report))
            s = json.loads((report / "report.json").read_text())["score"]
            over = "—" if s["overshoot_m"] is None else f"{s['overshoot_m'] * 1e3:.1f} mm"
            to_target = "—" if s["time_to_target_s"] is None else f"{s['time_to_target_s']:.2f} s"
            sparc = "—" if s["smoothness_sparc"] is None else f"{s['smoothness_sparc']:.2f}"
            limit = f" (limit {extra[0].split('=')[1]} N)" if extra else ""
            print(f"| {n} | {float(depth) * 1e3:.0f} mm{limit} | {'passed' if s['passed'] else 'failed'} | "
                  f"{s['verdict']} | {over} | {s['peak_force_n']:.2f} N | {to_target} | {sparc} |")
        Path("out/training").mkdir(parents=True, exist_ok=True)
        palpus(args.palpus, "history", "--history", str(history), "--plot",
               f"out/training/{args.scene}_learning_curve.png")


if __name__ == "__main__":
    main()
