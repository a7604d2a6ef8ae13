#!/usr/bin/env python3
"""Writes the seeds of import_text, import_numpy and import_mat (standard
library only; run here): the shipped format samples of tests/data/formats and
small hostile files made byte by byte (a decompression bomb's header, sizes
that claim more than the file holds, a header that lies, decimal commas)."""
import os, struct, zlib, shutil

F = "../../tests/data/formats"
for d in ("import_text", "import_numpy", "import_mat"):
    os.makedirs(d, exist_ok=True)

def w(path, b):
    open(path, "wb").write(b if isinstance(b, bytes) else b.encode())

# Headerless text.
shutil.copy(f"{F}/lmt.txt", "import_text/lmt.txt")
shutil.copy(f"{F}/multi.txt", "import_text/multi.txt")
w("import_text/cr-only.txt", "0.5\r0.25\r-1\r" * 10)
w("import_text/decimal-comma.txt", "0,099;-0,099\n0,1;0,2\n")
w("import_text/empty-middle.txt", "1,2,3\n1,,-1\n")
w("import_text/beyond-2-53.txt", "1\n9007199254740993\n")
w("import_text/bom.txt", "\ufeff0.5\n0.25\n0.125\n")

# NumPy: the first byte picks .npy (even) or .npz (odd).
def npy(header, data):
    h = header.encode()
    while (10 + len(h) + 1) % 64:
        h += b" "
    h += b"\n"
    return b"\x93NUMPY\x01\x00" + struct.pack("<H", len(h)) + h + data

def zipfile(entries):
    b, central = b"", b""
    for name, method, data, full in entries:
        local = len(b)
        n = name.encode()
        b += b"PK\x03\x04" + struct.pack("<HHH", 20, 0, method) + b"\0" * 8
        b += struct.pack("<IIHH", len(data), full, len(n), 0) + n + data
        central += b"PK\x01\x02" + struct.pack("<HHHH", 20, 20, 0, method) + b"\0" * 8
        central += struct.pack("<IIH", len(data), full, len(n)) + b"\0" * 12
        central += struct.pack("<I", local) + n
    return b + central + b"PK\x05\x06" + b"\0" * 4 + struct.pack(
        "<HHII", len(entries), len(entries), len(central), len(b)) + b"\0\0"

def deflate(data):
    c = zlib.compressobj(9, zlib.DEFLATED, -15)
    return c.compress(data) + c.flush()

ok = npy("{'descr': '<f8', 'fortran_order': False, 'shape': (3,), }", struct.pack("<3d", 1, 2, 3))
w("import_numpy/one.npy", b"\0" + open(f"{F}/one.npy", "rb").read())
w("import_numpy/two.npy", b"\0" + open(f"{F}/two.npy", "rb").read())
w("import_numpy/arrays.npz", b"\1" + open(f"{F}/arrays.npz", "rb").read())
w("import_numpy/small.npy", b"\0" + ok)
w("import_numpy/lying-key.npy", b"\0" + npy(
    "{'descr': '<f8', 'fortran_order': False, 'note': \"'shape': (1,)\", 'shape': (3,), }",
    struct.pack("<3d", 1, 2, 3)))
w("import_numpy/u64-max.npy", b"\0" + npy(
    "{'descr': '<u8', 'fortran_order': False, 'shape': (2,), }", struct.pack("<2Q", 1, 2**64 - 1)))
w("import_numpy/claims-4gb.npz", b"\1" + zipfile([(f"{c}.npy", 8, deflate(ok), 0xFFFFFFF0) for c in "abc"]))
w("import_numpy/stored.npz", b"\1" + zipfile([("acc.npy", 0, ok, len(ok))]))
w("import_numpy/deflated.npz", b"\1" + zipfile([("acc.npy", 8, deflate(ok), len(ok))]))

# MATLAB level 5.
def header(big=False):
    h = b"MATLAB 5.0 MAT-file, made by make-readers.py".ljust(124, b" ")
    return h + (b"\x01\x00MI" if big else b"\x00\x01IM")

def element(kind, data):
    e = struct.pack("<II", kind, len(data)) + data
    return e + b"\0" * (-len(e) % 8)

def variable(name, dims, values):
    m = element(6, bytes([6, 0, 0, 0, 0, 0, 0, 0]))
    m += element(12, struct.pack(f"<{len(dims)}q", *dims))
    m += element(1, name.encode())
    m += element(9, struct.pack(f"<{len(values)}d", *values))
    return element(14, m)

shutil.copy(f"{F}/signal.mat", "import_mat/signal.mat")
shutil.copy(f"{F}/compressed.mat", "import_mat/compressed.mat")
shutil.copy(f"{F}/v73.mat", "import_mat/v73.mat")
w("import_mat/small.mat", header() + variable("x", [3, 1], [1, 2, 3]))
w("import_mat/fs-2000.mat", header() + variable("x", [3, 1], [1, 2, 3]) + variable("fs", [1, 1], [2000]))
w("import_mat/dims-2-32.mat", header() + variable("x", [2**32, 2**32], []))
w("import_mat/swapped.mat", header(True) + variable("x", [3, 1], [1, 2, 3]))
packed = zlib.compress(variable("x", [3, 1], [1, 2, 3]), 9)
w("import_mat/zlib.mat", header() + struct.pack("<II", 15, len(packed)) + packed)
