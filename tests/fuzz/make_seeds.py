#!/usr/bin/env python3
"""make_seeds.py - writes the seed corpus tests/fuzz/corpus/<target>/ from the
shipped configs and small files made here (valid ones and broken ones). Run
from the top directory; it only adds or rewrites its own seed-* files, so
crash inputs kept in the corpus (crash-*, named by what they found) stay."""
import os
import re
import struct

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
CORPUS = os.path.join(ROOT, "tests", "fuzz", "corpus")


def put(target, name, data):
    d = os.path.join(CORPUS, target)
    os.makedirs(d, exist_ok=True)
    if isinstance(data, str):
        data = data.encode()
    assert len(data) <= 8192, (target, name, len(data))
    with open(os.path.join(d, "seed-" + name), "wb") as f:
        f.write(data)


def config(rel):
    with open(os.path.join(ROOT, rel), "rb") as f:
        return f.read()


# ---- PLY -------------------------------------------------------------------
TRI_HEADER = ("ply\nformat {fmt} 1.0\ncomment a triangle\nelement vertex 3\nproperty float x\nproperty float y\n"
              "property float z\n{extra}element face 1\nproperty list uchar int vertex_indices\nend_header\n")
put("ply", "cube_ascii.ply", config("configs/scenes/data/cube.ply"))
put("ply", "tri_ascii.ply", TRI_HEADER.format(fmt="ascii", extra="") + "0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n")
put("ply", "quad_normals_colors.ply",
    "ply\nformat ascii 1.0\nelement vertex 4\nproperty double x\nproperty double y\nproperty double z\n"
    "property float nx\nproperty float ny\nproperty float nz\nproperty uchar red\nproperty uchar green\n"
    "property uchar blue\nelement face 1\nproperty list uchar uint vertex_index\nend_header\n"
    "0 0 0 0 0 1 255 0 0\n1 0 0 0 0 1 0 255 0\n1 1 0 0 0 1 0 0 255\n0 1 0 0 0 1 9 9 9\n4 0 1 2 3\n")
for fmt, end in (("binary_little_endian", "<"), ("binary_big_endian", ">")):
    body = struct.pack(end + "9f", 0, 0, 0, 1, 0, 0, 0, 1, 0) + struct.pack(end + "B3i", 3, 0, 1, 2)
    put("ply", fmt + ".ply", TRI_HEADER.format(fmt=fmt, extra="").encode() + body)
    other = ("ply\nformat " + fmt + " 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
             "property short confidence\nelement face 1\nproperty list uchar int vertex_indices\n"
             "property uchar flags\nelement edge 1\nproperty int vertex1\nproperty int vertex2\nend_header\n")
    body = b"".join(struct.pack(end + "3fh", x, y, 0, 7) for x, y in ((0, 0), (1, 0), (0, 1)))
    body += struct.pack(end + "B3iB", 3, 0, 1, 2, 1) + struct.pack(end + "2i", 0, 1)
    put("ply", fmt + "_extra.ply", other.encode() + body)
put("ply", "bad_index.ply", TRI_HEADER.format(fmt="ascii", extra="") + "0 0 0\n1 0 0\n0 1 0\n3 0 1 7\n")
put("ply", "bad_count.ply", TRI_HEADER.format(fmt="ascii", extra="").replace("vertex 3", "vertex 4000000000")
    + "0 0 0\n")
put("ply", "bad_nan.ply", TRI_HEADER.format(fmt="ascii", extra="") + "0 nan 0\n1 0 0\n0 1 0\n3 0 1 2\n")
put("ply", "bad_header.ply", "ply\nformat ascii 2.0\nelement vertex x\nend_header\n")
put("ply", "bad_truncated.ply", TRI_HEADER.format(fmt="binary_little_endian", extra="").encode() + b"\0\0\x80")

# ---- particles: PLY point sets and LAMMPS dumps --------------------------------
POINTS_HEADER = ("ply\nformat {fmt} 1.0\nelement vertex 3\nproperty float x\nproperty double y\nproperty float z\n"
                 "property uchar red\nproperty uchar green\nproperty uchar blue\nproperty list uchar int near\n"
                 "property short intensity\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n")
put("particles", "points_ascii.ply", POINTS_HEADER.format(fmt="ascii")
    + "0 0 0 255 0 0 0 -5\n1 0.5 -1 0 255 0 2 0 1 7\n0 1 1e3 0 0 255 1 2 32767\n3 0 1 2\n")
for fmt, end in (("binary_little_endian", "<"), ("binary_big_endian", ">")):
    body = b"".join(struct.pack(end + "fdf3BB", x, y, 0.5, 10, 20, 30, 1) + struct.pack(end + "ih", 2, -x)
                    for x, y in ((0, 0), (1, 2), (3, 4)))
    put("particles", fmt + ".ply", POINTS_HEADER.format(fmt=fmt).encode() + body + struct.pack(end + "B3i", 3, 0, 1, 2))
    fixed = "ply\nformat " + fmt + " 1.0\nelement vertex 4\nproperty float x\nproperty float y\nproperty float z\n" \
            "property ushort id\nend_header\n"
    put("particles", fmt + "_fixed.ply", fixed.encode() + b"".join(struct.pack(end + "3fH", i, -i, 0.25 * i, i)
                                                                 for i in range(4)))
LAMMPS = ("ITEM: TIMESTEP\n{step}\nITEM: NUMBER OF ATOMS\n{n}\nITEM: BOX BOUNDS {box}\n{bounds}"
          "ITEM: ATOMS {cols}\n{atoms}")
ORTHO = "0 10\n-1 1\n0.0000000000000000e+00 5.0387885741475216e+01\n"
put("particles", "melt.dump", LAMMPS.format(step=0, n=3, box="pp pp pp", bounds=ORTHO, cols="id type x y z vx vy vz c_ke",
                                            atoms="1 1 0 0 0 -0.214306 -0.982589 -2.92294 4.7775\n"
                                                  "2 1 0.839798 0.839798 0 -1.81848 2.09402 2.27378 6.43094\n"
                                                  "3 1 0.839798 0 0.839798 -1.82652 -0.970185 1.58592 3.39628\n"))
put("particles", "scaled.dump", LAMMPS.format(step=50, n=2, box="pp ff pp", bounds=ORTHO, cols="id xs ys zs",
                                              atoms="1 0.5 0.25 0\n2 1 1 1\n"))
put("particles", "series.lammpstrj",
    "ITEM: UNITS\nlj\nITEM: TIME\n0.5\n"
    + LAMMPS.format(step=100, n=2, box="xy xz yz pp pp pp", bounds="0 4 0.5\n0 4 0\n0 4 0\n", cols="id xu yu zu",
                    atoms="1 0 1 2\n2 3 4 5\n")
    + LAMMPS.format(step=200, n=1, box="pp pp pp", bounds=ORTHO, cols="x y z", atoms="1 2 3\n"))
put("particles", "bad_count.dump", LAMMPS.format(step=0, n=4000000, box="pp pp pp", bounds=ORTHO, cols="x y z",
                                                 atoms="1 2 3\n"))
put("particles", "bad_columns.dump", LAMMPS.format(step=0, n=2, box="pp pp pp", bounds=ORTHO, cols="x y vx vx",
                                                   atoms="1 2 3 4\n5 nan 6\n"))
put("particles", "bad_truncated.ply", POINTS_HEADER.format(fmt="binary_little_endian").encode() + b"\0\0\x80")

# ---- OBJ (+ MTL after a "#--mtl--" line) -----------------------------------
put("obj", "quad.obj", config("configs/scenes/data/quad.obj"))
put("obj", "materials.obj",
    "mtllib in.mtl\no box\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nvt 0 0\nvt 1 0\nvt 1 1\nvn 0 0 1\n"
    "usemtl red\nf 1/1/1 2/2/1 3/3/1\nusemtl blue\nf 1//1 3//1 4//1\ng rest\nf -4 -3 -1\n"
    "#--mtl--\nnewmtl red\nKd 0.8 0.1 0.1\nKs 0.5 0.5 0.5\nNs 32\nnewmtl blue\nKd 0.1 0.1 0.9\nmap_Kd tex.png\n")
put("obj", "polygon.obj", "v 0 0 0 1\nv 1 0 0\nv 1 1 0 0.5 0.5 0.5\nv 0 1 0\nv 0.5 1.5 0\nf 1 2 3 4 5\nl 1 2\np 3\n")
put("obj", "bad_number.obj", "v 1 abc 2\nv 0 0 0\nv 1 1 1\nf 1 2 3\n")
put("obj", "bad_index.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 9\n")
put("obj", "bad_inf.obj", "v 0 0 0\nv 1e999 0 0\nv 0 1 0\nf 1 2 3\n")
put("obj", "bad_mtl.obj", "mtllib in.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl x\nf 1 2 3\n#--mtl--\nnewmtl x\nKd a b c\nd\n")

# ---- scene JSON (meshes: quad.ply and tri.ply beside the scene) -------------
def scene_from(rel):
    text = config(rel).decode()
    text = re.sub(r'"data/quad\.obj"', '"quad.ply"', text)
    text = re.sub(r'"data/cube\.ply"', '"tri.ply"', text)
    return text

put("scene", "spheres.json", scene_from("configs/scenes/spheres.json"))
put("scene", "cornell_like.json", scene_from("configs/scenes/cornell_like.json"))
put("scene", "minimal.json", '{"spheres": [{"center": [0, 0, 0], "radius": 1}]}')
put("scene", "matrix.json",
    '{"materials": {"default": {"diffuse": [1, 1, 1]}}, "lights": [],\n'
    ' "meshes": [{"file": "tri.ply", "matrix": [1,0,0,1, 0,2,0,0, 0,0,3,0]},\n'
    '            {"file": "quad.ply", "transform": {"scale": [1, 2, 3], "rotate_deg": [10, 20, 30]}},\n'
    '            {"file": "missing.ply", "optional": true}]}')
put("scene", "bad_syntax.json", '{"camera": {"eye": [0, 0, 1], "look_at": [0, 0, 0]}, /* x */ "spheres": [}')
put("scene", "bad_duplicate.json", '{"spheres": [], "spheres": []}')
put("scene", "bad_field.json", '{"lights": [{"type": "spot", "position": [0, 1, 0]}], "spheres": [{"center": [0,0,0], "radius": 1}]}')
put("scene", "bad_material.json", '{"spheres": [{"center": [0,0,0], "radius": 1, "material": "nope"}]}')
put("scene", "bad_mesh.json", '{"meshes": [{"file": "missing.obj"}]}')
put("scene", "bad_number.json", '{"ambient": [1e39, 0, 0], "spheres": [{"center": [0,0,0], "radius": -1}]}')

# ---- wall configs ------------------------------------------------------------
for name in ("desk", "portrait_3x1", "vm_2x2", "wall_2x2"):
    put("wall_config", name + ".json", config("configs/walls/%s.json" % name))
put("wall_config", "edid_px.json",
    '{"format": "tessera-wall", "version": 1, "units": "mm", "outputs": [\n'
    ' {"connector": "HDMI-A-1", "edid": {"manufacturer": "GSM", "model": "LG HDR 4K"}, "mode": "2560x1440@59.95",\n'
    '  "rotation": 0, "position_px": [0, 0], "size_mm": [597, 336]},\n'
    ' {"connector": "DP-2", "mode": "1080x1920", "rotation": 90, "position_mm": [600, 0], "size_mm": [336, 597],\n'
    '  "bezel_mm": {"left": 1, "right": 2.5}}]}')
put("wall_config", "bad_overlap.json",
    '{"format": "tessera-wall", "version": 1, "units": "mm", "outputs": [\n'
    ' {"connector": "Virtual-1", "position_mm": [0, 0], "size_mm": [100, 100]},\n'
    ' {"connector": "Virtual-2", "position_mm": [50, 50], "size_mm": [100, 100]}]}')
put("wall_config", "bad_mode.json",
    '{"format": "tessera-wall", "version": 1, "units": "mm", "outputs": [\n'
    ' {"connector": "Virtual-1", "mode": "1920x0@x", "grid": [0, 0], "size_mm": [100, 100]}]}')
put("wall_config", "bad_format.json", '{"format": "tessera-camera-path", "version": 1}')

# ---- bindings ----------------------------------------------------------------
put("bindings", "bindings.json", config("configs/bindings.json"))
put("bindings", "small.json", '{"format": "tessera-bindings", "version": 1, "keys": {"KEY_Q": "home", "BTN_SIDE": "pan"},'
    ' "quit_chord": ["KEY_RIGHTCTRL", "KEY_ESC"]}')
put("bindings", "bad_key.json", '{"format": "tessera-bindings", "version": 1, "keys": {"KEY_WW": "home"}}')
put("bindings", "bad_gesture.json", '{"format": "tessera-bindings", "version": 1, "gestures": {"tap": "orbit", "swirl": "pan"}}')
put("bindings", "bad_chord.json", '{"format": "tessera-bindings", "version": 1, "quit_chord": ["BTN_LEFT", 3]}')

# ---- camera paths --------------------------------------------------------------
for name in ("flythrough", "orbit", "tour"):
    put("camera_path", name + ".json", config("configs/paths/%s.json" % name))
put("camera_path", "linear_loop.json",
    '{"format": "tessera-camera-path", "version": 1, "interpolation": "linear", "loop": true, "keyframes": [\n'
    ' {"time": 0, "eye": [0, 0, 5], "look_at": [0, 0, 0]},\n'
    ' {"time": 1e-300, "eye": [5, 0, 0], "look_at": [0, 0, 0], "up": [0, 0, 1], "fov_deg": 179.9},\n'
    ' {"time": 2, "eye": [0, 0, 5], "look_at": [0, 0, 0]}]}')
put("camera_path", "bad_order.json",
    '{"format": "tessera-camera-path", "version": 1, "keyframes": [\n'
    ' {"time": 1, "eye": [0, 0, 5], "look_at": [0, 0, 0]}, {"time": 1, "eye": [1, 0, 5], "look_at": [0, 0, 0]}]}')
put("camera_path", "bad_camera.json",
    '{"format": "tessera-camera-path", "version": 1, "keyframes": [{"time": 0, "eye": [0, 0, 0], "look_at": [0, 0, 0]}]}')
put("camera_path", "bad_loop.json",
    '{"format": "tessera-camera-path", "version": 1, "loop": true, "keyframes": [{"time": 0, "eye": [0, 0, 5], "look_at": [0, 0, 0]}]}')

# ---- pipeline configs ------------------------------------------------------------
for name in ("kiosk", "stills", "two_views"):
    put("pipeline_config", name + ".json", config("configs/pipeline/%s.json" % name))
put("pipeline_config", "input.json",
    '{"threads": 2, "time": {"mode": "fixed", "rate_hz": 24}, "sampler": {"name": "jittered", "k": 3},\n'
    ' "camera": {"eye": [0, 1, 5], "look_at": [0, 0, 0]}, "display": {"name": "dump", "out": "out/f_####.png"},\n'
    ' "input": {"enabled": true, "seat": "seat0", "devices": ["/dev/input/event3"],\n'
    '           "map": {"/dev/input/event3": "HDMI-A-1"}, "idle_timeout_s": 0, "tour": "t.json"}}')
put("pipeline_config", "bad_threads.json", '{"threads": 0}')
put("pipeline_config", "bad_channel.json", '{"channels": [{"size": [0, 10], "display": {"name": "dump"}}]}')
put("pipeline_config", "bad_order.json", '{"traverser": {"name": "tiled", "order": "zigzag"}}')

# ---- input records ------------------------------------------------------------------
HEAD = "tessera-input-record 1\n"
put("record", "session.rec",
    HEAD + "# a session\n0.000000 camera 0x0p+0 0x1p+0 0x1.4p+2 0x0p+0 0x0p+0 0x0p+0 0x0p+0 0x1p+0 0x0p+0 0x1.4p+5\n"
    "0.100000 cursor 1 0x1p-1 -0x1.8p-2\n0.200000 status \"picked mesh 0 'bunny' \\\"x\\\" \\\\ \\x7f\"\n"
    "0.300000 hide 3\n0.400000 unhide-all\n0.500000 tour 1\n\n0.600000 tour 0\n0.700000 quit\r\n")
put("record", "bad_kind.rec", HEAD + "0.1 zoom 3\n")
put("record", "bad_float.rec", HEAD + "0.1 cursor 1 0.1 0.5\n")
put("record", "bad_order.rec", HEAD + "0.5 quit\n0.25 quit\n")
put("record", "bad_escape.rec", HEAD + "0.5 status \"abc\\q\"\n0.6 status \"\\x4\n")
put("record", "bad_header.rec", "tessera-input-record 2\n0 quit\n")

# ---- EDID base blocks ----------------------------------------------------------------
def edid(mfg, product, serial, descriptors):
    b = bytearray(128)
    b[0:8] = b"\x00\xff\xff\xff\xff\xff\xff\x00"
    letters = [ord(c) - ord("A") + 1 for c in mfg]
    v = letters[0] << 10 | letters[1] << 5 | letters[2]
    b[8], b[9] = v >> 8, v & 0xFF
    b[10:12] = struct.pack("<H", product)
    b[12:16] = struct.pack("<I", serial)
    b[18], b[19] = 1, 4
    for k, (tag, text) in enumerate(descriptors):
        d = bytearray(18)
        if tag is None:
            d[0:2] = b"\x02\x3a"  # a detailed timing
        else:
            d[3] = tag
            t = text.encode()[:13]
            t = t + (b"\n" + b" " * 12 if len(t) < 13 else b"")
            d[5:18] = t[:13]
        b[54 + 18 * k: 72 + 18 * k] = d
    b[127] = (-sum(b[:127])) & 0xFF
    return bytes(b)

put("edid", "dell.bin", edid("DEL", 0xA0C4, 0x4C4B4A41, [(None, ""), (0xFF, "ABC123"), (0xFC, "DELL U2415"), (0xFD, "")]))
put("edid", "qemu.bin", edid("RHT", 0x1234, 0, [(None, ""), (0xFC, "QEMU Monitor"), (0x10, ""), (0x10, "")]))
put("edid", "full_text.bin", edid("ZZZ", 1, 1, [(0xFC, "ABCDEFGHIJKLM"), (0xFF, "\x01\x7f\xff x   "), (0xFC, ""), (0xFF, "")]))
put("edid", "bad_checksum.bin", edid("DEL", 1, 1, [])[:127] + b"\x00")
put("edid", "bad_short.bin", edid("DEL", 1, 1, [])[:100])
