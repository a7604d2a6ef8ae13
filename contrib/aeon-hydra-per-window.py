"""aeon's Hydra transform per window on one thread, beside
`cargo run --release --example hydra_window_cpu -- POINTS` (hapticlab's
`features = "hydra"`): 100 windows of a noisy sine, one channel, after a
fit and an untimed warm-up; the best of three batches, as CPU per window.
aeon and torch in their own environment (see contrib/aeon-peer.py), never
in CI.

    /tmp/aeonenv/bin/python contrib/aeon-hydra-per-window.py POINTS
"""
import resource
import sys

import numpy as np
import torch
from aeon.transformations.collection.convolution_based import HydraTransformer


def cpu():
    r = resource.getrusage(resource.RUSAGE_SELF)
    return r.ru_utime + r.ru_stime


def main():
    if len(sys.argv) != 2 or not sys.argv[1].isdigit():
        print("usage: aeon-hydra-per-window.py POINTS (a whole number)", file=sys.stderr)
        sys.exit(2)
    n = int(sys.argv[1])
    torch.set_num_threads(1)
    rng = np.random.default_rng(0)
    x = np.sin(np.arange(n) * 0.3)[None, None, :] + rng.standard_normal((100, 1, n))
    t = HydraTransformer(random_state=0, n_jobs=1)
    t.fit(x[:10])
    t.transform(x[:2])
    times = []
    for _ in range(3):
        c0 = cpu()
        f = t.transform(x)
        times.append((cpu() - c0) / len(x))
    print(f"aeon HydraTransformer, {n} points: {min(times) * 1e3:.3f} ms CPU a window "
          f"(batch of 100, best of 3), {f.shape[1]} features")


if __name__ == "__main__":
    main()
