#!/usr/bin/env python3
"""Writes the bad-input corpus of tests/bad_inputs: for every format nbv reads, files that are
empty, truncated at several points, with a wrong magic or header, NaN and Inf values, bad
indices, absurd counts, binary garbage, a directory in place of a file, and a missing file.

    python3 tests/bad_inputs/generate.py build/apps/nbv

The map files are cut from maps nbv itself writes, so it needs the nbv binary. The output is
committed; MANIFEST lists every case as `kind <TAB> path <TAB> fragment of the expected error`,
where kind says which reader takes the file (mesh, cloud, views, map, depth: a 16-bit depth
PNG, tum: a TUM RGB-D folder; cloud_points: a readable cloud that `nbv integrate` refuses;
depth_frame: a readable depth PNG that `nbv integrate --depth` refuses; frames: a numbered
frame folder with its poses.txt). tests/test_bad_inputs.cpp
feeds each to the library, tests/bad_inputs_test.sh to the command line.
"""
import os
import random
import shutil
import struct
import subprocess
import sys
import tempfile

HERE = os.path.dirname(os.path.abspath(__file__))
for old in ("mesh", "cloud", "cloud_points", "views", "map", "depth", "depth_frame", "tum"):
    for name in os.listdir(os.path.join(HERE, old)) if os.path.isdir(os.path.join(HERE, old)) else []:
        target = os.path.join(HERE, old, name)
        shutil.rmtree(target) if os.path.isdir(target) else os.remove(target)
cases = []  # (kind, relative path, fragment)


def put(kind, name, data, fragment):
    path = os.path.join(HERE, kind, name)
    os.makedirs(os.path.dirname(path), exist_ok=True)
    with open(path, "wb") as f:
        f.write(data.encode() if isinstance(data, str) else data)
    cases.append((kind, f"{kind}/{name}", fragment))


def put_directory(kind, name):
    path = os.path.join(HERE, kind, name)
    os.makedirs(path, exist_ok=True)
    with open(os.path.join(path, ".gitkeep"), "w"):
        pass
    cases.append((kind, f"{kind}/{name}", "directory"))


def garbage(size, seed):
    rng = random.Random(seed)
    return bytes(rng.randrange(256) for _ in range(size))


def cuts(kind, stem, ext, good, points, fragment):
    """The good file cut after each fraction of its bytes in `points`."""
    for p in points:
        n = max(1, int(len(good) * p))
        put(kind, f"{stem}_cut{int(p * 100):02d}{ext}", good[:n], fragment)


# ---- meshes (assimp reads OFF, OBJ, STL, PLY; nbv checks counts before it does) ----
TETRA_V = [(0, 0, 0), (1, 0, 0), (0, 1, 0), (0, 0, 1)]
TETRA_F = [(0, 2, 1), (0, 1, 3), (0, 3, 2), (1, 2, 3)]


def off(vertices=TETRA_V, faces=TETRA_F, counts=None):
    nv, nf = counts if counts else (len(vertices), len(faces))
    lines = ["OFF", f"{nv} {nf} 0"]
    lines += [" ".join(str(c) for c in v) for v in vertices]
    lines += ["3 " + " ".join(str(i) for i in f) for f in faces]
    return "\n".join(lines) + "\n"


def obj(vertices=TETRA_V, faces=TETRA_F):
    return "".join(f"v {x} {y} {z}\n" for x, y, z in vertices) + "".join(
        f"f {a + 1} {b + 1} {c + 1}\n" for a, b, c in faces)


def stl_binary(faces, claimed=None):
    body = b"".join(struct.pack("<12fH", 0, 0, 0, *TETRA_V[a], *TETRA_V[b], *TETRA_V[c], 0)
                    for a, b, c in faces)
    return b"nbv bad-input corpus".ljust(80, b" ") + struct.pack("<I", claimed if claimed is not None else len(faces)) + body


def stl_ascii(vertices=TETRA_V):
    out = "solid tetra\n"
    for a, b, c in TETRA_F:
        out += " facet normal 0 0 0\n  outer loop\n"
        for i in (a, b, c):
            out += "   vertex {} {} {}\n".format(*vertices[i])
        out += "  endloop\n endfacet\n"
    return out + "endsolid tetra\n"


def ply_mesh(binary, nv=None, nf=None, vertices=TETRA_V, faces=TETRA_F):
    fmt = "binary_little_endian" if binary else "ascii"
    head = (f"ply\nformat {fmt} 1.0\nelement vertex {nv if nv is not None else len(vertices)}\n"
            "property float x\nproperty float y\nproperty float z\n"
            f"element face {nf if nf is not None else len(faces)}\nproperty list uchar int vertex_indices\nend_header\n")
    if binary:
        body = b"".join(struct.pack("<3f", *v) for v in vertices)
        body += b"".join(struct.pack("<B3i", 3, *f) for f in faces)
        return head.encode() + body
    return head + "".join("{} {} {}\n".format(*v) for v in vertices) + "".join(
        "3 {} {} {}\n".format(*f) for f in faces)


good_off = off()
put("mesh", "empty.off", "", "empty")
put_directory("mesh", "directory.off")
cases.append(("mesh", "mesh/missing.off", "no such file"))
cuts("mesh", "off", ".off", good_off, [0.02, 0.3, 0.6, 0.9], "")
put("mesh", "magic.off", good_off.replace("OFF", "ONF", 1), "")
put("mesh", "nan_vertex.off", off([(0, 0, 0), (1, float("nan"), 0), (0, 1, 0), (0, 0, 1)]), "")
put("mesh", "inf_vertex.off", off([(0, 0, 0), (1, 0, 0), (0, float("inf"), 0), (0, 0, 1)]), "")
put("mesh", "negative_index.off", off(faces=[(0, 2, 1), (0, -1, 3)]), "")
put("mesh", "index_out_of_range.off", off(faces=[(0, 2, 1), (0, 1, 7)]), "")
put("mesh", "bomb.off", off(counts=(10**12, 4)), "more than the file can hold")
put("mesh", "negative_count.off", off(counts=(-4, 4)), "not counts")
put("mesh", "garbage.off", garbage(2048, 1), "")
put("mesh", "no_triangles.off", off(faces=[]), "no (non-degenerate) triangles")
put("mesh", "degenerate_only.off", off(faces=[(0, 0, 1), (1, 2, 2)]), "no (non-degenerate) triangles")
# A fuzzer finding: a face's vertex count of 2^64 - 1 (n + 1 wrapped to 0 past the check).
put("mesh", "face_count_overflow.off", off(counts=(4, 1), faces=[]) + f"{2**64 - 1} 0 1 2\n", "a face is 'n i_1 ... i_n'")

good_obj = obj()
put("mesh", "empty.obj", "", "empty")
put("mesh", "nan_vertex.obj", obj([(0, 0, 0), (float("nan"), 0, 0), (0, 1, 0), (0, 0, 1)]), "")
put("mesh", "index_out_of_range.obj", good_obj + "f 1 2 99\n", "")
put("mesh", "negative_index.obj", good_obj + "f 1 2 -99\n", "")
put("mesh", "garbage.obj", garbage(2048, 2), "")
put("mesh", "no_faces.obj", "".join(f"v {x} {y} {z}\n" for x, y, z in TETRA_V), "")
cuts("mesh", "obj", ".obj", good_obj, [0.3], "")

good_stl = stl_binary(TETRA_F)
put("mesh", "empty.stl", "", "empty")
put("mesh", "header_only.stl", good_stl[:80], "")
cuts("mesh", "stl", ".stl", good_stl, [0.5, 0.9], "")
put("mesh", "bomb.stl", stl_binary(TETRA_F, claimed=4_000_000_000), "")
put("mesh", "nan_vertex.stl", good_stl[:84] + struct.pack("<12fH", 0, 0, 0, 0, 0, 0, float("nan"), 0, 0, 0, 1, 0, 0)
    + good_stl[134:], "")
put("mesh", "float_overflow.stl", stl_ascii([(0, 0, 0), (1, 0, 0), (0, 6.7e40, 0), (0, 0, 1)]), "not finite in single precision")
put("mesh", "inf_vertex_ascii.stl", stl_ascii([(0, 0, 0), (1, 0, 0), (0, float("inf"), 0), (0, 0, 1)]), "")
cuts("mesh", "stl_ascii", ".stl", stl_ascii().encode(), [0.05, 0.5], "")

good_ply_mesh = ply_mesh(True)
put("mesh", "empty.ply", "", "empty")
cuts("mesh", "ply", ".ply", good_ply_mesh, [0.1, 0.5, 0.8, 0.97], "")
put("mesh", "magic.ply", b"plx" + good_ply_mesh[3:], "")
put("mesh", "bomb_vertices.ply", ply_mesh(True, nv=10**12), "more than the file can hold")
put("mesh", "bomb_faces.ply", ply_mesh(True, nf=10**12), "more than the file can hold")
put("mesh", "bomb_ascii.ply", ply_mesh(False, nv=10**12), "more than the file can hold")
put("mesh", "index_out_of_range.ply", ply_mesh(False, faces=[(0, 2, 1), (0, 1, 9)]), "")
put("mesh", "negative_index.ply", ply_mesh(False, faces=[(0, 2, 1), (0, 1, -3)]), "")
put("mesh", "nan_vertex.ply", ply_mesh(False, vertices=[(0, 0, 0), (float("nan"), 0, 0), (0, 1, 0), (0, 0, 1)]), "")
put("mesh", "garbage.ply", b"ply\n" + garbage(2048, 3), "")
# Formats nbv does not read itself go through assimp.
put("mesh", "garbage.dae", garbage(2048, 9), "")
put("mesh", "truncated.dae", '<?xml version="1.0"?>\n<COLLADA xmlns="http://www.collada.org/2005/11/COLLADASchema" version="1.4.1">\n<library_geometries><geometry id="g"><mesh><source id="p"><float_array id="a" count="9">0 0 0 1', "")

# ---- point clouds (nbv's own PLY reader) ----
HEADER = ("ply\nformat {fmt} 1.0\nelement vertex {n}\nproperty float x\nproperty float y\n"
          "property float z\nend_header\n")
POINTS = [(0.3, 0.0, 0.0), (0.3, 0.1, 0.05), (0.0, 0.2, 0.1)]
good_cloud = HEADER.format(fmt="binary_little_endian", n=3).encode() + b"".join(struct.pack("<3f", *p) for p in POINTS)
put("cloud", "empty.ply", "", "empty")
put_directory("cloud", "directory.ply")
cases.append(("cloud", "cloud/missing.ply", "no such file"))
cuts("cloud", "cloud", ".ply", good_cloud, [0.05, 0.4, 0.8], "")
put("cloud", "cut_last_byte.ply", good_cloud[:-1], "truncated")
put("cloud", "magic.ply", b"plx" + good_cloud[3:], "not a PLY")
put("cloud", "format.ply", good_cloud.replace(b"binary_little_endian", b"binary_middle_endian"), "line 2")
put("cloud", "no_z.ply", HEADER.format(fmt="ascii", n=1).replace("property float z\n", "") + "1 2\n", "lacks x, y or z")
put("cloud", "text_value.ply", HEADER.format(fmt="ascii", n=2) + "1 2 3\n4 five 6\n", "line 9")
put("cloud", "negative_count.ply", HEADER.format(fmt="ascii", n=-4), "line 3")
put("cloud", "bomb.ply", HEADER.format(fmt="binary_little_endian", n=10**12).encode() + bytes(64), "more than the file can hold")
put("cloud", "garbage.ply", garbage(2048, 4), "not a PLY")
put("cloud", "header_garbage.ply", b"ply\n" + garbage(512, 5), "")

# Readable clouds with no usable point: the reader returns what is there (SEMANTICS.md "The map" skips
# non-finite points one by one), `nbv integrate` refuses the cloud as a whole.
put("cloud_points", "nan.ply", HEADER.format(fmt="ascii", n=2) + "nan 2 3\nnan 0 0\n", "no finite point")
put("cloud_points", "inf.ply", HEADER.format(fmt="binary_little_endian", n=1).encode() + struct.pack("<3f", 0, float("inf"), 0), "no finite point")
put("cloud_points", "no_points.ply", HEADER.format(fmt="ascii", n=0), "no points")

# ---- view files (nbv's own format: N, then N lines x y z qx qy qz qw) ----
good_views = "2\n1 0 0.5 0 0 0 1\n0 1 0.5 0 0 0.7071068 0.7071068\n"
put("views", "empty.txt", "", "empty")
put_directory("views", "directory.txt")
cases.append(("views", "views/missing.txt", "no such file"))
put("views", "count_word.txt", "two\n", "line 1")
put("views", "negative_count.txt", "-2\n1 0 0 0 0 0 1\n", "line 1")
put("views", "short.txt", good_views.splitlines(True)[0] + good_views.splitlines(True)[1], "ends after 1 of 2")
cuts("views", "views", ".txt", good_views.encode(), [0.5, 0.75], "")
put("views", "nan.txt", "1\n0 nan 0 0 0 0 1\n", "line 2")
put("views", "inf.txt", "1\n0 0 0 0 0 inf 1\n", "line 2")
put("views", "nan_quaternion.txt", "1\n0 0 1 nan 0 0 1\n", "line 2")
put("views", "zero_quaternion.txt", "1\n0 0 0 0 0 0 0\n", "zero quaternion")
put("views", "fields.txt", "1\n0 0 0 0 0 1\n", "line 2")
put("views", "extra.txt", "1\n0 0 0 0 0 0 1 5\n", "extra value")
put("views", "more.txt", "1\n0 0 0 0 0 0 1\n0 0 0 0 0 0 1\n", "more lines")
put("views", "bomb.txt", "1000000000000\n0 0 0 0 0 0 1\n", "more than the file can hold")
put("views", "garbage.txt", garbage(1024, 6), "")
put("views", "huge_value.txt", "1\n1e400 0 0 0 0 0 1\n", "line 2")

# ---- maps (.vdb through OpenVDB, .ot and .bt through liboctomap) ----
nbv = os.path.abspath(sys.argv[1]) if len(sys.argv) > 1 else None
if nbv is None:
    sys.exit("usage: generate.py PATH/TO/nbv")
with tempfile.TemporaryDirectory() as tmp:
    cloud = os.path.join(tmp, "scan.ply")
    with open(cloud, "wb") as f:
        f.write(good_cloud)
    vdb = os.path.join(tmp, "good.vdb")
    subprocess.run([nbv, "integrate", "--map", vdb, "--cloud", cloud, "--origin", "0", "0", "0.05",
                    "--resolution", "0.05"], check=True, stdout=subprocess.DEVNULL)
    for ext in (".ot", ".bt"):
        subprocess.run([nbv, "convert", vdb, os.path.join(tmp, "good" + ext)], check=True, stdout=subprocess.DEVNULL)
    good_maps = {ext: open(os.path.join(tmp, "good" + ext), "rb").read() for ext in (".vdb", ".ot", ".bt")}

for ext, good in good_maps.items():
    stem = ext[1:]
    put("map", f"empty{ext}", "", "")
    put_directory("map", f"directory{ext}")
    cases.append(("map", f"map/missing{ext}", "no such file"))
    cuts("map", stem, ext, good, [0.01, 0.1, 0.25, 0.5, 0.75, 0.99], "")
    put("map", f"garbage{ext}", garbage(4096, 7), "")
    put("map", f"magic{ext}", b"X" + good[1:], "")
    header_end = 8 if ext == ".vdb" else good.find(b"data\n") + 5
    put("map", f"header_then_garbage{ext}", good[:header_end] + garbage(4096, 8), "")

OT_HEAD = b"# Octomap OcTree file\nid OcTree\nsize {n}\nres {res}\ndata\n"
leaf = struct.pack("<fB", 1.0, 0)
put("map", "huge_volume.ot", OT_HEAD.replace(b"{n}", b"9").replace(b"{res}", b"0.01") + struct.pack("<fB", 1.0, 0xFF) + leaf * 8, "")
put("map", "nan_logodds.ot", OT_HEAD.replace(b"{n}", b"1").replace(b"{res}", b"0.01") + struct.pack("<fB", float("nan"), 0), "")
put("map", "inf_logodds.ot", OT_HEAD.replace(b"{n}", b"1").replace(b"{res}", b"0.01") + struct.pack("<fB", float("inf"), 0), "")
put("map", "zero_resolution.ot", OT_HEAD.replace(b"{n}", b"1").replace(b"{res}", b"0") + leaf, "")
put("map", "negative_resolution.bt", b"# Octomap OcTree binary file\nid OcTree\nsize 1\nres -0.05\ndata\n" + bytes(2), "")
put("map", "nan_resolution.ot", OT_HEAD.replace(b"{n}", b"1").replace(b"{res}", b"nan") + leaf, "")
put("map", "bomb_size.ot", OT_HEAD.replace(b"{n}", b"1000000000000").replace(b"{res}", b"0.01") + leaf, "")
put("map", "wrong_id.ot", OT_HEAD.replace(b"OcTree\nsize", b"ColorOcTree\nsize").replace(b"{n}", b"1").replace(b"{res}", b"0.01") + leaf, "")

# ---- depth images (16-bit greyscale PNG) and TUM RGB-D folders ----
import zlib  # noqa: E402


def png(width, height, bit_depth, colour_type, samples_per_pixel=1):
    """A PNG of zeros: signature, IHDR, one IDAT, IEND."""
    def chunk(kind, data):
        return struct.pack(">I", len(data)) + kind + data + struct.pack(">I", zlib.crc32(kind + data) & 0xFFFFFFFF)
    row = bytes(1 + width * samples_per_pixel * bit_depth // 8)  # filter byte 0, then zeros
    ihdr = struct.pack(">IIBBBBB", width, height, bit_depth, colour_type, 0, 0, 0)
    return (b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", ihdr) + chunk(b"IDAT", zlib.compress(row * height))
            + chunk(b"IEND", b""))


good_depth = png(752, 480, 16, 0)
put("depth", "empty.png", b"", "not a PNG file")
put_directory("depth", "directory.png")
cases.append(("depth", "depth/missing.png", "no such file"))
put("depth", "magic.png", b"GIF89a" + garbage(200, 7), "not a PNG file")
for p in (0.2, 0.5, 0.9):
    put("depth", f"png_cut{int(p * 100):02d}.png", good_depth[:max(9, int(len(good_depth) * p))], "truncated or corrupt PNG")
put("depth", "eight_bit.png", png(752, 480, 8, 0), "8-bit PNG")
put("depth", "colour.png", png(752, 480, 16, 2, 3), "colour or alpha PNG")
put("depth", "grey_alpha.png", png(752, 480, 16, 4, 2), "colour or alpha PNG")
put("depth", "garbage.png", b"\x89PNG\r\n\x1a\n" + garbage(500, 8), "truncated or corrupt PNG")
put("depth_frame", "small.png", png(10, 10, 16, 0), "is 10 x 10 pixels; the camera is 752 x 480")

GOOD_POSES = "# t tx ty tz qx qy qz qw\n1.000 0.6 0 0.15 0 0 0 1\n1.100 0.6 0.1 0.15 0 0 0 1\n"
GOOD_DEPTHS = "# t path\n1.000 depth/0.png\n1.100 depth/1.png\n"


def folder(kind, name, files, fragment):
    """One case: a folder of `files` (name -> content; None: left out)."""
    for file, data in files.items():
        if data is not None:
            put(kind, f"{name}/{file}", data, fragment)
            cases.pop()
    cases.append((kind, f"{kind}/{name}", fragment))


def tum(name, depths, poses, images=("depth/0.png", "depth/1.png"), fragment=""):
    folder("tum", name, {**{image: good_depth for image in images}, "depth.txt": depths, "groundtruth.txt": poses}, fragment)


tum("no_depth_list", None, GOOD_POSES, fragment="depth.txt: no such file")
tum("no_poses", GOOD_DEPTHS, None, fragment="groundtruth.txt: no such file")
tum("unsorted_frames", "1.100 depth/1.png\n1.000 depth/0.png\n", GOOD_POSES, fragment="line 2: timestamp 1.000000 is not after")
tum("unsorted_poses", GOOD_DEPTHS, "1.100 0.6 0 0.15 0 0 0 1\n1.000 0.6 0 0.15 0 0 0 1\n", fragment="line 2: timestamp")
tum("unmatched", "1.000 depth/0.png\n1.050 depth/1.png\n", GOOD_POSES, fragment="line 2: frame at 1.050000 s has no pose within 20 ms")
tum("nan_pose", GOOD_DEPTHS, "1.000 0.6 nan 0.15 0 0 0 1\n1.100 0.6 0 0.15 0 0 0 1\n", fragment="line 1: a value is not finite")
tum("zero_quaternion", GOOD_DEPTHS, "1.000 0.6 0 0.15 0 0 0 0\n1.100 0.6 0 0.15 0 0 0 1\n", fragment="line 1: zero quaternion")
tum("short_pose", GOOD_DEPTHS, "1.000 0.6 0 0.15 0 0 0\n", fragment="line 1: expected timestamp tx ty tz qx qy qz qw")
tum("missing_image", "1.000 depth/0.png\n1.100 depth/2.png\n", GOOD_POSES, fragment="no such depth image (depth.txt:2)")
tum("no_frames", "# nothing\n", GOOD_POSES, fragment="lists no depth image")
tum("bad_image", GOOD_DEPTHS, GOOD_POSES, images=("depth/0.png",), fragment="")
put("tum", "bad_image/depth/1.png", png(752, 480, 8, 0), "")
cases.pop()
cases[-1] = ("tum", "tum/bad_image", "8-bit PNG")

# A numbered frame folder and its pose file without timestamps (`nbv integrate --frames DIR
# --poses DIR/poses.txt`).
FRAME_POSES = "# tx ty tz qx qy qz qw\n0.6 0 0.15 0 0 0 1\n0.6 0.1 0.15 0 0 0 1\n"


def frames(name, poses, images=("0.png", "1.png"), fragment=""):
    folder("frames", name, {**{image: good_depth for image in images}, "poses.txt": poses}, fragment)


frames("no_poses", None, fragment="poses.txt: no such file")
frames("no_images", FRAME_POSES, images=(), fragment="holds no .png depth image")
frames("unnumbered", FRAME_POSES, images=("0.png", "depth.png"), fragment="has no frame number in its name")
frames("same_number", FRAME_POSES, images=("frame_1.png", "frame_01.png"), fragment="has the frame number of")
frames("short_pose", "0.6 0 0.15 0 0 0\n0.6 0.1 0.15 0 0 0 1\n", fragment="line 1: expected tx ty tz qx qy qz qw (7 numbers), got 6")
frames("timestamped", GOOD_POSES, fragment="line 2: expected tx ty tz qx qy qz qw (7 numbers), got 8")
frames("word", "0.6 zero 0.15 0 0 0 1\n0.6 0.1 0.15 0 0 0 1\n", fragment="line 1: expected tx ty tz qx qy qz qw; 'zero' is not a number")
frames("more_poses", FRAME_POSES + "0.6 0.2 0.15 0 0 0 1\n", fragment="line 4: more poses than the 2 images")
frames("fewer_poses", "0.6 0 0.15 0 0 0 1\n", fragment="holds 1 poses for the 2 images")
frames("nan_pose", "0.6 nan 0.15 0 0 0 1\n0.6 0.1 0.15 0 0 0 1\n", fragment="line 1: a value is not finite")
frames("zero_quaternion", "0.6 0 0.15 0 0 0 0\n0.6 0.1 0.15 0 0 0 1\n", fragment="line 1: zero quaternion")
frames("bad_image", FRAME_POSES, images=("0.png",), fragment="")
put("frames", "bad_image/1.png", png(752, 480, 8, 0), "")
cases.pop()
cases[-1] = ("frames", "frames/bad_image", "8-bit PNG")

# ---- seeds of the fuzz targets (tests/fuzz): good files, and a few of the bad ones ----
# Written over by name: the seeds a fuzzer found and a session committed (fuzz_ig_rays) stay.
SEEDS = os.path.join(os.path.dirname(HERE), "fuzz", "corpus")


def seed(target, name, data):
    os.makedirs(os.path.join(SEEDS, target), exist_ok=True)
    with open(os.path.join(SEEDS, target, name), "wb") as f:
        f.write(data.encode() if isinstance(data, str) else data)


seed("fuzz_ply_cloud", "binary", good_cloud)
seed("fuzz_ply_cloud", "ascii", HEADER.format(fmt="ascii", n=3) + "".join("{} {} {}\n".format(*p) for p in POINTS))
seed("fuzz_ply_cloud", "big_endian_double", HEADER.format(fmt="binary_big_endian", n=1).replace("float", "double").encode()
     + struct.pack(">3d", 1, 2, 3))
for i, data in enumerate([good_off.encode(), good_obj.encode(), good_stl, stl_ascii().encode(), good_ply_mesh,
                          ply_mesh(False).encode()]):
    seed("fuzz_mesh", f"mesh{i}", bytes([(0, 1, 2, 2, 3, 3)[i]]) + data)
seed("fuzz_views", "two", good_views)
seed("fuzz_views", "nonunit", "1\n0 0 1 0 0 0 3\n")
for i, ext in enumerate((".ot", ".bt", ".vdb")):  # the first byte picks the extension
    seed("fuzz_map", "map" + ext, bytes([i]) + good_maps[ext])
# IG rays: resolution, box (min, size per axis), voxel kinds, then an origin and ends on the lattice.
seed("fuzz_ig_rays", "corner_rays", bytes([0, 8, 4, 8, 4, 8, 4]) + bytes((i * 7) % 4 for i in range(64))
     + bytes([16, 16, 16]) + bytes([20, 24, 30, 2, 31, 28, 30, 30, 30]))
seed("fuzz_ig_rays", "fractions", bytes([1, 9, 3, 10, 5, 6, 2]) + bytes((i * 5) % 3 for i in range(30))
     + bytes([17, 128, 15, 64, 16]) + bytes([25, 3, 26, 200, 27, 9, 50, 12, 0, 31, 31]))
# A sparse box (bit 2 of the first byte): 21^3 unmeasured voxels but for a free one at the centre
# and an occupied one, so runs reach 10 voxels.
seed("fuzz_ig_rays", "sparse_runs", bytes([4, 8, 20, 8, 20, 8, 20, 2, 22, 18, 0, 232, 3, 1]) + bytes([6, 6, 6])
     + bytes([30, 28, 26, 24, 30, 18, 31, 128, 27, 64, 25, 200]))
# Boxes of one kind laid over one another (bit 5 of the first byte): runs of free, marked,
# measured unknown and occupied voxels, crossed in closed form.
seed("fuzz_ig_rays", "runs_of_every_kind", bytes([32, 2, 11, 3, 11, 1, 11, 5, 0, 0, 0, 9, 9, 9, 1, 2, 2, 2, 7, 7, 7, 4,
                                                  6, 1, 1, 4, 4, 8, 3, 0, 5, 0, 10, 2, 10, 0, 1, 9, 9, 9, 2, 2, 2, 2])
     + bytes([3, 16, 17, 30, 2, 31, 28, 30, 30, 30, 25, 3, 26, 200, 27, 9]))
rng = random.Random(11)
for i in range(4):  # scans: origin, n, n points; the view from the last 3 bytes
    scan = bytes([128, 128, 60, 40]) + bytes(rng.randrange(256) for _ in range(120))
    seed("fuzz_integrate_evaluate", f"scan{i}", scan * (i + 1))


with open(os.path.join(HERE, "MANIFEST"), "w") as f:
    f.write("# kind\tpath (relative to tests/bad_inputs)\tfragment the error must contain (besides the path)\n")
    f.write("# Written by generate.py; do not edit by hand.\n")
    for kind, path, fragment in cases:
        f.write(f"{kind}\t{path}\t{fragment}\n")
print(f"{len(cases)} bad inputs in {HERE}")
