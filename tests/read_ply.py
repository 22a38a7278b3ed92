#!/usr/bin/python3
"""Reads a binary PLY of `nbv export` (x y z float, red green blue uchar; faces as a list of
uchar count and int indices) and prints its counts and colours as JSON, for report_test.sh.

Usage: read_ply.py FILE
"""
import json
import sys

import numpy as np


def read(path):
    with open(path, "rb") as f:
        data = f.read()
    end = data.index(b"end_header\n") + len(b"end_header\n")
    header = data[:end].decode("ascii").splitlines()
    assert header[0] == "ply" and header[1] == "format binary_little_endian 1.0", header[:2]
    counts = {}
    for line in header:
        if line.startswith("element "):
            _, name, count = line.split()
            counts[name] = int(count)
    vertex = np.dtype([("x", "<f4"), ("y", "<f4"), ("z", "<f4"), ("r", "u1"), ("g", "u1"), ("b", "u1")])
    vertices = np.frombuffer(data, vertex, counts.get("vertex", 0), end)
    offset = end + vertices.nbytes
    faces = np.frombuffer(data, np.dtype([("n", "u1"), ("i", "<i4", 3)]), counts.get("face", 0), offset)
    assert offset + faces.nbytes == len(data), "bytes left after the faces"
    assert np.all(faces["n"] == 3), "a face that is not a triangle"
    assert faces.size == 0 or (faces["i"].min() >= 0 and faces["i"].max() < vertices.size), "a face index out of range"
    colours = {}
    for r, g, b in zip(vertices["r"], vertices["g"], vertices["b"]):
        colours[f"{r},{g},{b}"] = colours.get(f"{r},{g},{b}", 0) + 1
    return {"vertices": int(vertices.size), "faces": int(faces.size), "colours": colours,
            "finite": bool(np.all(np.isfinite(vertices["x"])))}


if __name__ == "__main__":
    print(json.dumps(read(sys.argv[1])))
