#!/usr/bin/env python3
"""A picture of a peridynamic run's damage (or any scalar point array) from one of its
.vtu files, for the docs: each node a square of the node spacing, white (0) to dark red
(1), written as PNG with numpy and zlib only (no plotting library).

The .vtu files mlsm writes (src/output/vtk.rs) hold each array inline in base64, one
little-endian UInt64 byte count, then the values.

Usage: python3 benches/damage_png.py RUN.vtu OUT.png [--field damage] [--scale PIXELS_PER_SPACING]"""
import argparse, base64, re, struct, zlib
import numpy as np


def array(xml, name):
    """The values of the DataArray called `name` (Points: `name = None`)."""
    if name is None:
        m = re.search(r"<Points><DataArray[^>]*>([^<]*)</DataArray>", xml)
    else:
        m = re.search(r'<DataArray[^>]*Name="%s"[^>]*>([^<]*)</DataArray>' % re.escape(name), xml)
    if not m:
        raise SystemExit(f"no array {name or 'Points'} in the file")
    raw = base64.b64decode(m.group(1).strip())
    (count,) = struct.unpack("<Q", raw[:8])
    return np.frombuffer(raw[8 : 8 + count], dtype="<f8")


def png(path, rgb):
    """Write an 8-bit RGB image (rows top to bottom)."""
    h, w, _ = rgb.shape
    rows = b"".join(b"\x00" + rgb[r].astype(np.uint8).tobytes() for r in range(h))
    chunk = lambda kind, data: struct.pack(">I", len(data)) + kind + data + struct.pack(">I", zlib.crc32(kind + data) & 0xFFFFFFFF)
    header = struct.pack(">IIBBBBB", w, h, 8, 2, 0, 0, 0)
    open(path, "wb").write(b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", header) + chunk(b"IDAT", zlib.compress(rows, 9)) + chunk(b"IEND", b""))


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("vtu")
    ap.add_argument("out")
    ap.add_argument("--field", default="damage")
    ap.add_argument("--scale", type=int, default=6)
    a = ap.parse_args()
    xml = open(a.vtu).read()
    p = array(xml, None).reshape(-1, 3)[:, :2]
    v = array(xml, a.field)
    # Each node paints a square of the mean spacing (sqrt of the box area per node), so
    # that grids and Gauss points (two gaps per cell) both fill the solid.
    lo, hi = p.min(axis=0), p.max(axis=0)
    h = np.sqrt((hi - lo).prod() / len(p))
    px = h / a.scale
    w, ht = int(np.ceil((hi[0] - lo[0] + h) / px)), int(np.ceil((hi[1] - lo[1] + h) / px))
    img = np.full((ht, w, 3), 235.0)  # background: light grey (no node)
    t = np.clip(v, 0.0, 1.0)[:, None]
    white, red = np.array([255.0, 255.0, 255.0]), np.array([150.0, 0.0, 0.0])
    colour = white * (1 - t) + red * t
    # Paint the least damaged first, so that damage is never hidden by an overlap.
    for k in np.argsort(v):
        x0, y0 = int((p[k, 0] - lo[0]) / px), int((p[k, 1] - lo[1]) / px)
        img[max(ht - y0 - a.scale - 1, 0) : ht - y0, x0 : x0 + a.scale + 1] = colour[k]
    png(a.out, img)
    print(f"{a.out}: {len(v)} nodes, spacing {h:.3e}, {a.field} from {v.min():.3f} to {v.max():.3f}")


if __name__ == "__main__":
    main()
