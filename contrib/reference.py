#!/usr/bin/env python3
"""The script a researcher writes for a profile's analysis and classifier, in
numpy, scipy, pandas and scikit-learn: hapticlab's peer in the README's speed
figures, and a check of its features and predictions. Not run by CI (it
needs `pip install numpy scipy pandas scikit-learn`).

    contrib/reference.py DIR [--profile profiles/thesis.toml] [--folds K]
                             [--method holdout|k-fold|leave-one-out] [--features OUT.csv]

Reads every recording under DIR (`DIR/<label>/*.csv[.gz]`, format v1; pandas
reads it with comment='#') in file-name order, skips incomplete ones (no
`# end samples` trailer); the label is the `label` metadata, else the folder.

Features, as `src/analysis.rs` documents them, for each window (the profile's
`window`, or each sub-window of `windows = { length, hop }`):
- resampling: the axis measured from the first sample in the direction of
  travel; each sample to its nearest grid point (where that leaves grid
  points empty, samples within TIE spacings of a bin's edge go to the bin
  above if that fills more); each non-empty grid point
  replaced by its bin's centroid; the grid interpolated between centroids,
  extrapolated linearly beyond the first and last;
- detrend none / mean / linear (scipy.signal.detrend) over the window;
- spectrum: magnitude |DFT| of the tapered window (none or periodic Hann);
  power and log-power with scipy.signal.periodogram; welch and log-welch with
  scipy.signal.welch (segment mean removed unless detrend = "none"); power is
  scipy's density with fs = 1, i.e. 2|X_k|^2 / sum(w^2) off DC and Nyquist;
  log = log10(max(P, 1e-300));
- kept: bins [a, b], or `band` [lo, hi] (Hz on t_s, cycles/mm on *_m), or
  `bands` (band energies, log10 for log spectra) and `cepstra` (their DCT-II,
  orthonormal) as issue 13's spec says;
- channels: `channel`, then `channels`, concatenated.

Classifier: z-score with the training examples' mean and population standard
deviation when `standardize` (a constant feature keeps scale 1); k nearest by
the metric (euclidean, manhattan, cosine = 1 - cos), ties in distance kept in
training order; votes uniform or 1/distance (an exact match outvotes the
rest); a tie in votes goes to the smaller summed distance, then the label
that sorts first (hapticlab's rule). With windows, every training window is
an example; a recording's class is the majority of its windows' predictions,
a tie going to the class with more neighbour votes summed over the windows,
then to the first label.

Evaluation: holdout (per class, the first train_per_class recordings in
file-name order train, the next gap_per_class are left out, the next
test_per_class test), leave-one-out (each recording against all others), or
stratified k-fold (scikit-learn's folds).

Where hapticlab may differ:
- features agree to float rounding (about 1e-12 relative; `features --out`
  prints 10 significant digits, so a comparison of the files shows up to
  1e-9); a sample exactly half-way between grid points, or a bin frequency
  exactly on a band edge (edges from np.geomspace / np.linspace), may fall
  on the other side in the last bit;
- k-fold: hapticlab deals its folds with its own seeded shuffle, so the folds
  and the accuracy differ (the mean over folds agrees within the spread);
  holdout and leave-one-out are the same splits;
- neighbours at nearly equal distance may come out in another order;
- hapticlab lowers k where a class has fewer than k training examples, and
  chooses k = "auto" by inner cross-validation; neither is done here (this
  script refuses k = "auto" and warns when k exceeds a class's examples);
- shuffle_seed and group_by are refused.
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
from scipy import fft, signal
from sklearn.model_selection import StratifiedKFold

FLOOR = 1e-300
TIE = 1e-6  # a millionth of a spacing: a sample this close to a bin's edge is on it


def read(path):
    """(samples, label) of a complete recording, or None for an incomplete one."""
    raw = gzip.open(path, "rb").read() if path.suffix == ".gz" else path.read_bytes()
    if b"# end samples" not in raw[-200:]:
        return None
    label = path.parent.name
    for line in raw[:4096].decode(errors="replace").splitlines():
        if line.startswith("# label"):
            label = line.split("=", 1)[1].strip().strip('"')
    return pd.read_csv(io.BytesIO(raw), comment="#"), label


def points(lo, hi, h):
    return int(np.floor((hi - lo) / h + 1e-6)) + 1


def bins(u, n, half):
    """Each grid coordinate's bin (or -1): [i - half, i + 1 - half) is bin i."""
    i = np.floor(u + half).astype(np.int64)
    return np.where((u >= -half) & (u < n - half) & (i < n), i, -1)


def resample(d, s, lo, h, n):
    """The signal on the grid lo + i h, i < n (see src/analysis.rs)."""
    u = (d - lo) * (1.0 / h)  # as hapticlab rounds it: samples half-way between grid points go alike
    i = bins(u, n, 0.5)
    # Where rounding leaves bins empty, samples within TIE spacings of an
    # edge go to the bin above if that fills more (engine/src/analysis/resample.rs).
    filled = np.unique(i[i >= 0]).size
    if filled < n:
        up = bins(u, n, 0.5 + TIE)
        if np.unique(up[up >= 0]).size > filled:
            i = up
    u, s, i = u[i >= 0], s[i >= 0], i[i >= 0]
    count = np.bincount(i, minlength=n)
    full = count > 0
    if full.sum() < 2 or (n - full.sum()) * 4 > n:
        raise ValueError(f"the window at {lo} has {full.sum()} of {n} grid points with samples")
    cu = np.bincount(i, weights=u, minlength=n)[full] / count[full]
    cs = np.bincount(i, weights=s, minlength=n)[full] / count[full]
    g = np.arange(n, dtype=float)
    # Segment m joins centroids m and m + 1; the end segments extrapolate.
    m = np.clip(np.searchsorted(cu, g, side="left") - 1, 0, len(cu) - 2)
    du = cu[m + 1] - cu[m]
    safe = np.where(du > 0, du, 1.0)
    return np.where(du > 0, cs[m] + (g - cu[m]) * (cs[m + 1] - cs[m]) / safe, 0.5 * (cs[m] + cs[m + 1]))


def spectrum(x, a, n):
    """The one-sided spectrum of the window x (power for the log kinds) and
    the bin width (in Hz, or cycles/mm on a position axis)."""
    kind, taper = a.get("spectrum", "magnitude"), a.get("taper", "none")
    window = "hann" if taper == "hann" else "boxcar"
    if kind in ("welch", "log-welch"):
        m = a.get("welch_segment", max(n // 4, 4))
        step = max(int(np.floor(m * (1 - a.get("welch_overlap", 0.5)) + 0.5)), 1)
        detrend = False if a.get("detrend", "mean") == "none" else "constant"
        _, p = signal.welch(x, 1.0, window=window, nperseg=m, noverlap=m - step, detrend=detrend)
    elif kind == "magnitude":
        m = n
        p = np.abs(np.fft.rfft(x * signal.get_window(window, n)))
    else:
        m = n
        _, p = signal.periodogram(x, 1.0, window=window, detrend=False)
    return p, 1.0 / (m * a["spacing"]) / (1000.0 if a["axis"].endswith("_m") else 1.0)


def kept(p, width, a):
    """The features of one channel's spectrum p (bin k at k x width)."""
    kind = a.get("spectrum", "magnitude")
    if "bands" in a:
        b = a["bands"]
        N, f0, f1 = b["count"], b["from"], b["to"]
        edges = np.geomspace(f0, f1, N + 1) if b.get("scale", "log") == "log" else np.linspace(f0, f1, N + 1)
        f = np.arange(len(p)) * width
        band = np.searchsorted(edges, f, side="right") - 1
        band[f == edges[-1]] = N - 1
        inside = (band >= 0) & (band < N)
        if np.bincount(band[inside], minlength=N).min() == 0:
            i = int(np.argmin(np.bincount(band[inside], minlength=N)))
            raise ValueError(f"band {i + 1} [{edges[i]:g}, {edges[i + 1]:g}) holds no bin ({width:g} apart): raise `from`, use fewer bands or longer segments")
        E = np.bincount(band[inside], weights=p[inside], minlength=N)
        L = np.log10(np.maximum(E, FLOOR))
        if "cepstra" in a:
            c = fft.dct(L, type=2, norm="ortho")[: a["cepstra"]]
            return c[1:] if a.get("drop_level", False) else c
        return L if kind.startswith("log") else E
    if kind.startswith("log"):
        p = np.log10(np.maximum(p, FLOOR))
    if "band" in a:
        lo, hi = a["band"]
        first = max(int(np.ceil(lo / width - 1e-9)), 0)
        last = min(int(np.floor(hi / width + 1e-9)), len(p) - 1)
        return p[first : last + 1]
    b0, b1 = a.get("bins", [0, 0])
    return p[b0 : b1 + 1]


def features(df, a):
    """One feature row per window of the recording df."""
    axis = df[a["axis"]].to_numpy(float)
    sign = 1.0 if axis[-1] >= axis[0] else -1.0
    d = sign * (axis - axis[0])
    w0, w1 = a["window"]
    h = a["spacing"]
    if "windows" in a:
        L, H = a["windows"]["length"], a["windows"]["hop"]
        starts = [w0 + j * H for j in range(int((w1 - w0) / H) + 2) if w0 + j * H + L <= w1 + 1e-9 * L]
    else:
        starts, L = [w0], w1 - w0
    rows = []
    for lo in starts:
        n = points(lo, lo + L, h)
        row = []
        for c in [a["channel"]] + a.get("channels", []):
            y = resample(d, df[c].to_numpy(float), lo, h, n)
            detrend = a.get("detrend", "mean")
            if detrend != "none":
                y = signal.detrend(y, type="constant" if detrend == "mean" else "linear")
            row.append(kept(*spectrum(y, a, n), a))
        rows.append(np.concatenate(row))
    return rows


def distances(metric, A, q):
    if metric == "manhattan":
        return np.abs(A - q).sum(1)
    if metric == "cosine":
        norms = np.linalg.norm(A, axis=1) * np.linalg.norm(q)
        return np.where(norms > 0, 1.0 - A @ q / np.where(norms > 0, norms, 1.0), 1.0)
    return np.sqrt(((A - q) ** 2).sum(1))


def knn(Xtr, ytr, q, c, classes):
    """Per-class votes and summed distances of q's k nearest, and the winner."""
    d = distances(c.get("metric", "euclidean"), Xtr, q)
    near = np.argsort(d, kind="stable")[: c["k"]]
    dn, yn = d[near], ytr[near]
    if c.get("weights", "uniform") == "uniform":
        w = np.ones(len(near))
    elif (dn == 0).any():
        w = (dn == 0).astype(float)
    else:
        w = 1.0 / dn
    votes = np.array([w[yn == l].sum() for l in classes])
    summed = np.array([dn[yn == l].sum() if (yn == l).any() else np.inf for l in classes])
    return votes, classes[np.lexsort((np.arange(len(classes)), summed, -votes))[0]]


def predict(X, rec, y, train, test, c):
    """The class of each test recording (windows vote)."""
    classes = np.array(sorted(set(y)))
    tr = np.isin(rec, train)
    Xtr, ytr = X[tr], y[rec[tr]]
    if c.get("standardize", False):
        mu, sd = Xtr.mean(0), Xtr.std(0)
        sd[sd == 0] = 1.0
        Xtr = (Xtr - mu) / sd
    out = []
    for r in test:
        Q = X[rec == r]
        if c.get("standardize", False):
            Q = (Q - mu) / sd
        results = [knn(Xtr, ytr, q, c, classes) for q in Q]
        wins = np.zeros(len(classes))
        for _, w in results:
            wins[classes == w] += 1
        votes = sum(v for v, _ in results)
        out.append(classes[np.lexsort((np.arange(len(classes)), -votes, -wins))[0]])
    return np.array(out)


def main():
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("dir", type=Path)
    p.add_argument("--profile", type=Path, default=Path(__file__).parent.parent / "profiles/thesis.toml")
    p.add_argument("--method", choices=["holdout", "k-fold", "leave-one-out"], help="default: the profile's")
    p.add_argument("--folds", type=int, help="stratified K-fold with K folds")
    p.add_argument("--features", type=Path, help="write file,label[,window],f1..fN here")
    args = p.parse_args()
    profile = tomllib.loads(args.profile.read_text())
    a, c, ev = profile["analysis"], profile["classifier"], profile.get("evaluation", {})
    if "bands" in a and ("band" in a or a.get("spectrum", "magnitude") == "magnitude" or "bins" in a):
        sys.exit(f"{args.profile}: bands takes a power spectrum and replaces bins and band")
    if c["k"] == "auto" or "shuffle_seed" in ev or "group_by" in ev:
        sys.exit(f"{args.profile}: k = \"auto\", shuffle_seed and group_by are not supported here")
    started = time.perf_counter()
    files = sorted(f for f in args.dir.rglob("*") if f.name.endswith((".csv", ".csv.gz")) and not f.name.startswith("."))
    names, labels, X, rec = [], [], [], []
    for f in files:
        got = read(f)
        if got is None:
            print(f"skipped (incomplete): {f}", file=sys.stderr)
            continue
        try:
            rows = features(got[0], a)
        except ValueError as e:
            sys.exit(f"{f}: {e}")
        rec += [len(names)] * len(rows)
        names.append(str(f))
        labels.append(got[1])
        X += rows
    X, y, rec = np.array(X), np.array(labels), np.array(rec)
    if args.features:
        cols = [f"f{j + 1}" for j in range(X.shape[1])]
        out = pd.DataFrame(X, columns=cols).assign(file=[names[r] for r in rec], label=y[rec])
        if "windows" in a:
            out["window"] = np.concatenate([np.arange((rec == r).sum()) for r in range(len(names))])
            cols = ["window"] + cols
        out[["file", "label"] + cols].to_csv(args.features, index=False, float_format="%.9e")
    method = args.method or ("k-fold" if args.folds else ev.get("method", "holdout"))
    idx = np.arange(len(names))
    if method == "k-fold":
        folds = args.folds or ev.get("folds", 10)
        splits = StratifiedKFold(n_splits=folds, shuffle=True, random_state=0).split(idx, y)
        how = f"{folds}-fold (scikit-learn's stratified folds, not hapticlab's)"
    elif method == "leave-one-out":
        splits = [(idx[idx != j], idx[j : j + 1]) for j in idx]
        how = "leave-one-out"
    else:
        ntr, nte = ev["train_per_class"], ev["test_per_class"]
        gap = ev.get("gap_per_class", 0)
        train, test = [], []
        for label in sorted(set(labels)):
            mine = idx[y == label]
            train += list(mine[:ntr])
            test += list(mine[ntr + gap : ntr + gap + nte])
        splits = [(np.array(train), np.array(test))]
        left = f", the next {gap} left out" if gap else ""
        how = f"holdout, the first {ntr} of each label train{left} and the next {nte} test"
    right = total = 0
    for tr, te in splits:
        smallest = min(np.isin(rec, tr[y[tr] == l]).sum() for l in set(y[tr]))
        if c["k"] > smallest:
            print(f"warning: k = {c['k']} exceeds a class's {smallest} training examples", file=sys.stderr)
        right += int((predict(X, rec, y, tr, te, c) == y[te]).sum())
        total += len(te)
    elapsed = time.perf_counter() - started
    print(f"accuracy: {right}/{total} ({100.0 * right / total:.1f} %) over {len(names)} recordings, {how}, in {elapsed:.2f} s")


if __name__ == "__main__":
    main()
