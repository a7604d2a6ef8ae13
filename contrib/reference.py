#!/usr/bin/env python3
"""The script a researcher writes for the thesis's analysis, in numpy, pandas
and scikit-learn: hapticlab's peer in the README's speed figures, and a check
of its features and predictions. Not run by CI (it needs numpy, pandas and
scikit-learn: `pip install numpy pandas scikit-learn`).

    contrib/reference.py DIR [--profile profiles/thesis.toml] [--folds K] [--features OUT.csv]

Reads every recording under DIR (`DIR/<label>/*.csv[.gz]`, hapticlab's format
v1: pandas reads it with comment='#'), skips incomplete ones (no
`# end samples` trailer), and computes each scan's features the way
`src/analysis.rs` documents them: the signal channel along the axis, measured
from the first sample in the direction of travel; each sample to its nearest
grid point in the window; each bin replaced by its centroid; the grid
interpolated between centroids (extrapolated from the two nearest beyond the
ends); the mean removed (detrend = "mean") or not ("none"); |DFT| of the
chosen bins (spectrum = "magnitude"). Other analysis options are refused.

Then k-NN (scikit-learn, Euclidean, majority vote) on the profile's holdout
split: per class, the first train_per_class recordings in file-name order
train and the next test_per_class test; or stratified K-fold with --folds.
Votes tied in count go to the class with the nearest neighbour among the tied
ones in hapticlab; scikit-learn takes the first label in sorted order, so on
a tie the two may differ.
"""
import argparse
import gzip
import io
import sys
import time
import tomllib
from pathlib import Path

import numpy as np
import pandas as pd
from sklearn.model_selection import StratifiedKFold
from sklearn.neighbors import KNeighborsClassifier


def read(path):
    """The samples of a complete recording, or None for an incomplete one."""
    raw = gzip.open(path, "rb").read() if path.suffix == ".gz" else path.read_bytes()
    if b"# end samples" not in raw[-200:]:
        return None
    return pd.read_csv(io.BytesIO(raw), comment="#")


def features(df, a):
    axis = df[a["axis"]].to_numpy()
    signal = df[a["channel"]].to_numpy()
    sign = 1.0 if axis[-1] >= axis[0] else -1.0
    d = sign * (axis - axis[0])
    lo, hi = a["window"]
    h = a["spacing"]
    n = int(round((hi - lo) / h)) + 1
    i = np.rint((d - lo) / h).astype(np.int64)
    keep = (i >= 0) & (i < n)
    i, d, s = i[keep], d[keep], signal[keep]
    count = np.bincount(i, minlength=n)
    full = count > 0
    cd = np.bincount(i, weights=d, minlength=n)[full] / count[full]
    cs = np.bincount(i, weights=s, minlength=n)[full] / count[full]
    grid = lo + h * np.arange(n)
    y = np.interp(grid, cd, cs)
    # np.interp holds the end values: extrapolate linearly instead.
    if len(cd) >= 2:
        for ends, (a0, a1) in ((grid < cd[0], (0, 1)), (grid > cd[-1], (-2, -1))):
            slope = (cs[a1] - cs[a0]) / (cd[a1] - cd[a0])
            y[ends] = cs[a0] + slope * (grid[ends] - cd[a0])
    if a.get("detrend", "mean") == "mean":
        y = y - y.mean()
    b0, b1 = a["bins"]
    return np.abs(np.fft.fft(y))[b0 : b1 + 1]


def main():
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("dir", type=Path)
    p.add_argument("--profile", type=Path, default=Path(__file__).parent.parent / "profiles/thesis.toml")
    p.add_argument("--folds", type=int, help="stratified K-fold instead of the profile's holdout split")
    p.add_argument("--features", type=Path, help="write file,label,f1..fN here")
    args = p.parse_args()
    profile = tomllib.loads(args.profile.read_text())
    a = profile["analysis"]
    for key, allowed in (("spectrum", {"magnitude"}), ("detrend", {"mean", "none"})):
        if a.get(key, "magnitude" if key == "spectrum" else "mean") not in allowed:
            sys.exit(f"{args.profile}: analysis.{key} = {a[key]!r} is not supported here")
    if "channels" in a or "band" in a or a.get("taper", "none") != "none":
        sys.exit(f"{args.profile}: only channel, axis, window, spacing, detrend and bins are supported here")
    k = profile["classifier"]["k"]
    started = time.perf_counter()
    files = sorted(f for f in args.dir.rglob("*") if f.name.endswith((".csv", ".csv.gz")))
    names, labels, rows = [], [], []
    for f in files:
        df = read(f)
        if df is None:
            print(f"skipped (incomplete): {f}", file=sys.stderr)
            continue
        names.append(str(f))
        labels.append(f.parent.name)
        rows.append(features(df, a))
    X, y = np.array(rows), np.array(labels)
    if args.features:
        pd.DataFrame(X, columns=[f"f{j + 1}" for j in range(X.shape[1])]).assign(
            file=names, label=labels
        )[["file", "label"] + [f"f{j + 1}" for j in range(X.shape[1])]].to_csv(args.features, index=False)
    if args.folds:
        splits = StratifiedKFold(n_splits=args.folds, shuffle=True, random_state=0).split(X, y)
    else:
        ev = profile["evaluation"]
        ntr, nte = ev["train_per_class"], ev["test_per_class"]
        train, test = [], []
        for label in sorted(set(labels)):
            idx = [j for j, l in enumerate(labels) if l == label]
            train += idx[:ntr]
            test += idx[ntr : ntr + nte]
        splits = [(np.array(train), np.array(test))]
    right = total = 0
    for tr, te in splits:
        knn = KNeighborsClassifier(n_neighbors=k).fit(X[tr], y[tr])
        right += int((knn.predict(X[te]) == y[te]).sum())
        total += len(te)
    elapsed = time.perf_counter() - started
    print(f"accuracy: {right}/{total} ({100.0 * right / total:.1f} %) over {len(names)} recordings in {elapsed:.2f} s")


if __name__ == "__main__":
    main()
