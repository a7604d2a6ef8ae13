#!/usr/bin/env python3
"""The ten-line script a researcher writes, as the peer of `profile new`'s
first profile (issue 31): scipy's `welch` with its defaults on each
recording's first signal column, its natural log, 1-NN by Euclidean
distance, the time split (each label's first NTRAIN recordings in file
order train, the next NTEST test, after GAP left out). Prints the accuracy
in per cent. Needs numpy, scipy and pandas.

    contrib/welch_1nn.py REC_DIR RATE_HZ NTRAIN NTEST [GAP]
"""
import glob, os, sys

import numpy as np
import pandas as pd
from scipy.signal import welch

d, fs, ntrain, ntest = sys.argv[1], float(sys.argv[2]), int(sys.argv[3]), int(sys.argv[4])
gap = int(sys.argv[5]) if len(sys.argv) > 5 else 0
X, y, tr = [], [], []
for lab in sorted(os.listdir(d)):
    if not os.path.isdir(f"{d}/{lab}"):
        continue
    files = sorted(glob.glob(f"{d}/{lab}/*.csv*"))
    for i, f in enumerate(files[: ntrain + gap + ntest]):
        if ntrain <= i < ntrain + gap:
            continue
        x = pd.read_csv(f, comment="#").iloc[:, 1].to_numpy(float)
        X.append(np.log(welch(x, fs)[1][1:] + 1e-300)); y.append(lab); tr.append(i < ntrain)
X, y, tr = np.array(X), np.array(y), np.array(tr)
D = ((X[~tr][:, None, :] - X[tr][None, :, :]) ** 2).sum(-1)
pred = y[tr][D.argmin(1)]
print(round(100 * (pred == y[~tr]).mean(), 1))
