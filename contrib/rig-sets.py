#!/usr/bin/env python3
"""Test data of other rigs' character (issue 13), written deterministically:
not committed, generated. Needs numpy and scipy.

    contrib/rig-sets.py OUT_DIR [--seed S] [--only noise|sound|fingertip|long] [--trials N]

OUT_DIR/noise/<label>/<label>-trialNN.csv
    A stationary-noise set: 12 materials of one family x 8 trials, 2 s each
    at 1 kHz, one column `acc` (an accelerometer on a probe dragged at a
    steady speed): friction noise only, the material in small differences
    of its spectral envelope, no texture period, no transients, no drift
    (the contact force changes level and tilt a little per trial).

OUT_DIR/sound/<label>/<label>-clipN.wav
    A stylus-sound set: 14 materials x 4 clips, 5 s each, 44.1 kHz, 16-bit
    mono WAV (the microphone of a stylus dragged over a surface).
OUT_DIR/fingertip/<label>/<label>-trialNN.csv
    A fingertip-vibration set: 20 materials x 10 trials, 6 s each at 2.2 kHz
    (13,200 samples), one column `vib` (sensor counts), trials numbered in
    the order they were recorded, so file-name order is time order.
OUT_DIR/long/<label>/<label>.csv
    One long recording per material: 5 materials x one 60 s trace at
    100 Hz (6,000 samples), one column `acc` (an IMU on a probe), the gain
    drifting about 3 dB over the minute; cut into trials at import.

Import them with

    hapticlab import OUT_DIR/noise/*/*.csv --rate 1000 --out rec/noise
    hapticlab import OUT_DIR/sound/*/*.wav --out rec/sound
    hapticlab import OUT_DIR/fingertip/*/*.csv --rate 2200 --out rec/finger
    hapticlab import OUT_DIR/long/*/*.csv --rate 100 --split 2 --out rec/long

and the first 5 trials of each fingertip material are the earliest
(`train_per_class = 5, test_per_class = 5` is the time split).

The physics, briefly:
- Texture: each material has a spatial period (0.25-2.5 mm) with its own
  harmonic amplitudes. Stroked at speed v it sounds at f0 = v / period and
  its harmonics. The speed is the person's, not the material's: it differs
  from clip to clip (here 50-150 mm/s) and wobbles a little within a clip, so
  a material's peaks sit at different frequencies in different clips.
- Friction noise: white noise shaped by a material-specific spectral envelope
  (a power-law tilt, a smooth +-10 dB colouring over log frequency, and two
  or three resonances of the stylus/finger on the material), the part of
  the signal a log spectrum describes well.
- Contact transients: Poisson-timed impacts (material-specific rate), each a
  decaying ring at one of the material's resonances.
- Knocks (sound only): about one loud 5 ms broadband click per clip, at a
  random time, whatever the material. A whole-clip spectrum carries them;
  most 0.5 s windows do not, so windows that vote outvote them.
- Level: the contact force and microphone distance change between takes, a
  gain drawn per take (sound: 2.5 dB standard deviation; fingertip: 2 dB).
- Fingertip only, "over days": the gain drifts with the trial number (about
  +6 dB by trial 10) and the spectral tilt changes slowly (the skin and
  sensor coupling), so the last five trials differ from the first five in a
  way no training trial shows in full.
A sensor noise floor and 16-bit (sound) or integer-count (fingertip)
quantisation finish the signal.
"""
import argparse
from pathlib import Path

import numpy as np
from scipy.io import wavfile


def material(rng, f_lo, f_hi):
    """One material's parameters, drawn once."""
    n_res = int(rng.integers(2, 4))
    return {
        "period_mm": float(np.exp(rng.uniform(np.log(0.25), np.log(2.5)))),
        "harmonics": rng.uniform(0.2, 1.0, 6) * 0.7 ** np.arange(6),
        "periodic": float(rng.uniform(0.5, 1.5)),
        "tilt": float(rng.uniform(0.0, 3.0)),
        "res_f": np.exp(rng.uniform(np.log(f_lo), np.log(f_hi), n_res)),
        "res_q": rng.uniform(2.0, 8.0, n_res),
        "res_gain": rng.uniform(2.0, 10.0, n_res),
        "colour": [(rng.uniform(0.1, 0.6), rng.uniform(1.0, 3.0), rng.uniform(0, 6.3)) for _ in range(4)],
        "taps_per_s": float(rng.uniform(0.5, 4.0)),
    }


def envelope(m, f, f_ref, tilt_change=0.0):
    """The amplitude envelope of the friction noise at frequencies f."""
    f = np.maximum(f, 1.0)
    e = (f / f_ref) ** (-(m["tilt"] + tilt_change) / 2)
    for a, octaves, phase in m["colour"]:
        e = e * 10 ** (a / 2 * np.sin(2 * np.pi * np.log2(f) / octaves + phase))
    for fc, q, g in zip(m["res_f"], m["res_q"], m["res_gain"]):
        e = e * (1.0 + g / (1.0 + (q * (f / fc - fc / f)) ** 2))
    return e


def take(rng, m, rate, seconds, speed_mm_s, gain, tilt_change=0.0, knock=0.0):
    """One clip or trial of material m."""
    n = int(round(rate * seconds))
    t = np.arange(n) / rate
    # Periodic texture: phase of f0(t) = v(t) / period, v wobbling 5 %.
    v = speed_mm_s * (1 + 0.15 * np.sin(2 * np.pi * t / rng.uniform(1.5, 4.0) + rng.uniform(0, 6.3)))
    phase = 2 * np.pi * np.cumsum(v / m["period_mm"]) / rate
    periodic = np.zeros(n)
    for h, a in enumerate(m["harmonics"], start=1):
        if h * speed_mm_s / m["period_mm"] < 0.45 * rate:
            periodic += a * np.sin(h * phase + rng.uniform(0, 6.3))
    # Friction noise: white noise through the material's envelope.
    f = np.fft.rfftfreq(n, 1 / rate)
    noise = np.fft.irfft(np.fft.rfft(rng.standard_normal(n)) * envelope(m, f, rate / 20, tilt_change), n)
    noise /= noise.std()
    # Contact transients: decaying rings at the material's resonances.
    taps = np.zeros(n)
    for at in rng.uniform(0, seconds, rng.poisson(m["taps_per_s"] * seconds)):
        fc = rng.choice(m["res_f"])
        j0 = int(at * rate)
        tt = np.arange(min(n - j0, int(0.05 * rate))) / rate
        taps[j0 : j0 + len(tt)] += rng.uniform(2, 10) * np.exp(-tt * fc / 4) * np.sin(2 * np.pi * fc * tt)
    # Knocks: the hand bumps the rig now and then, whatever the material: a
    # few loud broadband clicks per take, at random.
    for at in rng.uniform(0, seconds, rng.poisson(0.2 * seconds)):
        j0 = int(at * rate)
        tt = np.arange(min(n - j0, int(0.005 * rate) + 1)) / rate
        taps[j0 : j0 + len(tt)] += knock * np.exp(rng.normal(0, 0.5)) * np.exp(-tt / 0.001) * rng.standard_normal(len(tt))
    x = m["periodic"] * periodic + noise + taps
    return gain * x + 0.01 * rng.standard_normal(n)


def sound_set(out, seed):
    rng = np.random.default_rng([seed, 1])
    rate = 44100
    for i in range(14):
        m = material(rng, 300.0, 8000.0)
        label = f"M{i + 1:02d}"
        (out / label).mkdir(parents=True, exist_ok=True)
        for c in range(4):
            crng = np.random.default_rng([seed, 1, i, c])
            speed = crng.uniform(50, 150)
            gain = 10 ** (crng.normal(0, 2.5) / 20)
            x = take(crng, m, rate, 5.0, speed, gain, knock=12.0)
            pcm = np.clip(np.rint(x * 1500), -32768, 32767).astype(np.int16)
            wavfile.write(out / label / f"{label}-clip{c + 1}.wav", rate, pcm)


def fingertip_set(out, seed, trials=10):
    rng = np.random.default_rng([seed, 2])
    rate = 2200
    # The slow drift is the rig's (skin, sensor coupling), shared by all
    # materials recorded that day, plus a little of each trial's own; over
    # more trials the same drift, spread over them.
    day_tilt = np.cumsum(rng.normal(0.015, 0.01, trials)) * (10 / trials)
    day_gain_db = np.linspace(0, 6, trials) + rng.normal(0, 1, trials)
    for i in range(20):
        m = material(rng, 40.0, 700.0)
        label = f"F{i + 1:02d}"
        (out / label).mkdir(parents=True, exist_ok=True)
        for trial in range(trials):
            crng = np.random.default_rng([seed, 2, i, trial])
            speed = crng.uniform(40, 120)
            gain = 10 ** ((day_gain_db[trial] + crng.normal(0, 2)) / 20)
            x = take(crng, m, rate, 6.0, speed, gain, day_tilt[trial] + crng.normal(0, 0.05))
            counts = np.rint(x * 400).astype(np.int64)
            path = out / label / f"{label}-trial{trial + 1:02d}.csv"
            path.write_text("vib\n" + "\n".join(map(str, counts)) + "\n")


def noise_set(out, seed):
    rng = np.random.default_rng([seed, 4])
    rate, seconds = 1000, 2.0
    n = int(rate * seconds)
    f = np.fft.rfftfreq(n, 1 / rate)
    # Materials of one family: a shared envelope, each with its own small
    # colouring and its resonances moved a little.
    base = material(rng, 20.0, 400.0)
    for i in range(12):
        m = dict(base)
        m["colour"] = [(rng.uniform(0.05, 0.25), rng.uniform(1.0, 3.0), rng.uniform(0, 6.3)) for _ in range(3)]
        m["res_f"] = base["res_f"] * np.exp(rng.normal(0, 0.1, len(base["res_f"])))
        label = f"N{i + 1:02d}"
        (out / label).mkdir(parents=True, exist_ok=True)
        for trial in range(8):
            crng = np.random.default_rng([seed, 4, i, trial])
            # The contact force changes a little per trial: level and tilt.
            e = envelope(m, f, rate / 20, crng.normal(0, 0.15))
            x = np.fft.irfft(np.fft.rfft(crng.standard_normal(n)) * e, n)
            x *= 10 ** (crng.normal(0, 2) / 20) / x.std()
            counts = np.rint((x + 0.01 * crng.standard_normal(n)) * 400).astype(np.int64)
            path = out / label / f"{label}-trial{trial + 1:02d}.csv"
            path.write_text("acc\n" + "\n".join(map(str, counts)) + "\n")


def long_set(out, seed):
    rng = np.random.default_rng([seed, 3])
    rate, seconds = 100, 60.0
    for i in range(5):
        m = material(rng, 3.0, 40.0)
        label = f"L{i + 1}"
        (out / label).mkdir(parents=True, exist_ok=True)
        crng = np.random.default_rng([seed, 3, i])
        x = take(crng, m, rate, seconds, crng.uniform(5, 15), 1.0)
        # The grip loosens over the minute: about +3 dB from start to end.
        x *= 10 ** (np.linspace(0, 3, len(x)) / 20)
        counts = np.rint(x * 400).astype(np.int64)
        (out / label / f"{label}.csv").write_text("acc\n" + "\n".join(map(str, counts)) + "\n")


def main():
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("out", type=Path)
    p.add_argument("--seed", type=int, default=13)
    p.add_argument("--only", choices=["noise", "sound", "fingertip", "long"])
    p.add_argument("--trials", type=int, default=10,
                   help="fingertip trials per material (10; 50 is the size of the real 1000-trial set)")
    args = p.parse_args()
    if args.only in (None, "noise"):
        noise_set(args.out / "noise", args.seed)
    if args.only in (None, "sound"):
        sound_set(args.out / "sound", args.seed)
    if args.only in (None, "fingertip"):
        fingertip_set(args.out / "fingertip", args.seed, args.trials)
    if args.only in (None, "long"):
        long_set(args.out / "long", args.seed)


if __name__ == "__main__":
    main()
