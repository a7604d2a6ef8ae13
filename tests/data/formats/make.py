#!/usr/bin/env python3
"""Writes the small files of this folder (needs numpy and scipy); run here.
Each holds 300 samples of a 50 Hz sine at 1 kHz, rounded to 3 decimals."""
import numpy as np
import scipy.io as sio

t = np.arange(300) / 1000.0
x = np.round(np.sin(2 * np.pi * 50 * t) * 1000) / 1000
np.save("one.npy", x)  # 1-D float64
np.save("two.npy", np.stack([np.arange(300, dtype=np.int16), -np.arange(300, dtype=np.int16)], axis=1))
np.savez_compressed("arrays.npz", acc=x, force=np.arange(300, dtype=np.float32) * 0.5, fs=1000.0)
sio.savemat("signal.mat", {"acc": x, "force": np.arange(300, dtype=np.int16)[:, None], "fs": 1000.0})
sio.savemat("compressed.mat", {"acc": x, "xyz": np.stack([x, 2 * x, 3 * x], axis=1)}, do_compression=True)
# A v7.3 header and the HDF5 signature at byte 512, as MATLAB writes them.
hdr = b"MATLAB 7.3 MAT-file, Platform: GLNXA64, Created on: Mon Jan  1 00:00:00 2024 HDF5 schema 1.00 ."
hdr = hdr.ljust(116, b" ") + b"\0" * 8 + b"\x00\x02" + b"IM"
open("v73.mat", "wb").write(hdr.ljust(512, b"\0") + b"\x89HDF\r\n\x1a\n" + b"\0" * 24)
open("lmt.txt", "w").write("\n".join("%g" % v for v in x) + "\n")
open("multi.txt", "w").write("% three axes\n" + "\n".join("%g %g\t%g" % (a, 2 * a, 3 * a) for a in x) + "\n")
