#!/usr/bin/env python3
"""PNGs of diffrender's AOVs (docs/DIFFRENDER.md), in pure Python (no numpy, PIL or OpenEXR).

  diffrender_aov_png.py delta AOVS BASE.exr OUT.png [--scale S]
      dL (AOVS/diffrender_delta.exr, at 1/delta_scale, each sample drawn as a block) over a dim
      grey of BASE's luminance on scan pixels (AOVS/diffrender_mask.exr): blue where the inserted
      meshes darken the scan, red where they brighten it, full colour at |dL| = S (luminance,
      linear; default 0.25); the inserted meshes' pixels dimmer grey, the rest black.
  diffrender_aov_png.py rho AOVS OUT.png
      The material estimate (AOVS/diffrender_rho.exr), linear rho through the sRGB curve;
      magenta where a channel reached rho_max = 1 (clamped); black off the scan.
  diffrender_aov_png.py diff BEFORE.exr AFTER.exr MASK.exr OUT.png [--scale S]
      The composite's change on scan pixels (mask 1), AFTER - BEFORE, coloured as `delta`;
      the inserted meshes' pixels (mask 2) dim grey.

Reads scanline EXRs with NONE, RLE, ZIPS or ZIP compression and HALF, FLOAT or UINT channels
(what nestlight writes).
"""
import struct
import sys
import zlib


def _cstr(f):
    s = b""
    while True:
        c = f.read(1)
        if c in (b"\0", b""):
            return s.decode()
        s += c


def _unpredict(t):
    for i in range(1, len(t)):
        t[i] = (t[i - 1] + t[i] - 128) & 255
    half = (len(t) + 1) // 2
    u = bytearray(len(t))
    u[0::2], u[1::2] = t[:half], t[half:]
    return bytes(u)


def read_exr(path):
    """(width, height, {channel: [floats]}) of a scanline EXR."""
    with open(path, "rb") as f:
        if f.read(4) != b"\x76\x2f\x31\x01":
            raise ValueError(path + ": not an OpenEXR file")
        if struct.unpack("<I", f.read(4))[0] & 0x200:
            raise ValueError(path + ": tiled EXRs are not supported")
        attrs = {}
        while True:
            name = _cstr(f)
            if not name:
                break
            _cstr(f)
            size = struct.unpack("<i", f.read(4))[0]
            attrs[name] = f.read(size)
        chs, data, i = [], attrs["channels"], 0
        while data[i] != 0:
            j = data.index(b"\0", i)
            chs.append((data[i:j].decode(), struct.unpack("<i", data[j + 1:j + 5])[0]))
            i = j + 17
        chs.sort()
        comp = attrs["compression"][0]
        lines = {0: 1, 1: 1, 2: 1, 3: 16}.get(comp)
        if lines is None:
            raise ValueError("%s: compression %d is not supported" % (path, comp))
        x0, y0, x1, y1 = struct.unpack("<4i", attrs["dataWindow"])
        w, h = x1 - x0 + 1, y1 - y0 + 1
        blocks = (h + lines - 1) // lines
        offsets = struct.unpack("<%dQ" % blocks, f.read(8 * blocks))
        img = {c: [0.0] * (w * h) for c, _ in chs}
        for o in offsets:
            f.seek(o)
            y, size = struct.unpack("<ii", f.read(8))
            d = f.read(size)
            n = min(lines, y1 + 1 - y)
            raw = sum(w * (2 if t == 1 else 4) for _, t in chs) * n
            if size < raw and comp in (2, 3):
                d = _unpredict(bytearray(zlib.decompress(d)))
            elif size < raw and comp == 1:
                out, k = bytearray(), 0
                while k < len(d):
                    c = struct.unpack("b", d[k:k + 1])[0]
                    k += 1
                    if c < 0:
                        out += d[k:k - c]
                        k -= c
                    else:
                        out += d[k:k + 1] * (c + 1)
                        k += 1
                d = _unpredict(out)
            p = 0
            for line in range(n):
                row = (y - y0 + line) * w
                for c, t in chs:
                    fmt, size1 = ("e", 2) if t == 1 else ("f", 4) if t == 2 else ("I", 4)
                    img[c][row:row + w] = struct.unpack("<%d%s" % (w, fmt), d[p:p + size1 * w])
                    p += size1 * w
        return w, h, img


def write_png(path, w, h, pixels):
    """pixels: (r, g, b) in [0, 1], row-major; written through the sRGB curve."""

    def enc(v):
        v = min(max(v, 0.0), 1.0)
        return int(round(255 * (12.92 * v if v <= 0.0031308 else 1.055 * v ** (1 / 2.4) - 0.055)))

    raw = bytearray()
    for y in range(h):
        raw.append(0)
        for px in pixels[y * w:(y + 1) * w]:
            raw += bytes(enc(c) for c in px)

    def chunk(t, d):
        return struct.pack(">I", len(d)) + t + d + struct.pack(">I", zlib.crc32(t + d) & 0xFFFFFFFF)

    with open(path, "wb") as f:
        f.write(b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", w, h, 8, 2, 0, 0, 0)))
        f.write(chunk(b"IDAT", zlib.compress(bytes(raw), 9)) + chunk(b"IEND", b""))


def lum(img, i):
    return 0.2126 * img["R"][i] + 0.7152 * img["G"][i] + 0.0722 * img["B"][i]


def signed(grey, v):
    """Dim grey, towards blue for v < 0 and red for v > 0 (|v| = 1: full)."""
    g = 0.25 * min(1.0, grey * 1.2)
    a = min(1.0, abs(v))
    if v < 0:
        return (g * (1 - a), g * (1 - a), g + a * (1 - g))
    if v > 0:
        return (g + a * (1 - g), g * (1 - a), g * (1 - a))
    return (g, g, g)


def main(argv):
    scale = 0.25
    if "--scale" in argv:
        k = argv.index("--scale")
        scale = float(argv[k + 1])
        argv = argv[:k] + argv[k + 2:]
    if len(argv) < 2:
        sys.exit(__doc__)
    what, args = argv[0], argv[1:]
    if what == "delta" and len(args) == 3:
        dw, dh, d = read_exr(args[0] + "/diffrender_delta.exr")
        w, h, base = read_exr(args[1])
        _, _, m = read_exr(args[0] + "/diffrender_mask.exr")
        s = max(1, w // dw)
        px = []
        for y in range(h):
            for x in range(w):
                i, k = y * w + x, m["R"][y * w + x]
                if k == 1:
                    px.append(signed(lum(base, i), lum(d, min(y // s, dh - 1) * dw + min(x // s, dw - 1)) / scale))
                else:
                    g = 0.15 * min(1.0, lum(base, i) * 1.2) if k == 2 else 0.003
                    px.append((g, g, g))
        write_png(args[2], w, h, px)
    elif what == "rho" and len(args) == 2:
        w, h, r = read_exr(args[0] + "/diffrender_rho.exr")
        px = [(1.0, 0.0, 1.0) if max(r[c][i] for c in "RGB") >= 0.999 else (r["R"][i], r["G"][i], r["B"][i])
              for i in range(w * h)]
        write_png(args[1], w, h, px)
    elif what == "diff" and len(args) == 4:
        w, h, b = read_exr(args[0])
        _, _, a = read_exr(args[1])
        _, _, m = read_exr(args[2])
        px = []
        for i in range(w * h):
            k = m["R"][i]
            if k == 1:
                px.append(signed(lum(b, i), (lum(a, i) - lum(b, i)) / scale))
            elif k == 2:
                g = 0.15 * min(1.0, lum(b, i) * 1.2)
                px.append((g, g, g))
            else:
                px.append((0.003, 0.003, 0.003))
        write_png(args[3], w, h, px)
    else:
        sys.exit(__doc__)


if __name__ == "__main__":
    main(sys.argv[1:])
