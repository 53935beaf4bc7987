"""Edits every field of a recognizer file and runs the readers on each edit: prints the edits that `palpus run` starts a session from while `recognize eval` (or `eval --sequential`) refuses them.

Each number is set to 0, its negative, ×10, ÷10, ×1000, ÷1000, ±1e300, 1e-300, ±1 and 1; each
boolean flipped; each string emptied; each list shortened or emptied; each key removed. The
evaluation captures are rubbed through the simulated device on a track no recognizer was
trained on, as the scene header says. A refusal by `eval` whose reason is the captures
("no decisions to evaluate …", a surface the recognizer does not know) is printed too: it is
the captures' fault, not a second rule.

    python3 scripts/recognizer_readers.py assets/models/nakano_svm.json --method svm
"""

import copy
import json
import subprocess
import tempfile
from pathlib import Path

from palpus_cli import SCENE, parser, scene_captures, scene_training


def leaves(x, path=()):
    """Every key and the first item of every list (the others are alike), with its path."""
    if isinstance(x, dict):
        for k, v in x.items():
            yield path + (k,), v
            yield from leaves(v, path + (k,))
    elif isinstance(x, list) and x:
        yield path + (0,), x[0]
        if isinstance(x[0], (dict, list)):
            yield from leaves(x[0], path + (0,))


def edits(v):
    if isinstance(v, bool):
        return [not v, None]
    if isinstance(v, (int, float)):
        out = [0, -v, v * 10, v / 10, v * 1000, v / 1000, 1e300, -1e300, 1e-300, v + 1, v - 1, 1]
        return [int(o) if isinstance(v, int) and abs(o) < 1e18 else o for o in out]
    if isinstance(v, str):
        return ["", "x", None]
    if isinstance(v, list):
        return ["shorter", "empty", None]
    return [None]


def edited(base, path, e):
    d = copy.deepcopy(base)
    parent = d
    for k in path[:-1]:
        parent = parent[k]
    key, value = path[-1], parent[path[-1]]
    if e is None:
        if not isinstance(parent, dict):
            return None
        del parent[key]
    elif e == "shorter" and isinstance(value, list):
        parent[key] = value[:-1]
    elif e == "empty" and isinstance(value, list):
        parent[key] = []
    else:
        parent[key] = e
    return d


def main():
    p = parser(__doc__)
    p.add_argument("model")
    p.add_argument("--method", required=True, help="the scene's recognizer.method for this file")
    args = p.parse_args()
    binary = str(Path(args.palpus).resolve())
    base = json.loads(Path(args.model).read_text())
    with tempfile.TemporaryDirectory() as tmp:
        tmp = Path(tmp)
        surfaces, _ = scene_training()
        captures = scene_captures(binary, surfaces, (200,), tmp / "captures")
        model = tmp / "model.json"
        text = SCENE.read_text().replace("../assets", str(SCENE.parent.parent / "assets"))
        text = text.replace('method = "svm"', f'method = "{args.method}"')
        text = "\n".join(f'file = "{model}"' if line.startswith("file = ") else line for line in text.splitlines())
        scene = tmp / "scene.toml"
        scene.write_text(text)
        tried = found = 0
        for path, value in list(leaves(base)):
            for e in edits(value):
                d = edited(base, path, e)
                if d is None:
                    continue
                tried += 1
                model.write_text(json.dumps(d))
                run = lambda *a: subprocess.run([binary, *a], capture_output=True, text=True)
                plain = run("recognize", "eval", str(model), *captures)
                sequential = run("recognize", "eval", str(model), *captures, "--sequential", "0.9") \
                    if args.method != "som" else plain
                refused = next((r for r in (plain, sequential) if r.returncode != 0), None)
                if refused is None:
                    continue
                session = run("run", str(scene), "--headless", "--unpaced", "--duration", "0.3",
                              "--report", str(tmp / "report"))
                if session.returncode == 0:
                    found += 1
                    reason = (refused.stderr.strip().splitlines() or [""])[-1][:160]
                    print(f"{'.'.join(map(str, path))} = {e!r}: run accepts, eval refuses: {reason}", flush=True)
        print(f"{tried} edits, {found} accepted by run and refused by eval")


if __name__ == "__main__":
    main()
