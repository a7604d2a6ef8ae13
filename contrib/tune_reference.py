#!/usr/bin/env python3
"""The speed peer of `hapticlab tune` (issue 21): the same nested search in
scikit-learn, run side by side with hapticlab in one run, parsing included.
Needs numpy, scipy and scikit-learn.

    contrib/tune_reference.py DIR -p P.toml [--hapticlab target/release/hapticlab]
                              [--budget 96] [--seed 0] [--jobs -1] [--cached]

1. Runs `hapticlab tune DIR -p P.toml --out TMP --budget N --seed S --json`
   and times it (wall clock: reading the recordings, every setting, the
   outer test, writing the profile).
2. Reads the same recordings with numpy (parsing timed too), then runs a
   GridSearchCV with 5 stratified inner folds on the training part of the
   profile's holdout over the SAME settings hapticlab scored (its JSON
   lists the feature settings; every one is crossed with the same
   classifier grid: k 1/3/5/9, euclidean/manhattan/cosine, uniform/distance,
   standardize or not), refits the best on the training part and scores
   it once on the test part.

The estimator is the usual scikit-learn way: one estimator whose
parameters are the feature and classifier options, features computed in
`fit` and `predict` (so per fold and per setting, as a Pipeline with a
FunctionTransformer does), vectorised in numpy (every sub-window of every
recording in one `welch` call), StandardScaler fitted per fold, k-NN by
brute force, and sub-windows voting per recording. With `--cached`, the
strongest peer: each feature setting's features are made once for every
recording before the search (Welch fits nothing, so nothing leaks) and
GridSearchCV fits only the scaler and the k-NN per fold.

The features follow the hapticlab profile's analysis: the window cut from
the start of each recording, its mean removed, Welch with a Hann or
rectangular window and half-overlapping segments, log10 floored at
1e-300, bins 1..segment/2, or 13 DCT-II cepstra of log band energies (32
log bands from 2 bins to Nyquist). They are close to, not bit-for-bit,
hapticlab's (no resampling: the signals are already evenly sampled): the
accuracies are printed for reference, the figure is the time per setting.

Only a holdout [evaluation] is supported here (the time split of the
fingertip set); prints one line per side and the ratio.

    contrib/tune_reference.py DIR -p P.toml --settings TUNE.json

runs the scikit-learn side alone over the feature settings of a saved
`hapticlab tune --json` (for timing the two sides as separate commands,
run alternately by an outside timer) and prints its line.
"""
import argparse
import json
import subprocess
import tempfile
import time
import tomllib
from pathlib import Path

import numpy as np
from scipy.fft import dct
from scipy.signal import welch
from sklearn.base import BaseEstimator, ClassifierMixin
from sklearn.model_selection import GridSearchCV, StratifiedKFold
from sklearn.neighbors import KNeighborsClassifier
from sklearn.preprocessing import StandardScaler


def read_recording(path):
    """A hapticlab recording v1 (CSV with `#` header lines): label, rate, columns."""
    meta = {}
    with open(path) as f:
        for line in f:
            if not line.startswith("#"):
                header = line.strip().split(",")
                break
            if "=" in line:
                k, v = line[1:].split("=", 1)
                meta[k.strip()] = v.strip().strip('"')
        data = np.loadtxt(f, delimiter=",", comments="#", ndmin=2)
    return meta, dict(zip(header, data.T))


def floor3(v):
    scale = 10 ** (2 - np.floor(np.log10(v)))
    return np.floor(v * scale) / scale


class WelchKnn(ClassifierMixin, BaseEstimator):
    """Features (Welch bins or cepstra, per sub-window) then k-NN, sub-windows voting."""

    def __init__(self, rate=2200.0, window=(0.0, 1.0), spectrum="log-welch", taper="none",
                 segment=256, cepstra=0, drop_level=False, windows=None, k=1,
                 metric="euclidean", weights="uniform", standardize=False, table=None):
        self.rate = rate
        self.window = window
        self.spectrum = spectrum
        self.taper = taper
        self.segment = segment
        self.cepstra = cepstra
        self.drop_level = drop_level
        self.windows = windows
        self.k = k
        self.metric = metric
        self.weights = weights
        self.standardize = standardize
        self.table = table

    def _spans(self):
        w0, w1 = self.window
        if self.windows is None:
            return [(w0, w1)]
        length, hop = self.windows
        out, j = [], 0
        while w0 + j * hop + length <= w1 + 1e-9 * length:
            out.append((w0 + j * hop, w0 + j * hop + length))
            j += 1
        return out

    def _key(self):
        return (self.spectrum, self.taper, self.segment, self.cepstra, self.drop_level, self.windows)

    def _rows(self, X):
        """With a table (--cached), X holds recording indices into it."""
        if self.table is None:
            return self._windows_of(X)
        made = self.table[self._key()][np.asarray(X)[:, 0]]
        return made.reshape(-1, made.shape[-1]), [made.shape[1]] * len(made)

    def _windows_of(self, X):
        """Every sub-window of every recording at once (numpy over a stack,
        as a researcher vectorises it): rows, and the rows per recording."""
        spans = self._spans()
        n = int(np.floor((spans[0][1] - spans[0][0]) * self.rate + 1e-6)) + 1
        starts = [int(round(s * self.rate)) for s, _ in spans]
        stack = np.stack([np.stack([x[i0:i0 + n] for i0 in starts]) for x in X]).reshape(-1, n)
        stack = stack - stack.mean(axis=1, keepdims=True)
        f, p = welch(stack, fs=self.rate, window="hann" if self.taper == "hann" else "boxcar",
                     nperseg=self.segment, noverlap=self.segment // 2, detrend=False, axis=-1)
        if self.cepstra:
            bw = self.rate / self.segment
            edges = np.geomspace(floor3(2 * bw), floor3(self.rate / 2), 33)
            band = np.searchsorted(edges, f, side="right") - 1
            band[f == edges[-1]] = 31
            member = (band[:, None] == np.arange(32)[None, :]).astype(float)
            c = dct(np.log10(np.maximum(p @ member, 1e-300)), type=2, norm="ortho", axis=-1)[:, :self.cepstra]
            rows = c[:, 1:] if self.drop_level else c
        else:
            kept = p[:, 1:self.segment // 2 + 1]
            rows = np.log10(np.maximum(kept, 1e-300)) if self.spectrum == "log-welch" else kept
        return rows, [len(spans)] * len(X)

    def fit(self, X, y):
        rows, counts = self._rows(X)
        labels = np.repeat(y, counts)
        self.scaler_ = StandardScaler().fit(rows) if self.standardize else None
        if self.scaler_ is not None:
            rows = self.scaler_.transform(rows)
        self.knn_ = KNeighborsClassifier(n_neighbors=min(self.k, len(rows)), metric=self.metric,
                                         weights=self.weights, algorithm="brute").fit(rows, labels)
        self.classes_ = np.unique(y)
        return self

    def predict(self, X):
        rows, counts = self._rows(X)
        if self.scaler_ is not None:
            rows = self.scaler_.transform(rows)
        votes = self.knn_.predict(rows)
        out, at = [], 0
        for n in counts:
            labels, seen = np.unique(votes[at:at + n], return_counts=True)
            out.append(labels[np.argmax(seen)])
            at += n
        return np.array(out)


def feature_grid(scored):
    """hapticlab's feature settings (its --json) as parameter values."""
    out = []
    for d in scored:
        d = dict(d)
        windows = None
        if d["windows"] != "none":
            length, hop = d["windows"].split(" every ")
            windows = (float(length), float(hop))
        cep = 0 if d["cepstra"] == "none" else int(d["cepstra"].split()[0])
        out.append(dict(spectrum=[d["spectrum"]], taper=[d["taper"]], segment=[int(d["welch_segment"])],
                        cepstra=[cep], drop_level=[d["drop_level"] == "true"], windows=[windows]))
    return out


def main():
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("dir", type=Path)
    p.add_argument("-p", "--profile", type=Path, required=True)
    p.add_argument("--hapticlab", default="target/release/hapticlab")
    p.add_argument("--budget", type=int, default=96)
    p.add_argument("--seed", type=int, default=0)
    p.add_argument("--jobs", type=int, default=-1)
    p.add_argument("--cached", action="store_true",
                   help="make each feature setting's features once, before the search (Welch fits nothing)")
    p.add_argument("--settings", type=Path, help="a saved `hapticlab tune --json`: run scikit-learn alone")
    a = p.parse_args()

    if a.settings is not None:
        report, ours = json.loads(a.settings.read_text()), None
    else:
        with tempfile.TemporaryDirectory() as tmp:
            start = time.perf_counter()
            run = subprocess.run([a.hapticlab, "tune", str(a.dir), "-p", str(a.profile), "--out",
                                  str(Path(tmp) / "tuned.toml"), "--budget", str(a.budget),
                                  "--seed", str(a.seed), "--json"], capture_output=True, text=True, check=True)
            ours = time.perf_counter() - start
        report = json.loads(run.stdout)

    profile = tomllib.loads(a.profile.read_text())
    an, ev = profile["analysis"], profile["evaluation"]
    if ev.get("method", "holdout") != "holdout" or ev.get("shuffle_seed") is not None:
        raise SystemExit("tune_reference.py: only an unshuffled holdout [evaluation] is supported")
    start = time.perf_counter()
    files = sorted(f for f in a.dir.rglob("*.csv"))
    recs = [read_recording(f) for f in files]
    rate = float(recs[0][0]["rate_hz"])
    X = [cols[an["channel"]] for _, cols in recs]
    y = np.array([m.get("label", f.parent.name) for (m, _), f in zip(recs, files)])
    train, test = [], []
    for label in sorted(set(y)):
        idx = [i for i in range(len(y)) if y[i] == label]
        first = ev["train_per_class"] + ev.get("gap_per_class", 0)
        train += idx[:ev["train_per_class"]]
        test += idx[first:first + ev["test_per_class"]]
    classifier = dict(k=[1, 3, 5, 9], metric=["euclidean", "manhattan", "cosine"],
                      weights=["uniform", "distance"], standardize=[False, True])
    grid = [{**f, **classifier} for f in feature_grid(report["feature_settings_scored"])]
    settings = sum(int(np.prod([len(v) for v in g.values()])) for g in grid)
    base = WelchKnn(rate=rate, window=tuple(an["window"]))
    if a.cached:
        table = {}
        for g in grid:
            one = base.set_params(**{k: v[0] for k, v in g.items() if k not in classifier})
            rows, counts = one._windows_of(X)
            table[one._key()] = rows.reshape(len(X), counts[0], -1)
        base = WelchKnn(rate=rate, window=tuple(an["window"]), table=table)
        X = np.arange(len(X)).reshape(-1, 1)
    search = GridSearchCV(base, grid, cv=StratifiedKFold(5, shuffle=True, random_state=a.seed), n_jobs=a.jobs)
    Xtr = [X[i] for i in train]
    search.fit(Xtr, y[train])
    outer = float(np.mean(search.predict([X[i] for i in test]) == y[test]))
    theirs = time.perf_counter() - start

    n = report["configurations"]
    print(f"scikit-learn:     {settings} settings in {theirs:.2f} s ({theirs / settings * 1000:.1f} ms per setting), "
          f"outer {outer * 100:.1f} %, inner best {search.best_score_ * 100:.1f} %, chose {search.best_params_}")
    if ours is None:
        return
    print(f"hapticlab tune:   {n} settings in {ours:.2f} s ({ours / n * 1000:.1f} ms per setting), "
          f"outer {report['outer_accuracy'] * 100:.1f} %, inner best {report['chosen']['inner_accuracy'] * 100:.1f} %")
    print(f"ratio (time per setting, scikit-learn / hapticlab): {theirs / settings / (ours / n):.1f}x")


if __name__ == "__main__":
    main()
