#!/usr/bin/env python3
"""docs/needle.md's table of the needle models on records shaped like real rigs', from one run.

For every record of assets/captures/needle_corpus (made by scripts/needle_corpus.py), runs
`palpus identify --model needle-phases --json` on its training recording with its held-out one
as --test, and prints one Markdown row: the held-out AISE of the phase model, the smooth ε-SVR,
F = Fc·sgn(v) + c·v + k·depth (or why it was not fitted), the RBF network and the mean force;
how many of the tissue's ruptures (the recording's metadata) the model renders within 1 mm
and 10 % of the tissue's peak; the outliers left out; and the warnings. A record the model
refuses gets its reason instead. The foreign log is imported first, as a user would.

    python3 scripts/needle_corpus_table.py [--palpus target/release/palpus]
"""

import json
import subprocess
import tempfile
from pathlib import Path

from palpus_cli import palpus, parser as cli_parser

CORPUS = Path(__file__).resolve().parent.parent / "assets" / "captures" / "needle_corpus"


def meta(path):
    with open(path) as f:
        return dict(t.split("=", 1) for t in f.readline().split() if "=" in t)


def truth(m):
    """Every (depth m, peak N) the tissue ruptured at, all insertions together."""
    out = []
    for k in range(int(m["insertions"])):
        depths = m.get(f"truth.insertion.{k}.puncture_depths_m", "none")
        peaks = m.get(f"truth.insertion.{k}.puncture_peaks_n", "none")
        if depths != "none":
            out += list(zip(map(float, depths.split(";")), map(float, peaks.split(";"))))
    return out


def found(report, ruptures):
    """How many of `ruptures` the model renders within 1 mm and 10 % of the peak."""
    hits = 0
    for depth, peak in ruptures:
        for p in report["punctures"]:
            d, f = p.get("predicted_depth_m"), p.get("predicted_peak_force_n")
            if d is not None and abs(d - depth) < 1e-3 and abs(f / peak - 1) < 0.10:
                hits += 1
                break
    return hits


def aise(m):
    return "—" if m is None else f"{m['aise']:.2e}"


def main():
    args = cli_parser(__doc__).parse_args()
    tmp = Path(tempfile.mkdtemp(prefix="needle-corpus-"))
    manifest = [line.split(",") for line in (CORPUS / "MANIFEST.csv").read_text().splitlines()[1:]]
    records = []
    for row in manifest:
        if row[1] not in records:
            records.append(row[1])
    print("| record | phases | smooth ε-SVR | Fc·sgn(v)+c·v+k·d | RBF network | mean force "
          "| ruptures within 1 mm and 10 % | outliers left out | what the report says |")
    print("|---|---|---|---|---|---|---|---|---|")
    for record in records:
        if record == "foreign":
            spec = json.loads((CORPUS / "foreign_units.truth.json").read_text())
            train = tmp / "foreign.csv"
            palpus(args.palpus, "import", str(CORPUS / "foreign_units.csv"), "--kind", "insertion",
                   "--map", spec["import_map"], "--rate-hz", str(spec["rate_hz"]), "--out", str(train))
            test, evaluated = None, "train"
            ruptures = [(d, f) for i in spec["insertions"]
                        for d, f in zip(i["puncture_depths_m"], i["puncture_peaks_n"])]
        else:
            train, test = CORPUS / f"{record}_train.csv", CORPUS / f"{record}_test.csv"
            evaluated = "test"
            ruptures = truth(meta(test))
        command = [args.palpus, "identify", str(train), "--model", "needle-phases", "--json"]
        if test is not None:
            command += ["--test", str(test)]
        out = subprocess.run(command, capture_output=True, text=True)
        if out.returncode != 0:
            # The last line names the capture, then says why.
            reason = out.stderr.strip().splitlines()[-1].split(".csv: ", 1)[-1]
            print(f"| {record} | refused | | | | | | | {reason} |")
            continue
        r = json.loads(out.stdout)
        m = r["metrics"]
        law = aise(m["coulomb_viscous_stiffness"])
        if m["coulomb_viscous_stiffness"] is None:
            law = "— (" + next(b["reason"] for b in r["baselines_not_fitted"]
                               if b["baseline"] == "coulomb_viscous_stiffness").split(":")[-1].strip() + ")"
        outliers = sum(len(s["rows"]) for s in r.get("outliers", []))
        notes = []
        if any("withdrawal law not measured" in w for w in r["warnings"]):
            notes.append("withdrawal not measured")
        one_speed = sum("measured at one speed" in w for w in r["warnings"])
        if one_speed:
            notes.append(f"{one_speed} of {r['n_layers']} thresholds at one speed")
        notes = "; ".join(notes)
        print(f"| {record} ({evaluated}) | {aise(m['svr'])} | {aise(m.get('smooth_svr'))} | {law} "
              f"| {aise(m['rbf_network'])} | {aise(m['mean'])} | {found(r, ruptures)} of {len(ruptures)} "
              f"| {outliers} | {notes} |")


if __name__ == "__main__":
    main()
