#!/usr/bin/env python3
"""hapticlab against aeon's time-series classifiers on the same recordings,
the same split and the same points (issue 32). Not run by CI.

aeon goes into a virtual environment of its own, never the system's
(MultiRocket-Hydra needs torch too; without it that row says so):

    python3 -m venv /tmp/aeonenv && /tmp/aeonenv/bin/pip install aeon
    /tmp/aeonenv/bin/pip install torch      # for MultiRocket-Hydra only

    /tmp/aeonenv/bin/python contrib/aeon-peer.py DIR -p PROFILE.toml
        [--hapticlab PATH] [--methods minirocket,hydra,quant,tune]
        [--seed S] [--threads N] [--budget N] [--json] [--no-warm-up] [--znorm]
    /tmp/aeonenv/bin/python contrib/aeon-peer.py --per-window POINTS [--repeats R]

The split is hapticlab's own: `hapticlab evaluate DIR -p PROFILE --json`
names the training files and every test file, so aeon trains and tests on
exactly the recordings hapticlab does. A holdout (or time split) is one
fit; k-fold, leave-one-out and grouped folds are one fit per fold, each
fold's test files read off the JSON in order (`folds[].tested` of them)
and its training part every other evaluated recording. A fold that left
recordings out of its training part (overlapping segments of one
recording) is refused: the JSON does not say which.

The signal: the profile's `[analysis]` `channel` (and `channels`, as more
dimensions of one multivariate series) along `axis`, measured from the
first sample in the direction of travel, over `window` = [start, end],
linearly interpolated onto the grid start + i * spacing (i = 0 .. while
within end), the points hapticlab resamples. aeon sees that whole window;
the profile's sub-windows, spectrum and k-NN are hapticlab's alone.
aeon's classifiers do not normalise a series (the UCR archive's series
come z-normalised); --znorm z-normalises each channel of each recording
before aeon sees it (mean 0, standard deviation 1), which takes a gain
out of the signal as hapticlab's cepstra without c0 do.

Methods, each a fit on the training part and a prediction of the test
part, timed as wall time and as this process's CPU (user + system of
every thread: numba's, torch's, BLAS's), after an untimed warm-up fit on
two training recordings a label (numba compiles, or loads its cache, on
the first call; --no-warm-up times that too):
- minirocket: aeon's MiniRocketClassifier (MiniRocket's 9996 features,
  a scaler and RidgeClassifierCV, as the paper);
- hydra: aeon's MultiRocketHydraClassifier (needs torch);
- hydra-alone: aeon's HydraClassifier, the competing kernels alone (needs
  torch; not run unless named), beside hapticlab's `features = "hydra"`;
- quant: aeon's QUANTClassifier (interval quantiles, extra trees);
- tune: `hapticlab tune DIR -p PROFILE --json --out NEW` (its outer
  estimate, `outer_accuracy`), its CPU the child's (RUSAGE_CHILDREN);
- evaluate: the profile as written (the run that gave the split), shown
  for reference.
--threads N sets numba's, BLAS's and torch's threads and aeon's n_jobs,
and pins hapticlab to N cores (it uses every core it may run on);
default: every core this process may use.

--per-window POINTS times aeon's MiniRocket transform on one core
(NUMBA_NUM_THREADS=1), fitted on 80 windows of POINTS points, after a
warm-up call (numba's compilation is not counted): one window per call,
and per window in a batch of 100; for comparing with
`cargo bench --bench kernels`.

Exit codes: 0 ok, 2 bad input (a refusal, one line on standard error),
1 a failure of hapticlab or aeon.
"""
import argparse
import gzip
import io
import json
import os
import resource
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

METHODS = ("minirocket", "hydra", "quant", "tune", "hydra-alone")
NAMES = {
    "minirocket": "aeon MiniRocket",
    "hydra": "aeon MultiRocket-Hydra",
    "quant": "aeon QUANT",
    "hydra-alone": "aeon Hydra",
    "tune": "hapticlab tune (outer)",
    "evaluate": "hapticlab evaluate (profile as written)",
}


def refuse(msg):
    print(f"aeon-peer: {msg}", file=sys.stderr)
    sys.exit(2)


def fail(msg):
    print(f"aeon-peer: {msg}", file=sys.stderr)
    sys.exit(1)


def usable_cores():
    try:
        return sorted(os.sched_getaffinity(0))
    except AttributeError:
        return list(range(os.cpu_count() or 1))


def parse():
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("dir", type=Path, nargs="?", help="a folder of hapticlab recordings (format v1)")
    p.add_argument("-p", "--profile", type=Path, help="the hapticlab profile: its [analysis] and [evaluation]")
    p.add_argument("--hapticlab", default="hapticlab", help="the hapticlab binary (default: on PATH)")
    p.add_argument("--methods", default="minirocket,hydra,quant,tune", help="comma list of " + ", ".join(METHODS))
    p.add_argument("--seed", type=int, default=0, help="aeon's random_state and tune's --seed (the split is the profile's)")
    p.add_argument("--threads", type=int, help="threads for aeon and cores for hapticlab (default: every usable core)")
    p.add_argument("--budget", type=int, help="tune's --budget (default: tune's)")
    p.add_argument("--json", action="store_true", help="print the results as JSON")
    p.add_argument("--znorm", action="store_true", help="z-normalise each series (every channel) before aeon sees it")
    p.add_argument("--no-warm-up", action="store_true", help="time aeon's first call too (numba's compilation or cache load)")
    p.add_argument("--per-window", type=int, metavar="POINTS", help="time MiniRocket's transform per window on one core")
    p.add_argument("--repeats", type=int, default=50, help="--per-window: single-window calls timed")
    a = p.parse_args()
    if a.per_window is None and (a.dir is None or a.profile is None):
        refuse("give DIR and -p PROFILE (or --per-window POINTS)")
    if a.threads is not None and a.threads < 1:
        refuse("--threads must be 1 or more")
    a.methods = [m.strip() for m in a.methods.split(",") if m.strip()]
    bad = [m for m in a.methods if m not in METHODS]
    if bad:
        refuse(f"--methods: no method {bad[0]!r} (one of {', '.join(METHODS)})")
    return a


def set_threads(n):
    """Thread caps read when numba, BLAS and torch load: before aeon is imported."""
    for var in ("NUMBA_NUM_THREADS", "OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
        os.environ[var] = str(n)


def import_aeon():
    try:
        import aeon  # noqa: F401
    except ImportError:
        refuse("aeon is not importable by " + sys.executable
               + ": python3 -m venv /tmp/aeonenv && /tmp/aeonenv/bin/pip install aeon, then run this with /tmp/aeonenv/bin/python")
    return aeon.__version__


def cpu_self():
    r = resource.getrusage(resource.RUSAGE_SELF)
    return r.ru_utime + r.ru_stime


def cpu_children():
    r = resource.getrusage(resource.RUSAGE_CHILDREN)
    return r.ru_utime + r.ru_stime


def hapticlab(a, args, cores):
    """Run hapticlab pinned to `cores`; (stdout, cpu s, wall s)."""
    pin = (lambda: os.sched_setaffinity(0, cores)) if hasattr(os, "sched_setaffinity") else None
    c0, w0 = cpu_children(), time.perf_counter()
    try:
        run = subprocess.run([a.hapticlab, *args], capture_output=True, text=True, preexec_fn=pin)
    except FileNotFoundError:
        refuse(f"no hapticlab binary {a.hapticlab!r} (give --hapticlab PATH)")
    wall, cpu = time.perf_counter() - w0, cpu_children() - c0
    if run.returncode != 0:
        err = run.stderr.strip().splitlines()
        msg = f"hapticlab {args[0]} exited {run.returncode}: {err[-1] if err else ''}"
        (refuse if run.returncode == 2 else fail)(msg)
    return run.stdout, cpu, wall


# --- the split ---------------------------------------------------------------


def split(ev):
    """[(train files, test files)] from `evaluate --json`: one part for a
    holdout, one per fold for k-fold, leave-one-out and grouped folds."""
    test = [r["file"] for r in ev["predictions"]]
    if "folds" not in ev:
        return [(list(ev["train"]), test)], "holdout"
    folds = ev["folds"]
    if any(f.get("left_out", 0) for f in folds):
        refuse("a fold left overlapping segments out of its training part, and evaluate's JSON does not say which: "
               "only a holdout (or folds without overlapping segments) can be reproduced")
    if sum(f["tested"] for f in folds) != len(test) or len(set(test)) != len(test):
        refuse("evaluate's JSON: the folds' tested counts do not add up to its predictions, each tested once")
    everyone = set(ev["train"]) | set(test)
    parts, at = [], 0
    for f in folds:
        t = test[at : at + f["tested"]]
        at += f["tested"]
        held = set(t)
        parts.append(([x for x in sorted(everyone) if x not in held], t))
    return parts, ev.get("method", "folds")


# --- the signal --------------------------------------------------------------


def analysis(profile):
    import tomllib

    try:
        a = tomllib.loads(profile.read_text()).get("analysis", {})
    except (OSError, tomllib.TOMLDecodeError) as e:
        refuse(f"{profile}: {e}")
    for key in ("channel", "axis", "window", "spacing"):
        if key not in a:
            refuse(f"{profile}: [analysis] has no {key} (this script reads it from the profile file)")
    if not (isinstance(a["window"], list) and len(a["window"]) == 2):
        refuse(f"{profile}: [analysis] window = {a['window']!r}: only [start, end] is read here")
    return [a["channel"], *a.get("channels", [])], a["axis"], [float(v) for v in a["window"]], float(a["spacing"])


def read(path):
    import pandas as pd

    raw = Path(path).read_bytes()
    if str(path).endswith(".gz"):
        raw = gzip.decompress(raw)
    return pd.read_csv(io.BytesIO(raw), comment="#")


def series(path, channels, axis, window, spacing, znorm):
    """The channels of one recording on the analysis grid: (channels, points)."""
    import numpy as np

    df = read(path)
    for c in [axis, *channels]:
        if c not in df.columns:
            refuse(f"{path}: no column {c!r} (the profile's [analysis] names it)")
    x = df[axis].to_numpy(float)
    d = (x - x[0]) * (1.0 if x[-1] >= x[0] else -1.0)
    lo, hi = window
    n = int(np.floor((hi - lo) / spacing + 1e-6)) + 1
    grid = lo + spacing * np.arange(n)
    if grid[-1] > d.max() + spacing or lo < d.min() - spacing:
        refuse(f"{path}: covers {d.min():g} to {d.max():g} of {axis}, the window is [{lo:g}, {hi:g}]")
    order = np.argsort(d, kind="stable")  # a position axis may step back
    x = np.stack([np.interp(grid, d[order], df[c].to_numpy(float)[order]) for c in channels])
    if znorm:
        sd = x.std(axis=1, keepdims=True)
        x = (x - x.mean(axis=1, keepdims=True)) / np.where(sd > 0, sd, 1.0)
    return x


# --- the methods -------------------------------------------------------------


def classifier(name, seed, threads):
    if name == "minirocket":
        from aeon.classification.convolution_based import MiniRocketClassifier

        return MiniRocketClassifier(n_jobs=threads, random_state=seed)
    if name == "hydra-alone":
        from aeon.classification.convolution_based import HydraClassifier

        return HydraClassifier(n_jobs=threads, random_state=seed)
    if name == "hydra":
        from aeon.classification.convolution_based import MultiRocketHydraClassifier

        return MultiRocketHydraClassifier(n_jobs=threads, random_state=seed)
    from aeon.classification.interval_based import QUANTClassifier
    from sklearn.ensemble import ExtraTreesClassifier

    # QUANT's paper forest (200 trees, a tenth of the features per split,
    # entropy), with n_jobs so --threads reaches it.
    trees = ExtraTreesClassifier(n_estimators=200, max_features=0.1, criterion="entropy",
                                 n_jobs=threads, random_state=seed)
    return QUANTClassifier(estimator=trees, random_state=seed)


def run_aeon(name, parts, X, y, seed, threads, warm_up):
    import numpy as np

    if name in ("hydra", "hydra-alone"):
        try:
            import torch  # noqa: F401
        except ImportError:
            return {"method": name, "skipped": "needs torch (pip install torch in the same environment)"}
    warm = None
    if warm_up:
        # One small fit and prediction first, untimed but for its own line:
        # numba compiles (or loads its cache) on the first call, as a
        # researcher's second run would not.
        train, test = parts[0]
        few, seen = [], {}
        for f in train:
            if seen.get(y[f], 0) < 2:
                seen[y[f]] = seen.get(y[f], 0) + 1
                few.append(f)
        c0 = cpu_self()
        clf = classifier(name, seed, threads)
        clf.fit(np.stack([X[f] for f in few]), np.array([y[f] for f in few]))
        clf.predict(np.stack([X[f] for f in test[:2]]))
        warm = cpu_self() - c0
    right = total = 0
    c0, w0 = cpu_self(), time.perf_counter()
    for train, test in parts:
        clf = classifier(name, seed, threads)
        clf.fit(np.stack([X[f] for f in train]), np.array([y[f] for f in train]))
        pred = clf.predict(np.stack([X[f] for f in test]))
        right += int(sum(p == y[f] for p, f in zip(pred, test)))
        total += len(test)
    return {"method": name, "accuracy": right / total, "right": right, "total": total,
            "cpu_s": cpu_self() - c0, "wall_s": time.perf_counter() - w0, "warm_up_cpu_s": warm}


def run_tune(a, cores):
    out = Path(tempfile.mkdtemp(prefix="aeon-peer-")) / "tuned.toml"
    try:
        args = ["tune", str(a.dir), "-p", str(a.profile), "--json", "--out", str(out), "--seed", str(a.seed)]
        if a.budget:
            args += ["--budget", str(a.budget)]
        text, cpu, wall = hapticlab(a, args, cores)
    finally:
        shutil.rmtree(out.parent, ignore_errors=True)
    t = json.loads(text)
    conf = t["outer"]["confusion"]
    right, total = sum(conf[i][i] for i in range(len(conf))), sum(map(sum, conf))
    return {"method": "tune", "accuracy": t["outer_accuracy"], "right": right, "total": total,
            "cpu_s": cpu, "wall_s": wall, "settings": t.get("configurations"),
            "chosen": t.get("chosen", {}).get("options")}


# --- per window --------------------------------------------------------------


def per_window(points, repeats):
    set_threads(1)
    version = import_aeon()
    import numpy as np
    from aeon.transformations.collection.convolution_based import MiniRocket

    rng = np.random.default_rng(1)
    t = np.arange(points)

    def windows(count):
        period = np.array([5.0, 9.0, 14.0, 23.0])[np.arange(count) % 4, None]
        phase = rng.uniform(0, 2 * np.pi, (count, 1))
        return (np.sin(2 * np.pi * t / period + phase) + 0.3 * rng.uniform(-1, 1, (count, points)))[:, None, :]

    mr = MiniRocket(n_jobs=1, random_state=1).fit(windows(80))
    one, batch = windows(1), windows(100)
    features = mr.transform(one).shape[1]  # the warm-up: numba compiles here
    mr.transform(batch)
    single, cpu = [], []
    for _ in range(repeats):
        c0, w0 = cpu_self(), time.perf_counter()
        mr.transform(one)
        single.append(time.perf_counter() - w0)
        cpu.append(cpu_self() - c0)
    c0, w0 = cpu_self(), time.perf_counter()
    mr.transform(batch)
    batched, batched_cpu = (time.perf_counter() - w0) / len(batch), (cpu_self() - c0) / len(batch)
    return {"aeon": version, "points": points, "features": features, "threads": 1,
            "one_window_ms_median": 1e3 * float(np.median(single)), "one_window_ms_min": 1e3 * float(np.min(single)),
            "one_window_cpu_ms_median": 1e3 * float(np.median(cpu)),
            "batch_of_100_ms_per_window": 1e3 * batched, "batch_of_100_cpu_ms_per_window": 1e3 * batched_cpu}


# --- main --------------------------------------------------------------------


def table(rows):
    lines = [f"{'method':40} {'accuracy':>9} {'right/total':>11} {'CPU s':>8} {'wall s':>8}"]
    for r in rows:
        name = NAMES[r["method"]]
        if "skipped" in r:
            lines.append(f"{name:40} skipped: {r['skipped']}")
            continue
        lines.append(f"{name:40} {100 * r['accuracy']:8.1f}% {r['right']:>5}/{r['total']:<5} "
                     f"{r['cpu_s']:8.2f} {r['wall_s']:8.2f}")
    return "\n".join(lines)


def main():
    a = parse()
    if a.per_window is not None:
        if a.per_window < 9:
            refuse("--per-window: MiniRocket needs at least 9 points")
        r = per_window(a.per_window, a.repeats)
        if a.json:
            print(json.dumps(r))
        else:
            print(f"aeon {r['aeon']} MiniRocket transform, one core, {r['features']} features, windows of {r['points']} points: "
                  f"{r['one_window_ms_median']:.3f} ms per call of one window (median of {a.repeats}, min "
                  f"{r['one_window_ms_min']:.3f}; CPU {r['one_window_cpu_ms_median']:.3f}), "
                  f"{r['batch_of_100_ms_per_window']:.3f} ms per window in a batch of 100 (CPU {r['batch_of_100_cpu_ms_per_window']:.3f})")
        return
    cores = usable_cores()
    threads = a.threads or len(cores)
    cores = cores[:threads] if threads <= len(cores) else cores
    set_threads(threads)
    version = import_aeon()

    channels, axis, window, spacing = analysis(a.profile)
    text, ev_cpu, ev_wall = hapticlab(a, ["evaluate", str(a.dir), "-p", str(a.profile), "--json"], cores)
    ev = json.loads(text)
    parts, method = split(ev)
    files = sorted({f for tr, te in parts for f in tr + te})
    X = {f: series(f, channels, axis, window, spacing, a.znorm) for f in files}
    labels = {r["file"]: r["label"] for r in ev["predictions"]}
    # Training files that are never tested (a holdout): their label is the
    # recording's own `# label`, as hapticlab reads it.
    for f in files:
        if f not in labels:
            labels[f] = label_of(f)
    right = sum(r["predicted"] == r["label"] for r in ev["predictions"])
    rows = [{"method": "evaluate", "accuracy": ev["accuracy"], "right": right, "total": len(ev["predictions"]),
             "cpu_s": ev_cpu, "wall_s": ev_wall}]
    for m in a.methods:
        if m == "tune":
            rows.append(run_tune(a, cores))
        else:
            rows.append(run_aeon(m, parts, X, labels, a.seed, threads, not a.no_warm_up))
        if not a.json:
            print(f"done: {NAMES[m]}", file=sys.stderr)
    n = next(iter(X.values())).shape
    head = {"dir": str(a.dir), "profile": str(a.profile), "aeon": version,
            "hapticlab": subprocess.run([a.hapticlab, "--version"], capture_output=True, text=True).stdout.strip(),
            "split": method, "parts": len(parts), "train": len(parts[0][0]), "test": sum(len(t) for _, t in parts),
            "channels": channels, "axis": axis, "window": window, "spacing": spacing, "points": n[1],
            "seed": a.seed, "threads": threads, "znorm": a.znorm}
    if a.json:
        print(json.dumps({**head, "results": rows}))
        return
    print(f"{a.dir} with {a.profile}: {method}"
          + (f" ({len(parts)} parts)" if len(parts) > 1 else f" ({head['train']} train, {head['test']} test)")
          + f"; {', '.join(channels)} on {n[1]} points of {axis} ({window[0]:g} to {window[1]:g}, every {spacing:g});"
          + (" z-normalised for aeon;" if a.znorm else "")
          + f" aeon {version}, {head['hapticlab']}; seed {a.seed}, {threads} thread(s)")
    print(table(rows))


def label_of(path):
    raw = Path(path).read_bytes()
    if str(path).endswith(".gz"):
        raw = gzip.decompress(raw)
    for line in raw[:8192].decode(errors="replace").splitlines():
        if line.startswith("# label"):
            return line.split("=", 1)[1].strip().strip('"')
        if not line.startswith("#"):
            break
    return Path(path).parent.name


if __name__ == "__main__":
    main()
