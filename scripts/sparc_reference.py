"""Computes the spectral arc length (SPARC) of three speed profiles with the published reference implementation, and writes them as the fixture tests/fixtures/score/sparc.json.

The function below is Balasubramanian, Melendez-Calderon, Roby-Brami & Burdet, "On the analysis
of movement smoothness", J. NeuroEng. Rehabil. 12:112 (2015), as published with the paper
(padlevel 4, cutoff 10 Hz, amplitude threshold 0.05). The profiles are defined by formula, so
the Rust test builds the same samples:

- `minimum_jerk`: one minimum-jerk reach of 1 s, 30·τ²(1 − τ)², at 1 kHz;
- `two_submovements`: two such reaches of 0.6 s, the second starting 0.5 s after the first;
- `tremor`: the reach plus 0.1·sin(2π·7 t), a 7 Hz tremor.

    python3 scripts/sparc_reference.py
"""

import json
from pathlib import Path

import numpy as np


def sparc(movement, fs, padlevel=4, fc=10.0, amp_th=0.05):
    nfft = int(pow(2, np.ceil(np.log2(len(movement))) + padlevel))
    f = np.arange(0, fs, fs / nfft)
    Mf = abs(np.fft.fft(movement, nfft))
    Mf = Mf / max(Mf)
    fc_inx = ((f <= fc) * 1).nonzero()
    f_sel = f[fc_inx]
    Mf_sel = Mf[fc_inx]
    inx = ((Mf_sel >= amp_th) * 1).nonzero()[0]
    fc_inx = range(inx[0], inx[-1] + 1)
    f_sel = f_sel[fc_inx]
    Mf_sel = Mf_sel[fc_inx]
    return -sum(np.sqrt(pow(np.diff(f_sel) / (f_sel[-1] - f_sel[0]), 2) + pow(np.diff(Mf_sel), 2)))


def reach(t, start, duration):
    tau = np.clip((t - start) / duration, 0.0, 1.0)
    return 30.0 * tau**2 * (1.0 - tau) ** 2


def main():
    fs = 1000.0
    t = np.arange(1000) / fs
    t2 = np.arange(1100) / fs
    profiles = {
        "minimum_jerk": reach(t, 0.0, 1.0),
        "two_submovements": reach(t2, 0.0, 0.6) + reach(t2, 0.5, 0.6),
        "tremor": reach(t, 0.0, 1.0) + 0.1 * np.sin(2 * np.pi * 7.0 * t),
    }
    out = {name: {"samples": len(v), "rate_hz": fs, "sparc": float(sparc(v, fs))} for name, v in profiles.items()}
    path = Path(__file__).resolve().parent.parent / "tests" / "fixtures" / "score" / "sparc.json"
    path.write_text(json.dumps(out, indent=2) + "\n")
    for name, v in out.items():
        print(f"{name}: {v['sparc']:.6f}")


if __name__ == "__main__":
    main()
