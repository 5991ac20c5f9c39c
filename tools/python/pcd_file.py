# SPDX-License-Identifier: Apache-2.0
"""Binary PCD files (as rsu-sim and rsu-decode write them, and nebula's reference decodes) read in pure
Python, shared by the tests that check those files.

  read_binary_pcd(path) -> (field names, points as dicts of field -> value)
"""
import struct

_CODES = {("F", 4): "f", ("F", 8): "d", ("U", 1): "B", ("U", 2): "H", ("U", 4): "I", ("I", 1): "b",
          ("I", 2): "h", ("I", 4): "i"}


def read_binary_pcd(path):
    with open(path, "rb") as f:
        blob = f.read()
    header_end = blob.index(b"DATA binary\n") + len(b"DATA binary\n")
    header = {}
    for line in blob[:header_end].decode().splitlines():
        words = line.split()
        if words and not words[0].startswith("#"):
            header[words[0]] = words[1:]
    names, sizes, types = header["FIELDS"], [int(s) for s in header["SIZE"]], header["TYPE"]
    n = int(header["POINTS"][0])
    fmt = "<" + "".join(_CODES[(t, s)] for t, s in zip(types, sizes))
    step = struct.calcsize(fmt)
    data = blob[header_end:header_end + n * step]
    return names, [dict(zip(names, struct.unpack_from(fmt, data, i * step))) for i in range(n)]
