#!/usr/bin/env python3
"""Writes assets/captures/needle_corpus/: needle-insertion recordings shaped like real rigs' logs.

An independent tissue simulator, written apart from palpus's own needle world, so that
identifying a puncture model on these files tests the identification and not a simulator
agreeing with itself. Every record has its known truth (the depths where the tip ruptured a
membrane and the force the sensor read at each rupture's peak) on the metadata line.

    python3 scripts/needle_corpus.py [--out assets/captures/needle_corpus]

Needs numpy. Each file has its own fixed seed (`numpy.random.default_rng(seed)`), so a rerun
writes byte-identical files.

Tissue model
------------
The tissue is a stack of regions from the surface down. Region k has a cutting force `cut_n`
(the tip cutting uncut tissue while advancing, with a spatial texture of a few per cent and,
at the surface, an engagement length over which it builds up as the bevel enters), a
Coulomb-like shaft friction `fric_npm` per metre of needle inside it and a viscous part
`visc_nspm2` (N*s/m^2, times that length and the velocity). A membrane may sit at the top of
a region (contact depth c). While the tip presses it, the membrane adds `a1*u + a2*u^2`
(u = tip depth - c) and the cutting of the region above stops (faded over 0.2 mm); it gives
way when that added force reaches `P(v) = P0*(1 + 0.15*ln(v/v_ref))` (clipped to 0.6..1.4 P0).
Its force then falls exponentially to zero over ~0.15 mm of further travel (length 0.05 mm)
and the tip cuts the region below. A membrane opening into a lumen (cut ~0, tiny friction)
leaves the force below where it was before the membrane was reached.

Shaft friction acts over the channel actually cut, `[0, min(tip, deepest cut)]`, split by
region. Its Coulomb part follows the direction of motion through a presliding state that
reverses over 0.05 mm of travel, so withdrawal friction is negative; while the needle is
held it relaxes toward 30 % of its value with a 1 s time constant, and so does the force on
the tip. Withdrawing, the tip leaves its cavity and its force decays over 0.05 mm; membranes
already cut stay cut. Each insertion of a file goes into a fresh site of the same tissue:
the layers shift together by ~0.15 mm, each membrane by ~0.03 mm more, and P0, cutting and
friction vary by ~3 %.

Rigs
----
The physics runs at 5 kHz along trapezoidal strokes (20 ms acceleration ramps) starting 2 mm
above the surface. A rig optionally low-passes the force (first order, 30 Hz), samples it
at its rate, adds white noise and quantises it to its LSB; depth comes from an encoder
quantised to 1 um (0.5 um on the phantom rig) and velocity, where logged, from the encoder by
a backward difference over 8 ms plus a little noise. Truth peaks are the noiseless sensor
reading (filter, averaging and drift included, noise and quantisation not) at the written
row where the force peaks; truth depths are the tip's depth at the rupture itself.

Records (`<record>_train.csv` and `<record>_test.csv`, the test one a later recording of
the same tissue on the same rig, from another seed: for the records of several insertions,
the next single insertion at a speed within the training ones; MANIFEST.csv lists them):
- one_speed: liver, one 3 mm/s insertion to 40 mm ending at the bottom, 1 kHz averaged down
  to 200 Hz; capsule, a vessel wall opening into its lumen and the far wall.
- digitized: an epidural-route curve traced from a figure: ~370 irregular points, denser
  where it bends, force to 0.01 N, depth jittered, time from depth at 3 mm/s, two or three
  one-point slips; four punctures, two of them 2.5-2.8 mm apart.
- close_layers: abdominal wall, 2/5/8 mm/s to 30 mm with hold and withdrawal at 500 Hz;
  two fasciae ~2.2 mm apart and the peritoneum.
- lumen: heart-wall phantom, 4 and 8 mm/s, 1 kHz; a wall opening into a fluid lumen.
- outliers: close_layers' rig with a 50 N and a 1000 N sample, a 0.04 N offset drift and
  three dropouts (rows missing); `outliers.rows` gives the gross outliers' row indices.
- gel: a homogeneous gel, no membrane (nothing to identify a puncture from: expect=refuse).
- tiny: 12 rows of a truncated log (expect=refuse).
- foreign_units.csv: one_speed's rig written as a foreign log (ms, mm, mN, `;`), with its
  truth in foreign_units.truth.json.
"""

import argparse
import json
import math
from pathlib import Path

import numpy as np

SIM_HZ = 5000
RAMP_S = 0.02
START_DEPTH_M = -0.002
# Membrane force after rupture: exp(-travel/0.05 mm), so ~5 % is left after 0.15 mm.
RUPTURE_LENGTH_M = 0.05e-3
# The cut of the region above fades as the tip starts pressing the membrane instead.
CONTACT_FADE_M = 0.2e-3
PRESLIDE_M = 0.05e-3
TIP_RELEASE_M = 0.05e-3
HOLD_TAU_S = 1.0
HOLD_FLOOR = 0.3
RATE_SOFTENING = 0.15
V_REF_MPS = 0.005


# --------------------------------------------------------------------------- tissues
def region(name, top_mm, cut_n, fric_npm, visc_nspm2, engage_mm=0.0, texture=0.0, membrane=None):
    return dict(name=name, top=top_mm * 1e-3, cut=cut_n, fric=fric_npm, visc=visc_nspm2,
                engage=engage_mm * 1e-3, texture=texture, membrane=membrane)


def membrane(name, a1, a2, p0):
    return dict(name=name, a1=a1, a2=a2, p0=p0)


TISSUES = {
    # The capsule sits 1 mm below the rig's zero (a wet film above it); the vessel's lumen
    # is softer than the parenchyma around it.
    "bovine_liver": [
        region("film", 0.0, 0.02, 2.0, 50.0, engage_mm=0.3),
        region("parenchyma", 1.0, 0.25, 12.0, 300.0, texture=0.08,
               membrane=membrane("capsule", 40.0, 25000.0, 1.45)),
        region("vessel_lumen", 22.0, 0.01, 0.5, 10.0,
               membrane=membrane("vessel_wall", 80.0, 300000.0, 0.6)),
        region("deep_parenchyma", 26.0, 0.25, 12.0, 300.0, texture=0.08,
               membrane=membrane("far_wall", 60.0, 250000.0, 0.7)),
    ],
    # Midline lumbar route: supraspinous and interspinous ligaments close together, the
    # ligamentum flavum giving into the epidural space (loss of resistance), then the dura.
    "porcine_lumbar_back": [
        region("subcutis", 0.0, 0.35, 14.0, 300.0, engage_mm=1.5, texture=0.06),
        region("ligament", 14.0, 0.3, 24.0, 400.0, texture=0.08,
               membrane=membrane("supraspinous", 120.0, 500000.0, 1.0)),
        region("interspinous_ligament", 16.75, 0.35, 26.0, 400.0, texture=0.08,
               membrane=membrane("interspinous", 150.0, 600000.0, 1.1)),
        region("epidural_space", 25.5, 0.05, 3.0, 60.0,
               membrane=membrane("flavum", 300.0, 900000.0, 2.2)),
        region("csf", 33.6, 0.01, 0.5, 10.0,
               membrane=membrane("dura", 100.0, 400000.0, 0.55)),
    ],
    "porcine_abdominal_wall": [
        region("subcutis", 0.0, 0.2, 10.0, 250.0, engage_mm=1.0, texture=0.06),
        region("rectus_muscle", 10.0, 0.3, 15.0, 350.0, texture=0.08,
               membrane=membrane("anterior_fascia", 150.0, 700000.0, 0.9)),
        region("preperitoneal_fat", 12.1, 0.25, 12.0, 300.0, texture=0.06,
               membrane=membrane("posterior_fascia", 100.0, 550000.0, 0.8)),
        region("organ", 20.0, 0.3, 18.0, 400.0, texture=0.08,
               membrane=membrane("peritoneum", 60.0, 150000.0, 1.2)),
    ],
    # Chosen so that at 4 mm/s the force is ~0.9 N before the wall, ~1.6 N at its peak and
    # ~0.3 N in the lumen; the far wall opens into a stiffer septum.
    "heart_wall_phantom": [
        region("myocardium_gel", 0.0, 0.62, 20.0, 600.0, engage_mm=1.5, texture=0.05),
        region("lumen", 12.0, 0.01, 0.5, 10.0,
               membrane=membrane("near_wall", 200.0, 400000.0, 1.3)),
        region("septum", 24.0, 0.9, 35.0, 700.0, texture=0.05,
               membrane=membrane("far_wall", 150.0, 500000.0, 1.4)),
    ],
    "ovine_abdominal_wall": [
        region("subcutis", 0.0, 0.2, 10.0, 250.0, engage_mm=1.0, texture=0.06),
        region("muscle", 8.0, 0.3, 15.0, 350.0, texture=0.08,
               membrane=membrane("fascia", 120.0, 500000.0, 0.9)),
        region("organ", 16.0, 0.3, 18.0, 400.0, texture=0.08,
               membrane=membrane("peritoneum", 80.0, 200000.0, 1.1)),
    ],
    # Elastic build-up over the first 4 mm, then steady cutting and growing friction.
    "gelatin_10pct": [
        region("gel", 0.0, 0.35, 18.0, 400.0, engage_mm=4.0, texture=0.01),
    ],
}


def membranes_of(tissue):
    return [(r["membrane"], r["top"]) for r in TISSUES[tissue] if r["membrane"]]


def rupture_factor(v):
    return min(1.4, max(0.6, 1.0 + RATE_SOFTENING * math.log(max(v, 1e-5) / V_REF_MPS)))


def deflection_at_rupture(m, p):
    if m["a2"] > 0:
        return (-m["a1"] + math.sqrt(m["a1"] ** 2 + 4.0 * m["a2"] * p)) / (2.0 * m["a2"])
    return p / m["a1"]


def smooth_field(rng, length_m=0.08, step_m=0.05e-3, corr_m=0.4e-3):
    """Unit-variance random profile along depth (tissue inhomogeneity under the tip)."""
    n = int(length_m / step_m) + 1
    white = rng.standard_normal(n + 200)
    half = int(4 * corr_m / step_m)
    k = np.exp(-0.5 * (np.arange(-half, half + 1) * step_m / corr_m) ** 2)
    field = np.convolve(white, k / k.sum(), mode="same")[100:100 + n]
    return field / field.std()


def realise_site(tissue, rng):
    """One insertion site: the nominal tissue with this site's small variations."""
    shift = float(np.clip(rng.normal(0.0, 0.15e-3), -0.3e-3, 0.3e-3))
    regions = []
    for i, r in enumerate(TISSUES[tissue]):
        site = dict(r)
        if i > 0:
            own = float(np.clip(rng.normal(0.0, 0.03e-3), -0.06e-3, 0.06e-3))
            site["top"] = r["top"] + shift + own
        for key in ("cut", "fric"):
            site[key] = r[key] * float(1.0 + np.clip(rng.normal(0.0, 0.03), -0.06, 0.06))
        if r["membrane"]:
            m = dict(r["membrane"])
            m["p0"] *= float(1.0 + np.clip(rng.normal(0.0, 0.03), -0.06, 0.06))
            site["membrane"] = m
        site["field"] = smooth_field(rng)
        regions.append(site)
    return regions


# --------------------------------------------------------------------------- strokes
def stroke(x0, x1, speed):
    """Trapezoidal move from x0 to x1: (duration, x(tau), v(tau))."""
    d = x1 - x0
    sign = 1.0 if d > 0 else -1.0
    dist = abs(d)
    accel = speed / RAMP_S
    duration = dist / speed + RAMP_S

    def pos(tau):
        tau = np.clip(tau, 0.0, duration)
        up = np.minimum(tau, RAMP_S)
        down = np.clip(tau - (duration - RAMP_S), 0.0, RAMP_S)
        s = 0.5 * accel * up ** 2 + speed * np.clip(tau - RAMP_S, 0.0, duration - 2 * RAMP_S)
        s = s + speed * down - 0.5 * accel * down ** 2
        return x0 + sign * s

    def vel(tau):
        return sign * np.minimum(np.minimum(tau, duration - tau) * accel, speed).clip(0.0)

    return duration, pos, vel


def rest(x, duration):
    return duration, (lambda tau: np.full_like(tau, x)), (lambda tau: np.zeros_like(tau))


def timeline(insertions, target_m, hold_s=0.5, withdraw_mps=0.01, rest_s=0.2, end_at_bottom=False):
    """Samples at SIM_HZ: (t, x, v, site index, phase) for a list of insertion speeds."""
    segments = []
    for k, speed in enumerate(insertions):
        segments.append((k, "rest", rest(START_DEPTH_M, rest_s)))
        segments.append((k, "insert", stroke(START_DEPTH_M, target_m, speed)))
        if end_at_bottom:
            segments.append((k, "hold", rest(target_m, 0.02)))
            continue
        segments.append((k, "hold", rest(target_m, hold_s)))
        segments.append((k, "withdraw", stroke(target_m, START_DEPTH_M, withdraw_mps)))
    if not end_at_bottom:
        segments.append((len(insertions) - 1, "rest", rest(START_DEPTH_M, rest_s)))
    xs, vs, ks, phases = [], [], [], []
    for k, phase, (duration, pos, vel) in segments:
        n = int(round(duration * SIM_HZ))
        tau = np.arange(n) / SIM_HZ
        xs.append(pos(tau))
        vs.append(vel(tau))
        ks.append(np.full(n, k))
        phases.append(np.full(n, {"rest": 0, "insert": 1, "hold": 2, "withdraw": 3}[phase]))
    x = np.concatenate(xs)
    v = np.concatenate(vs)
    t = np.arange(len(x)) / SIM_HZ
    return t, x, v, np.concatenate(ks), np.concatenate(phases)


# --------------------------------------------------------------------------- physics
class Needle:
    """Force on a needle moving through one site; `step` is called once per sample."""

    def __init__(self, regions):
        self.r = regions
        self.tops = [r["top"] for r in regions] + [math.inf]
        self.deepest = 0.0
        self.next_m = 1  # index of the next region whose membrane is intact
        self.s = 0.0
        self.tip = 0.0
        self.x_ref = START_DEPTH_M
        self.x_prev = START_DEPTH_M
        self.hold_t = 0.0
        self.hold_s0 = 0.0
        self.hold_tip0 = 0.0
        self.rupture = None  # (depth, force) of the latest rupture
        self.events = []  # (sample, depth, region index)
        self.contact_depths = [r["top"] for r in regions if r["membrane"]]
        while self.next_m < len(regions) and not regions[self.next_m]["membrane"]:
            self.next_m += 1

    def region_at(self, x):
        k = 0
        while x >= self.tops[k + 1]:
            k += 1
        return k

    def cut(self, x):
        k = self.region_at(x)
        r = self.r[k]
        into = x - r["top"]
        cell = min(int(max(x, 0.0) / 0.05e-3), len(r["field"]) - 1)
        f = r["cut"] * (1.0 + r["texture"] * r["field"][cell])
        if r["engage"] > 0:
            f *= 1.0 - math.exp(-into / r["engage"])
        return f

    def step(self, i, x, v, dt):
        dx = x - self.x_prev
        self.x_prev = x
        if dx != 0.0:
            self.s += ((1.0 if dx > 0 else -1.0) - self.s) * (1.0 - math.exp(-abs(dx) / PRESLIDE_M))
        if v > 0.0:
            self.hold_t = 0.0
            tip = self.advance(i, x, v)
            self.tip = tip
            self.x_ref = x
        elif v == 0.0:
            if self.hold_t == 0.0:
                self.hold_s0, self.hold_tip0 = self.s, self.tip
            self.hold_t += dt
            relax = HOLD_FLOOR + (1.0 - HOLD_FLOOR) * math.exp(-self.hold_t / HOLD_TAU_S)
            self.s = self.hold_s0 * relax
            tip = self.tip = self.hold_tip0 * relax
            self.x_ref = x
        else:
            self.hold_t = 0.0
            tip = self.tip = self.tip * math.exp(-max(0.0, self.x_ref - x) / TIP_RELEASE_M)
            self.x_ref = min(self.x_ref, x)
        inside = min(x, self.deepest)
        friction = 0.0
        if inside > 0.0:
            for k, r in enumerate(self.r):
                length = min(inside, self.tops[k + 1]) - r["top"]
                if length <= 0.0:
                    break
                friction += length * (r["fric"] * self.s + r["visc"] * v)
        return tip + friction

    def advance(self, i, x, v):
        residual = 0.0
        if self.rupture:
            depth, force = self.rupture
            residual = force * math.exp(-(max(self.deepest, x) - depth) / RUPTURE_LENGTH_M)
        if self.next_m < len(self.r) and x >= self.r[self.next_m]["top"]:
            reg = self.r[self.next_m]
            m = reg["membrane"]
            c = reg["top"]
            above = self.cut(min(self.deepest, c - 1e-9)) if self.deepest > 0 else 0.0
            self.deepest = max(self.deepest, c)
            u = x - c
            p = m["p0"] * rupture_factor(v)
            load = m["a1"] * u + m["a2"] * u * u
            if load < p:
                return residual + above * math.exp(-u / CONTACT_FADE_M) + load
            depth = c + deflection_at_rupture(m, p)
            self.events.append((i, depth, self.next_m))
            self.rupture = (depth, p)
            self.deepest = depth
            self.next_m += 1
            while self.next_m < len(self.r) and not self.r[self.next_m]["membrane"]:
                self.next_m += 1
            residual = p * math.exp(-(x - depth) / RUPTURE_LENGTH_M)
        if x > self.deepest:
            self.deepest = x
        if x > 0.0 and x >= self.deepest:
            # The tip takes up the next region's cutting as the membrane lets go of it, so the
            # force at the rupture is the membrane's, not the membrane's plus a cut.
            held = residual / self.rupture[1] if self.rupture and self.rupture[1] > 0.0 else 0.0
            return residual + self.cut(x) * (1.0 - held)
        return residual


def simulate(tissue, insertions, target_m, rng, **kw):
    """Physical force along a timeline, one fresh site per insertion."""
    t, x, v, k, phase = timeline(insertions, target_m, **kw)
    sites = [realise_site(tissue, rng) for _ in insertions]
    force = np.zeros(len(t))
    needles = []
    dt = 1.0 / SIM_HZ
    current = -1
    for i in range(len(t)):
        if k[i] != current:
            current = k[i]
            needles.append(Needle(sites[current]))
        force[i] = needles[current].step(i, float(x[i]), float(v[i]), dt)
    events = [[(i, d, needles[j].r[reg]["membrane"]["name"]) for i, d, reg in needles[j].events]
              for j in range(len(needles))]
    contacts = [needle.contact_depths for needle in needles]
    return dict(t=t, x=x, v=v, k=k, phase=phase, force=force, events=events,
                contacts=contacts)


# --------------------------------------------------------------------------- sensors
RIGS = {
    "liver": dict(adc_hz=1000, out_hz=200, noise=0.01, lsb=0.005, lowpass_hz=None,
                  encoder_m=1e-6, velocity=False),
    "lab": dict(adc_hz=500, out_hz=500, noise=0.015, lsb=0.0025, lowpass_hz=30.0,
                encoder_m=1e-6, velocity=True),
    "phantom": dict(adc_hz=1000, out_hz=1000, noise=0.012, lsb=0.002, lowpass_hz=None,
                    encoder_m=0.5e-6, velocity=True),
    "gel": dict(adc_hz=500, out_hz=500, noise=0.01, lsb=0.0025, lowpass_hz=30.0,
                encoder_m=1e-6, velocity=True),
    "logger": dict(adc_hz=100, out_hz=100, noise=0.015, lsb=0.005, lowpass_hz=None,
                   encoder_m=1e-6, velocity=False),
}
VELOCITY_WINDOW_S = 0.008
VELOCITY_NOISE_MPS = 2e-5


def measure(sim, rig, rng, drift_n=0.0):
    """What the rig logs: rows of (t, depth, velocity, force) plus the noiseless force."""
    cfg = RIGS[rig]
    f = sim["force"]
    if cfg["lowpass_hz"]:
        alpha = 1.0 - math.exp(-2.0 * math.pi * cfg["lowpass_hz"] / SIM_HZ)
        y = np.empty_like(f)
        acc = 0.0
        for i, u in enumerate(f):
            acc += alpha * (u - acc)
            y[i] = acc
        f = y
    if drift_n:
        f = f + drift_n * sim["t"] / sim["t"][-1]
    pick = SIM_HZ // cfg["adc_hz"]
    idx = np.arange(0, len(f), pick)
    x_adc = np.round(sim["x"][idx] / cfg["encoder_m"]) * cfg["encoder_m"]
    f_adc = f[idx]
    block = cfg["adc_hz"] // cfg["out_hz"]
    # The liver rig averages blocks of 1 kHz samples down to 200 Hz: noise there is
    # specified after the averaging, as the file shows it.
    sigma_adc = cfg["noise"] * math.sqrt(block)
    noisy = f_adc + rng.normal(0.0, sigma_adc, len(f_adc))
    n = len(idx) // block * block
    shape = (-1, block)
    t_out = np.arange(n // block) / cfg["out_hz"] + (block - 1) / (2.0 * cfg["adc_hz"])
    x_out = x_adc[:n].reshape(shape).mean(axis=1)
    clean = f_adc[:n].reshape(shape).mean(axis=1)
    meas = noisy[:n].reshape(shape).mean(axis=1)
    meas = np.round(meas / cfg["lsb"]) * cfg["lsb"]
    sim_index = idx[:n].reshape(shape)[:, block // 2]
    vel = None
    if cfg["velocity"]:
        lag = int(round(VELOCITY_WINDOW_S * cfg["out_hz"]))
        vel = np.zeros_like(x_out)
        vel[lag:] = (x_out[lag:] - x_out[:-lag]) * cfg["out_hz"] / lag
        vel += rng.normal(0.0, VELOCITY_NOISE_MPS, len(vel))
    true_x = sim["x"][sim_index]
    return dict(t=t_out, x=x_out, v=vel, f=meas, clean=clean, true_x=true_x,
                sim_index=sim_index, k=sim["k"][sim_index], phase=sim["phase"][sim_index])


def truth_rows(sim, rows):
    """Per insertion: (depth, peak row) of each rupture, the peak read off the noiseless log."""
    out = []
    for k, events in enumerate(sim["events"]):
        found = []
        for i, depth, name in events:
            window = np.flatnonzero((rows["k"] == k) & (rows["phase"] == 1)
                                    & (rows["true_x"] >= depth - 0.3e-3)
                                    & (rows["true_x"] <= depth + 0.15e-3))
            peak = int(window[np.argmax(rows["clean"][window])])
            found.append(dict(depth=depth, row=peak, name=name, sim=i))
        out.append(found)
    return out


def check_contrast(rows, truths, contacts):
    """Each loading must rise, and each rupture fall, clearly above the noise."""
    for k, found in enumerate(truths):
        previous = 0.0
        for e in found:
            clean, tx = rows["clean"], rows["true_x"]
            adv = (rows["k"] == k) & (rows["phase"] == 1)
            contact = max(c for c in contacts[k] if c < e["depth"])
            before = np.flatnonzero(adv & (tx >= max(contact, previous))
                                    & (np.arange(len(tx)) <= e["row"]))
            after = np.flatnonzero(adv & (tx > e["depth"]) & (tx <= e["depth"] + 0.5e-3))
            peak = clean[e["row"]]
            e["rise"] = peak - clean[before].min()
            e["drop"] = peak - clean[after].min()
            assert e["rise"] >= 0.15 and e["drop"] >= 0.15, (k, e)
            previous = e["depth"]


# --------------------------------------------------------------------------- writing
def dec(value, places):
    s = f"{value:.{places}f}"
    if "." in s:
        s = s.rstrip("0").rstrip(".")
    return "0" if s in ("-0", "") else s


def dlist(values, places):
    return ";".join(dec(v, places) for v in values) if values else "none"


def write_capture(path, device_rate, meta, columns, data):
    """`data`: list of (array, decimals) in column order."""
    head = (f"# palpus-capture format=1 kind=insertion device={meta['device']} "
            f"rate_hz={device_rate} units=si")
    for key, value in meta.items():
        if key == "device":
            continue
        value = str(value)
        assert value and all(33 <= ord(c) < 127 for c in value), (key, value)
        head += f" {key}={value}"
    lines = [head, ",".join(columns)]
    cols = [[dec(float(v), places) for v in arr] for arr, places in data]
    lines += [",".join(row) for row in zip(*cols)]
    path.write_text("\n".join(lines) + "\n")
    return len(lines) - 2


def base_meta(record, split, seed, tissue, speeds):
    layers = membranes_of(tissue)
    meta = {
        "device": f"corpus-{record}",
        "protocol": "needle_corpus",
        "record": record,
        "split": split,
        "seed": seed,
        "source": "scripts/needle_corpus.py",
        "tissue": tissue,
        "insertions": len(speeds),
        "speeds_mps": dlist(speeds, 6),
        "truth.layers": ";".join(m["name"] for m, _ in layers) or "none",
    }
    for m, c in layers:
        meta[f"truth.{m['name']}.depth_m"] = dec(c, 7)
        meta[f"truth.{m['name']}.a1_npm"] = dec(m["a1"], 3)
        meta[f"truth.{m['name']}.a2_npm2"] = dec(m["a2"], 1)
        meta[f"truth.{m['name']}.puncture_force_n"] = dec(m["p0"], 4)
    if layers:
        meta["truth.rate_softening"] = dec(RATE_SOFTENING, 3)
        meta["truth.rate_ref_mps"] = dec(V_REF_MPS, 4)
    return meta


def insertion_meta(meta, speeds, start_times, truths, clean, contacts=None):
    for k, speed in enumerate(speeds):
        meta[f"insertion.{k}.speed_mps"] = dec(speed, 6)
        if start_times is not None:
            meta[f"insertion.{k}.start_s"] = dec(start_times[k], 6)
        found = truths[k]
        meta[f"truth.insertion.{k}.puncture_depths_m"] = dlist([e["depth"] for e in found], 7)
        meta[f"truth.insertion.{k}.puncture_peaks_n"] = dlist([clean[e["row"]] for e in found], 5)
        meta[f"truth.insertion.{k}.puncture_rows"] = ";".join(str(e["row"]) for e in found) or "none"
        if contacts is not None and contacts[k]:
            meta[f"truth.insertion.{k}.contact_depths_m"] = dlist(contacts[k], 7)


def rig_meta(meta, rig):
    cfg = RIGS[rig]
    meta["sensor.force_noise_std_n"] = dec(cfg["noise"], 4)
    meta["sensor.force_lsb_n"] = dec(cfg["lsb"], 4)
    meta["sensor.lowpass_hz"] = dec(cfg["lowpass_hz"], 1) if cfg["lowpass_hz"] else "none"
    meta["sensor.encoder_quantum_m"] = dec(cfg["encoder_m"], 8)
    if cfg["adc_hz"] != cfg["out_hz"]:
        meta["sensor.decimation"] = f"mean-of-{cfg['adc_hz'] // cfg['out_hz']}-from-{cfg['adc_hz']}hz"
    if cfg["velocity"]:
        meta["sensor.velocity"] = f"encoder-backward-difference-{dec(VELOCITY_WINDOW_S * 1000, 1)}ms"


def rig_columns(rows, rig, keep=None):
    cfg = RIGS[rig]
    sel = slice(None) if keep is None else keep
    force_places = 4 if cfg["lsb"] < 0.005 else 3
    t_places = 6 if cfg["out_hz"] != cfg["adc_hz"] else 3
    cols = ["time_s", "depth_m"]
    data = [(rows["t"][sel], t_places), (rows["x"][sel], 7)]
    if cfg["velocity"]:
        cols.append("velocity_mps")
        data.append((rows["v"][sel], 6))
    cols.append("axial_force_n")
    data.append((rows["f"][sel], force_places))
    return cols, data


# --------------------------------------------------------------------------- records
MANIFEST = []


def finish(out, name, record, split, expect, insertions, rows, description, truths=(), clean=None):
    MANIFEST.append((name, record, split, expect, insertions, rows, description))
    print(f"{name}: {rows} rows, {(out / name).stat().st_size} bytes")
    for k, found in enumerate(truths):
        for e in found:
            contrast = f", rise {e['rise']:.2f} N, drop {e['drop']:.2f} N" if "rise" in e else ""
            print(f"  insertion {k}: {e['name']} gave way at {e['depth'] * 1e3:.3f} mm, "
                  f"peak {clean[e['row']]:.3f} N{contrast}")


def rig_record(out, record, split, seed, tissue, rig, speeds, target_m, description, expect="model",
               corrupt=None, **kw):
    rng = np.random.default_rng(seed)
    sim = simulate(tissue, speeds, target_m, rng, **kw)
    drift = 0.04 if corrupt else 0.0
    rows = measure(sim, rig, rng, drift_n=drift)
    truths = truth_rows(sim, rows)
    if membranes_of(tissue):
        check_contrast(rows, truths, sim["contacts"])
    meta = base_meta(record, split, seed, tissue, speeds)
    meta["target_depth_m"] = dec(target_m, 6)
    if kw.get("end_at_bottom"):
        meta["withdrawal"] = "none"
    else:
        meta["hold_s"] = dec(kw.get("hold_s", 0.5), 3)
        meta["withdraw_speed_mps"] = dec(kw.get("withdraw_mps", 0.01), 4)
    rig_meta(meta, rig)
    keep = np.ones(len(rows["t"]), dtype=bool)
    if corrupt:
        keep, outliers, gaps = corrupt(rows, truths, rng)
        meta["sensor.offset_drift_n"] = dec(drift, 3)
    remap = np.cumsum(keep) - 1
    for found in truths:
        for e in found:
            assert keep[e["row"]]
            e["row_written"] = int(remap[e["row"]])
    start_times = [rows["t"][np.argmax((rows["k"] == k) & (rows["phase"] == 1))]
                   for k in range(len(speeds))]
    insertion_meta(meta, speeds, start_times, truths, rows["clean"], sim["contacts"])
    for k, found in enumerate(truths):
        written = ";".join(str(e["row_written"]) for e in found)
        meta[f"truth.insertion.{k}.puncture_rows"] = written or "none"
    if corrupt:
        meta["outliers.rows"] = ";".join(str(int(remap[r])) for r in outliers)
        meta["outliers.values_n"] = ";".join(dec(rows["f"][r], 1) for r in outliers)
        meta["dropouts.after_rows"] = ";".join(str(int(remap[a - 1])) for a, _ in gaps)
        meta["dropouts.missing_rows"] = ";".join(str(b - a) for a, b in gaps)
    meta["expect"] = expect
    rate = RIGS[rig]["out_hz"]
    cols, data = rig_columns(rows, rig, keep)
    name = f"{record}_{split}.csv"
    n = write_capture(out / name, rate, meta, cols, data)
    finish(out, name, record, split, expect, len(speeds), n, description, truths, rows["clean"])


def corrupt_outliers(rows, truths, rng):
    """A 50 N and a 1000 N spike in tissue, and three dropouts away from the punctures."""
    n = len(rows["t"])
    busy = np.zeros(n, dtype=bool)
    for found in truths:
        for e in found:
            busy[max(0, e["row"] - 150):e["row"] + 150] = True
    adv = rows["phase"] == 1
    first, last = truths[0][0], truths[-1][-1]
    between = np.flatnonzero(adv & (rows["k"] == 0) & ~busy
                             & (rows["true_x"] > first["depth"] + 1.5e-3)
                             & (rows["true_x"] < truths[0][1]["depth"] - 3e-3))
    deep = np.flatnonzero(adv & (rows["k"] == len(truths) - 1) & ~busy
                          & (rows["true_x"] > last["depth"] + 2e-3))
    spikes = [int(rng.choice(between)), int(rng.choice(deep))]
    rows["f"][spikes[0]] = 50.0
    rows["f"][spikes[1]] = 1000.0
    for s in spikes:
        busy[s - 100:s + 100] = True
    keep = np.ones(n, dtype=bool)
    gaps = []
    while len(gaps) < 3:
        length = int(rng.integers(20, 81))
        a = int(rng.integers(200, n - 200))
        if busy[a - 50:a + length + 50].any():
            continue
        keep[a:a + length] = False
        busy[a - 200:a + length + 200] = True
        gaps.append((a, a + length))
    gaps.sort()
    return keep, sorted(spikes), gaps


def digitized_record(out, split, seed, description):
    """A force-depth curve traced off a figure: irregular points, rounded forces."""
    rng = np.random.default_rng(seed)
    tissue = "porcine_lumbar_back"
    speed = 0.003
    sim = simulate(tissue, [speed], 0.0405, rng, end_at_bottom=True)
    ins = (sim["phase"] == 1) & (sim["x"] >= 0.0) & (sim["x"] <= 0.040)
    idx = np.flatnonzero(ins)
    x, f = sim["x"][idx], sim["force"][idx]
    # The figure's own trace carries its measurement noise, smoothed by the line width.
    plotted = f + np.convolve(rng.normal(0.0, 0.02, len(f)), np.ones(25) / 25, mode="same")
    # Clicks follow the bends: density from the curvature seen at the figure's scale.
    grid = np.arange(0.0, 0.040, 0.02e-3)
    fg = np.interp(grid, x, f)
    bend = np.abs(np.diff(fg, 2))
    bend = np.convolve(bend, np.ones(15) / 15, mode="same")
    weight = 1.0 + 6.0 * np.sqrt(bend / bend.max())
    weight = np.concatenate([[weight[0]], weight, [weight[-1]]])
    cum = np.cumsum(weight)
    cum = (cum - cum[0]) / (cum[-1] - cum[0])
    events = sim["events"][0]
    must = []
    for i, depth, _ in events:
        must += [depth, depth + 0.18e-3]
    # The peaks and the bottoms of the falls are clicked on purpose; clicks closer than
    # 0.04 mm would land on the same pixel, so ask for more until ~370 remain.
    count = 370 - len(must)
    while True:
        u = (np.arange(count) + 0.5 + rng.uniform(-0.35, 0.35, count)) / count
        picks = np.interp(u, cum, grid)
        picks = picks[np.min(np.abs(picks[:, None] - np.array(must)[None, :]), axis=1) > 0.06e-3]
        picks = picks[picks > 0.04e-3]
        picks = picks[np.concatenate([[True], np.diff(picks) > 0.04e-3])]
        if len(picks) + len(must) + 1 >= 368:
            break
        count += 370 - 1 - len(must) - len(picks)
    pts = np.sort(np.concatenate([[0.0], picks, must]))
    assert np.all(np.diff(pts) > 0.04e-3)
    force = np.interp(pts, x, plotted)
    clean = np.interp(pts, x, f)
    peaks = []
    for i, depth, _ in events:
        j = int(np.argmin(np.abs(pts - depth)))
        assert abs(pts[j] - depth) < 1e-12
        clean[j] = sim["force"][i - 1]  # the last reading before the fall
        before = np.searchsorted(x, depth) - 1
        force[j] = clean[j] + (plotted[before] - f[before])
        peaks.append(j)
    gaps = np.diff(pts)
    room = np.minimum(np.concatenate([[gaps[0]], gaps]), np.concatenate([gaps, [gaps[-1]]]))
    jitter = rng.uniform(-1.0, 1.0, len(pts)) * np.minimum(0.05e-3, 0.45 * room)
    jitter[0] = 0.0
    depth = np.round((pts + jitter) * 1e6) / 1e6
    force = force + rng.uniform(-0.004, 0.004, len(pts))
    # Digitizing slips: one point each, clearly below both neighbours, away from punctures.
    near = np.zeros(len(pts), dtype=bool)
    for j in peaks:
        near[max(0, j - 12):j + 12] = True
    candidates = np.flatnonzero(~near[1:-1]) + 1
    candidates = candidates[(pts[candidates] > 2e-3)]
    slips = []
    for _ in range(int(rng.integers(2, 4))):
        j = int(rng.choice(candidates))
        slips.append(j)
        candidates = candidates[np.abs(candidates - j) > 20]
    slips.sort()
    for j in slips:
        force[j] = min(force[j - 1], force[j + 1]) - rng.uniform(0.05, 0.1)
    force = np.round(force, 2)
    time = np.round(depth / speed, 6)
    assert np.all(np.diff(depth) > 0) and np.all(np.diff(time) > 0)
    for j in slips:
        assert force[j] < force[j - 1] and force[j] < force[j + 1]
    rate = max(1, int(round((len(time) - 1) / (time[-1] - time[0]))))
    found = [dict(depth=d, row=j, name=name) for (i, d, name), j in zip(events, peaks)]
    previous = 0.0
    for e in found:
        contact = max(c for c in sim["contacts"][0] if c < e["depth"])
        before = np.flatnonzero((pts >= max(contact, previous)) & (pts <= e["depth"]))
        after = np.flatnonzero((pts > e["depth"]) & (pts <= e["depth"] + 0.5e-3))
        e["rise"] = clean[e["row"]] - clean[before].min()
        e["drop"] = clean[e["row"]] - clean[after].min()
        assert e["rise"] >= 0.15 and e["drop"] >= 0.15, e
        previous = e["depth"]
    sep = np.diff([e["depth"] for e in found])
    assert len(found) == 4 and 2.5e-3 <= min(sep) <= 2.8e-3, sep
    assert 14.5e-3 < found[0]["depth"] and found[-1]["depth"] < 37e-3
    meta = base_meta("digitized", split, seed, tissue, [speed])
    meta["digitized.points"] = len(pts)
    meta["digitized.force_resolution_n"] = "0.01"
    meta["digitized.depth_jitter_m"] = "0.00005"
    meta["digitized.time"] = "depth_over_0.003mps"
    meta["digitized.slips.rows"] = ";".join(map(str, slips))
    insertion_meta(meta, [speed], None, [found], clean, sim["contacts"])
    meta["expect"] = "model"
    name = f"digitized_{split}.csv"
    n = write_capture(out / name, rate, meta, ["time_s", "depth_m", "axial_force_n"],
                      [(time, 6), (depth, 6), (force, 2)])
    finish(out, name, "digitized", split, "model", 1, n, description, [found], clean)


def tiny_record(out, split, seed, start_depth_m, description):
    rng = np.random.default_rng(seed)
    tissue = "porcine_abdominal_wall"
    sim = simulate(tissue, [0.005], 0.03, rng)
    rows = measure(sim, "logger", rng)
    first = int(np.argmax((rows["phase"] == 1) & (rows["true_x"] >= start_depth_m)))
    keep = np.zeros(len(rows["t"]), dtype=bool)
    keep[first:first + 12] = True
    meta = base_meta("tiny", split, seed, tissue, [0.005])
    rig_meta(meta, "logger")
    meta["truncated"] = "true"
    insertion_meta(meta, [0.005], None, [[]], rows["clean"])
    meta["expect"] = "refuse"
    cols, data = rig_columns(rows, "logger", keep)
    name = f"tiny_{split}.csv"
    n = write_capture(out / name, 100, meta, cols, data)
    finish(out, name, "tiny", split, "refuse", 1, n, description)


def foreign_record(out, seed):
    """one_speed's rig logged by a foreign program: ms, mm, mN, semicolons, no metadata."""
    rng = np.random.default_rng(seed)
    tissue = "bovine_liver"
    sim = simulate(tissue, [0.003], 0.040, rng, end_at_bottom=True)
    rows = measure(sim, "liver", rng)
    truths = truth_rows(sim, rows)
    check_contrast(rows, truths, sim["contacts"])
    lines = ["t[ms];depth[mm];F[mN]"]
    for t, x, f in zip(rows["t"], rows["x"], rows["f"]):
        lines.append(f"{dec(t * 1e3, 3)};{dec(x * 1e3, 4)};{dec(f * 1e3, 1)}")
    (out / "foreign_units.csv").write_text("\n".join(lines) + "\n")
    truth = {
        "record": "foreign",
        "source": "scripts/needle_corpus.py",
        "seed": seed,
        "tissue": tissue,
        "expect": "model",
        "columns": {"t[ms]": "time_s", "depth[mm]": "depth_m", "F[mN]": "axial_force_n"},
        "import_map": "time_s=t[ms],depth_m=depth[mm],axial_force_n=F[mN]",
        "rate_hz": RIGS["liver"]["out_hz"],
        "speed_mps": 0.003,
        "layers": [{"name": m["name"], "depth_m": round(c, 7)} for m, c in membranes_of(tissue)],
        "insertions": [{
            "speed_mps": 0.003,
            "puncture_depths_m": [round(e["depth"], 7) for e in truths[0]],
            "puncture_peaks_n": [round(float(rows["clean"][e["row"]]), 5) for e in truths[0]],
            "puncture_rows": [e["row"] for e in truths[0]],
        }],
    }
    (out / "foreign_units.truth.json").write_text(json.dumps(truth, indent=2, sort_keys=True) + "\n")
    finish(out, "foreign_units.csv", "foreign", "foreign", "model", 1, len(lines) - 1,
           "one_speed rig as a foreign log in ms mm and mN", truths, rows["clean"])
    MANIFEST.append(("foreign_units.truth.json", "foreign", "sidecar", "model", 1, 0,
                     "truth of foreign_units.csv"))


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", default=str(Path(__file__).resolve().parent.parent
                                             / "assets" / "captures" / "needle_corpus"))
    out = Path(parser.parse_args().out)
    out.mkdir(parents=True, exist_ok=True)

    liver = "liver capsule then vessel lumen and far wall at 3 mm/s"
    rig_record(out, "one_speed", "train", 101, "bovine_liver", "liver", [0.003], 0.040, liver,
               end_at_bottom=True)
    rig_record(out, "one_speed", "test", 102, "bovine_liver", "liver", [0.003], 0.040, liver,
               end_at_bottom=True)

    traced = "epidural route traced from a figure with four punctures"
    digitized_record(out, "train", 201, traced)
    digitized_record(out, "test", 202, traced)

    close = "abdominal wall with two fasciae 2.2 mm apart"
    rig_record(out, "close_layers", "train", 301, "porcine_abdominal_wall", "lab",
               [0.002, 0.005, 0.008], 0.030, close)
    rig_record(out, "close_layers", "test", 302, "porcine_abdominal_wall", "lab", [0.005], 0.030,
               close)

    lumen = "heart wall phantom whose wall opens into a fluid lumen"
    rig_record(out, "lumen", "train", 401, "heart_wall_phantom", "phantom", [0.004, 0.008], 0.035,
               lumen)
    rig_record(out, "lumen", "test", 402, "heart_wall_phantom", "phantom", [0.006], 0.035, lumen)

    dirty = "two layers with spikes and drift and dropouts"
    rig_record(out, "outliers", "train", 501, "ovine_abdominal_wall", "lab", [0.003, 0.006], 0.030,
               dirty, corrupt=corrupt_outliers)
    rig_record(out, "outliers", "test", 502, "ovine_abdominal_wall", "lab", [0.0045], 0.030, dirty,
               corrupt=corrupt_outliers)

    gel = "homogeneous gel without any membrane"
    rig_record(out, "gel", "train", 601, "gelatin_10pct", "gel", [0.004, 0.008], 0.025, gel,
               expect="refuse")
    rig_record(out, "gel", "test", 602, "gelatin_10pct", "gel", [0.006], 0.025, gel, expect="refuse")

    tiny_record(out, "train", 701, 3e-3, "twelve rows of a truncated log")
    tiny_record(out, "test", 702, 5e-3, "twelve rows of a truncated log")

    foreign_record(out, 801)

    lines = ["path,record,split,expect,insertions,rows,description"]
    lines += [",".join(map(str, row)) for row in MANIFEST]
    (out / "MANIFEST.csv").write_text("\n".join(lines) + "\n")


if __name__ == "__main__":
    main()
