#!/usr/bin/env python3
"""QMP client and image checks for the VM tests (python3 standard library only).

usage: qmp.py SOCKET COMMAND [ARGS...]
  wait [SECS]                    until the QMP socket answers (default 30 s)
  screendump FILE [HEAD [DEVICE]]  head HEAD (default 0) of the virtio-gpu DEVICE (its qom
                                 id, default gpu0; run-guest.sh -g 2: gpu1 is the second
                                 card); FILE *.png -> PNG, else PPM
  key KEY...                     press and release each KEY in turn; KEY is a QEMU
                                 qcode (a, 1, ret, esc, spc, up, f1, ...) or several
                                 joined by '+', held together (ctrl+alt+f2)
  type TEXT                      type lowercase letters, digits and spaces
  rel DX DY                      relative motion (virtio mouse)
  abs X Y [HEAD]                 absolute position, 0..32767 (virtio tablet; with
                                 HEAD: a tablet bound to that head of gpu0)
  click [BUTTON] [down|up] [HEAD]  left (default), right, middle, wheel-up, wheel-down;
                                 no down/up: press and release. Buttons go to the
                                 pointer device qemu calls current (see `mouse`; at boot
                                 the virtio tablet), with HEAD to a tablet bound to it
  mouse DEVICE                   make DEVICE the current pointer (gets the buttons and
                                 the wheel): mouse (the virtio mouse), tablet (the first
                                 virtio tablet), an index or a name from query-mice;
                                 prints "INDEX NAME"
  expect FILE REGEX SECS CMD [ARGS...]  run CMD (any command above), then wait until a
                                 line matching REGEX (Python re.search) is appended to
                                 FILE (e.g. a guest log in the share); prints "MS LINE",
                                 MS = milliseconds from before CMD to the line seen;
                                 exit 1 if it is not there within SECS
  raw JSON                       any QMP command, prints the return value
  quit                           stop qemu now
usage: qmp.py compare A B [TOL]  images (PPM P6, PNG or BMP); prints how many pixels differ
                                 by more than TOL (default 0) in a channel; exit 1 if any
usage: qmp.py match DUMP REF...  prints "I REF" for the first REF (I from 0) whose decoded
                                 RGB equals DUMP's exactly; exit 1 if none, printing the
                                 closest REF, its count of differing pixels and their rows,
                                 and whether every row equals a row of some REF (a mix of
                                 frames: tearing)
usage: qmp.py solid FILE RRGGBB [TOL]  exit 0 if every pixel is that colour
usage: qmp.py colors FILE [N]    size and the N (default 5) most common colours
usage: qmp.py evdev FILE         decode struct input_event records (x86-64) that
                                 were read from /dev/input/eventN: "type code value"
Exit status: 0 ok, 1 check failed, 2 usage, 3 QMP or I/O error.
"""
import collections
import json
import os
import re
import socket
import struct
import sys
import time
import zlib


class QMPError(Exception):
    pass


class QMP:
    """One QMP session on a unix socket: greeting, capabilities, commands."""

    def __init__(self, path, timeout=30.0):
        self.sock = socket.socket(socket.AF_UNIX, socket.SOCK_STREAM)
        self.sock.settimeout(timeout)
        self.sock.connect(path)
        self.rfile = self.sock.makefile("rb")
        self.next_id = 0
        greeting = self._message()
        if "QMP" not in greeting:
            raise QMPError(f"not a QMP greeting: {greeting}")
        self.execute("qmp_capabilities")

    def close(self):
        self.rfile.close()
        self.sock.close()

    def _message(self):
        line = self.rfile.readline()
        if not line:
            raise QMPError("QMP connection closed by qemu")
        return json.loads(line)

    def execute(self, command, **arguments):
        self.next_id += 1
        request = {"execute": command, "id": self.next_id}
        if arguments:
            request["arguments"] = arguments
        self.sock.sendall(json.dumps(request).encode() + b"\r\n")
        while True:
            msg = self._message()
            if msg.get("id") != self.next_id:
                continue  # asynchronous events
            if "error" in msg:
                err = msg["error"]
                raise QMPError(f"{command}: {err.get('class')}: {err.get('desc')}")
            return msg.get("return")

    def send_events(self, events, **where):
        return self.execute("input-send-event", events=events, **where)


def key_event(qcode, down):
    return {"type": "key", "data": {"down": down, "key": {"type": "qcode", "data": qcode}}}


def button_event(button, down):
    return {"type": "btn", "data": {"down": down, "button": button}}


def axis_events(kind, x, y):
    return [{"type": kind, "data": {"axis": "x", "value": x}},
            {"type": kind, "data": {"axis": "y", "value": y}}]


def connect_retry(path, secs):
    deadline = time.monotonic() + secs
    while True:
        try:
            return QMP(path)
        except (FileNotFoundError, ConnectionRefusedError, QMPError, socket.timeout):
            if time.monotonic() >= deadline:
                raise
            time.sleep(0.1)


# ---------------------------------------------------------------- images
def _ppm(data, path):
    fields, pos = [], 2
    while len(fields) < 3:
        while pos < len(data) and data[pos:pos + 1].isspace():
            pos += 1
        if data[pos:pos + 1] == b"#":
            pos = data.index(b"\n", pos) + 1
            continue
        start = pos
        while pos < len(data) and not data[pos:pos + 1].isspace():
            pos += 1
        fields.append(int(data[start:pos]))
    width, height, maxval = fields
    if maxval != 255:
        raise ValueError(f"{path}: only 8-bit PPM is supported")
    pos += 1  # the single whitespace after maxval
    pixels = data[pos:pos + width * height * 3]
    if len(pixels) != width * height * 3:
        raise ValueError(f"{path}: truncated PPM")
    return width, height, pixels


def _paeth(a, b, c):
    p = a + b - c
    pa, pb, pc = abs(p - a), abs(p - b), abs(p - c)
    if pa <= pb and pa <= pc:
        return a
    return b if pb <= pc else c


def _png(data, path):
    pos, chunks, header = 8, [], None
    while pos + 8 <= len(data):
        length, kind = struct.unpack(">I4s", data[pos:pos + 8])
        body = data[pos + 8:pos + 8 + length]
        if kind == b"IHDR":
            header = struct.unpack(">IIBBBBB", body)
        elif kind == b"IDAT":
            chunks.append(body)
        elif kind == b"IEND":
            break
        pos += 12 + length
    if header is None:
        raise ValueError(f"{path}: PNG without IHDR")
    width, height, depth, ctype, _, _, interlace = header
    if depth != 8 or ctype not in (2, 6) or interlace:
        raise ValueError(f"{path}: only 8-bit RGB/RGBA non-interlaced PNG is supported")
    bpp = 3 if ctype == 2 else 4
    stride = width * bpp
    raw = zlib.decompress(b"".join(chunks))
    prev = bytearray(stride)
    out = bytearray()
    for y in range(height):
        base = y * (stride + 1)
        ftype = raw[base]
        row = bytearray(raw[base + 1:base + 1 + stride])
        if ftype == 1:
            for i in range(bpp, stride):
                row[i] = (row[i] + row[i - bpp]) & 255
        elif ftype == 2:
            for i in range(stride):
                row[i] = (row[i] + prev[i]) & 255
        elif ftype == 3:
            for i in range(stride):
                left = row[i - bpp] if i >= bpp else 0
                row[i] = (row[i] + ((left + prev[i]) >> 1)) & 255
        elif ftype == 4:
            for i in range(stride):
                left = row[i - bpp] if i >= bpp else 0
                upleft = prev[i - bpp] if i >= bpp else 0
                row[i] = (row[i] + _paeth(left, prev[i], upleft)) & 255
        elif ftype != 0:
            raise ValueError(f"{path}: bad PNG filter {ftype}")
        if bpp == 3:
            out += row
        else:
            for i in range(0, stride, 4):
                out += row[i:i + 3]
        prev = row
    return width, height, bytes(out)


def _bmp(data, path):
    """Uncompressed 24-bit or 32-bit (BGRX) BMP, bottom-up or top-down."""
    offset, header_bytes = struct.unpack("<I", data[10:14])[0], struct.unpack("<I", data[14:18])[0]
    if header_bytes < 40:
        raise ValueError(f"{path}: unsupported BMP header ({header_bytes} bytes)")
    width, height, _, bits, compression = struct.unpack("<iiHHI", data[18:34])
    if bits not in (24, 32) or compression not in (0, 3) or (compression == 3 and bits != 32) or width <= 0:
        raise ValueError(f"{path}: only uncompressed 24/32-bit BMP is supported")
    bpp = bits // 8
    stride = (width * bpp + 3) & ~3
    rows = abs(height)
    if len(data) < offset + stride * rows:
        raise ValueError(f"{path}: truncated BMP")
    order = range(rows - 1, -1, -1) if height > 0 else range(rows)  # positive height: bottom row first
    packed = b"".join(data[offset + y * stride:offset + y * stride + width * bpp] for y in order)
    rgb = bytearray(width * rows * 3)
    for c in range(3):  # stored B, G, R(, X)
        rgb[2 - c::3] = packed[c::bpp]
    return width, rows, bytes(rgb)


def read_image(path):
    """(width, height, RGB bytes) of a P6 PPM, an 8-bit PNG or an uncompressed BMP."""
    with open(path, "rb") as f:
        data = f.read()
    if data[:2] == b"P6":
        return _ppm(data, path)
    if data[:8] == b"\x89PNG\r\n\x1a\n":
        return _png(data, path)
    if data[:2] == b"BM":
        return _bmp(data, path)
    raise ValueError(f"{path}: neither a P6 PPM, a PNG nor a BMP")


def compare(path_a, path_b, tol=0):
    wa, ha, a = read_image(path_a)
    wb, hb, b = read_image(path_b)
    if (wa, ha) != (wb, hb):
        print(f"size differs: {path_a} is {wa}x{ha}, {path_b} is {wb}x{hb}")
        return 1
    bad, worst, first = 0, 0, None
    if a != b:
        for i in range(0, len(a), 3):
            if a[i:i + 3] == b[i:i + 3]:
                continue
            d = max(abs(a[i] - b[i]), abs(a[i + 1] - b[i + 1]), abs(a[i + 2] - b[i + 2]))
            worst = max(worst, d)
            if d > tol:
                bad += 1
                if first is None:
                    first = (i // 3 % wa, i // 3 // wa, a[i:i + 3].hex(), b[i:i + 3].hex())
    msg = f"{bad} of {wa * ha} pixels differ" + (f" by more than {tol}" if tol else "")
    if worst:
        msg += f" (largest channel difference {worst})"
    if first:
        msg += f"; first at x={first[0]} y={first[1]}: {first[2]} vs {first[3]}"
    print(msg)
    return 1 if bad else 0


_NONZERO = bytes([0] + [1] * 255)


def differing_pixels(a, b):
    """Per pixel of two RGB byte strings of one size: b"\\x01" where they differ, else b"\\x00"."""
    x = (int.from_bytes(a, "little") ^ int.from_bytes(b, "little")).to_bytes(len(a), "little")
    nz = x.translate(_NONZERO)
    n = len(a) // 3
    return (int.from_bytes(nz[0::3], "little") | int.from_bytes(nz[1::3], "little") |
            int.from_bytes(nz[2::3], "little")).to_bytes(n, "little")


def match(dump, refs):
    """Index of the reference image identical to dump (exact RGB), else 1 and why not."""
    w, h, px = read_image(dump)
    images = []
    for i, ref in enumerate(refs):
        rw, rh, rpx = read_image(ref)
        if (rw, rh) == (w, h) and rpx == px:
            print(f"{i} {ref}")
            return 0
        images.append(rpx if (rw, rh) == (w, h) else None)
    best = None  # (differing pixels, index, first row, last row)
    for i, rpx in enumerate(images):
        if rpx is None:
            continue
        diff = differing_pixels(px, rpx)
        n = len(diff) - diff.count(0)
        if best is None or n < best[0]:
            first = len(diff) - len(diff.lstrip(b"\0"))
            last = len(diff.rstrip(b"\0")) - 1
            best = (n, i, first // w, last // w)
    if best is None:
        print(f"no reference is identical to {dump} ({w}x{h}): none has its size")
        return 1
    n, i, y0, y1 = best
    msg = (f"no reference is identical to {dump}; closest: {i} {refs[i]}: {n} of {w * h} pixels differ, "
           f"in rows {y0}..{y1}")
    # a mix of frames (tearing): does every row equal that row of some reference?
    # (rows many references share, such as background, go to the current run, else to the closest)
    stride, runs = w * 3, []
    for y in range(h):
        row = px[y * stride:(y + 1) * stride]
        order = ([runs[-1][0]] if runs else []) + [i] + list(range(len(images)))
        hit = next((k for k in order if images[k] is not None and images[k][y * stride:(y + 1) * stride] == row),
                   None)
        if hit is None:
            runs = None
            break
        if runs and runs[-1][0] == hit:
            runs[-1][2] = y
        else:
            runs.append([hit, y, y])
    if runs and len(runs) > 1:
        msg += "; every row equals a reference's row: " + ", ".join(f"rows {a}..{b} = {k}" for k, a, b in runs)
    print(msg)
    return 1


def colour_counts(path):
    w, h, px = read_image(path)
    counts = collections.Counter(px[i:i + 3] for i in range(0, len(px), 3))
    return w, h, counts


def solid(path, hexrgb, tol=0):
    want = bytes.fromhex(hexrgb)
    w, h, counts = colour_counts(path)
    off = sum(n for c, n in counts.items()
              if max(abs(c[k] - want[k]) for k in range(3)) > tol)
    common = ", ".join(f"{c.hex()} x{n}" for c, n in counts.most_common(3))
    print(f"{path}: {w}x{h}, {off} of {w * h} pixels are not {hexrgb}; most common: {common}")
    return 1 if off else 0


def colors(path, n=5):
    w, h, counts = colour_counts(path)
    print(f"{w}x{h} " + " ".join(f"{c.hex()}:{k}" for c, k in counts.most_common(n)))
    return 0


def evdev(path):
    # struct input_event on x86-64: struct timeval (2 x 8 bytes), u16 type, u16 code, s32 value
    with open(path, "rb") as f:
        data = f.read()
    for off in range(0, len(data) - len(data) % 24, 24):
        _, _, etype, code, value = struct.unpack("<qqHHi", data[off:off + 24])
        print(etype, code, value)
    return 0


# ---------------------------------------------------------------- commands
BUTTONS = ("left", "right", "middle", "wheel-up", "wheel-down", "side", "extra")


def pick_mouse(mice, want):
    """(index, name) of the query-mice entry meant by want (see `mouse` in the usage)."""
    names = {"mouse": "QEMU Virtio Mouse", "tablet": "QEMU Virtio Tablet"}
    for m in sorted(mice, key=lambda m: m["index"]):
        if str(m["index"]) == want or m["name"] == names.get(want, want):
            return m["index"], m["name"]
    raise QMPError(f"no pointer device '{want}' in query-mice: " +
                   ", ".join(f"{m['index']} {m['name']}" for m in mice))


def expect(sock, path, pattern, secs, op, args):
    """run op, then wait for a line matching pattern appended to path (see usage)."""
    regex = re.compile(pattern)
    offset = os.path.getsize(path) if os.path.exists(path) else 0
    t0 = time.monotonic()
    rc = run(sock, op, args)
    if rc:
        return rc
    pending = b""
    while True:
        try:
            with open(path, "rb") as f:
                f.seek(offset)
                chunk = f.read()
        except FileNotFoundError:
            chunk = b""
        offset += len(chunk)
        pending += chunk
        *lines, pending = pending.split(b"\n")
        for raw_line in lines:
            line = raw_line.decode(errors="replace")
            if regex.search(line):
                print(f"{(time.monotonic() - t0) * 1000:.0f} {line}")
                return 0
        if time.monotonic() - t0 > secs:
            print(f"qmp.py: no line matching '{pattern}' in {path} within {secs:g} s", file=sys.stderr)
            return 1
        time.sleep(0.005)


def run(sock, op, args):
    if op == "wait":
        connect_retry(sock, float(args[0]) if args else 30.0).close()
        return 0
    if op == "expect":
        if len(args) < 4:
            return usage()
        return expect(sock, args[0], args[1], float(args[2]), args[3], args[4:])
    q = QMP(sock)
    try:
        if op == "screendump":
            if not args:
                return usage()
            kw = {"filename": os.path.abspath(args[0]), "device": args[2] if len(args) > 2 else "gpu0",
                  "head": int(args[1]) if len(args) > 1 else 0}
            if args[0].lower().endswith(".png"):
                kw["format"] = "png"
            q.execute("screendump", **kw)
        elif op == "key":
            for combo in args:
                keys = combo.split("+")
                q.send_events([key_event(k, True) for k in keys])
                q.send_events([key_event(k, False) for k in reversed(keys)])
        elif op == "type":
            for ch in " ".join(args):
                k = "spc" if ch == " " else ch
                q.send_events([key_event(k, True)])
                q.send_events([key_event(k, False)])
        elif op == "rel":
            q.send_events(axis_events("rel", int(args[0]), int(args[1])))
        elif op == "abs":
            where = {"device": "gpu0", "head": int(args[2])} if len(args) > 2 else {}
            q.send_events(axis_events("abs", int(args[0]), int(args[1])), **where)
        elif op == "click":
            args = list(args)
            where = {"device": "gpu0", "head": int(args.pop())} if args and args[-1].isdigit() else {}
            button = args[0] if args else "left"
            if button not in BUTTONS:
                return usage()
            phases = {"down": [True], "up": [False]}.get(args[1] if len(args) > 1 else "", [True, False])
            for down in phases:
                q.send_events([button_event(button, down)], **where)
        elif op == "mouse":
            index, name = pick_mouse(q.execute("query-mice"), args[0])
            out = q.execute("human-monitor-command", **{"command-line": f"mouse_set {index}"})
            if out:
                raise QMPError(f"mouse_set {index}: {out.strip()}")
            print(index, name)
        elif op == "raw":
            req = json.loads(args[0])
            print(json.dumps(q.execute(req["execute"], **req.get("arguments", {}))))
        elif op == "quit":
            try:
                q.execute("quit")
            except (QMPError, OSError):
                pass  # qemu may close the socket before it answers
        else:
            return usage()
    finally:
        q.close()
    return 0


def usage():
    print(__doc__, file=sys.stderr)
    return 2


def main(argv):
    try:
        if argv and argv[0] == "compare" and len(argv) in (3, 4):
            return compare(argv[1], argv[2], int(argv[3]) if len(argv) > 3 else 0)
        if argv and argv[0] == "match" and len(argv) >= 3:
            return match(argv[1], argv[2:])
        if argv and argv[0] == "solid" and len(argv) in (3, 4):
            return solid(argv[1], argv[2], int(argv[3]) if len(argv) > 3 else 0)
        if argv and argv[0] == "colors" and len(argv) in (2, 3):
            return colors(argv[1], int(argv[2]) if len(argv) > 2 else 5)
        if argv and argv[0] == "evdev" and len(argv) == 2:
            return evdev(argv[1])
        if len(argv) < 2:
            return usage()
        return run(argv[0], argv[1], argv[2:])
    except (IndexError, ValueError) as e:
        print(f"qmp.py: {e}", file=sys.stderr)
        return 2
    except BrokenPipeError:
        raise
    except (QMPError, OSError, socket.timeout) as e:
        print(f"qmp.py: {e}", file=sys.stderr)
        return 3


if __name__ == "__main__":
    try:
        status = main(sys.argv[1:])
        sys.stdout.flush()
    except BrokenPipeError:  # e.g. "qmp.py evdev F | grep -q ..."
        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
        status = 0
    sys.exit(status)
