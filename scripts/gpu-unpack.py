#!/usr/bin/env python3
"""Unpacks a Nestlight GPU bundle (scripts/gpu-bundle.sh) with Python's standard library alone.

    python3 scripts/gpu-unpack.py BUNDLE.tar.xz DEST     -> DEST/nestlight-gpu/run PROGRAM ...

Besides the tar archive it unpacks the Debian packages of the GL loaders the bundle carries
(debs/*.deb: an `ar` archive holding data.tar.xz) into the bundle's gl/ folder, not into /, so a
bare machine gets libglvnd without dpkg and without touching its system folders. Every file is
checked against the bundle's MANIFEST.json (size and SHA-256). Prints the unpacked folder last.
"""
import hashlib
import io
import json
import lzma
import os
import shutil
import sys
import tarfile

LIB_DIRS = ("usr/lib/x86_64-linux-gnu/", "lib/x86_64-linux-gnu/")


def fail(msg):
    print("gpu-unpack: " + msg, file=sys.stderr)
    sys.exit(1)


def safe_extract(tar, dest, members=None):
    # Python 3.12's data filter refuses absolute paths, links out of DEST and device files.
    if hasattr(tarfile, "data_filter"):
        tar.extractall(dest, members=members, filter="data")
        return
    root = os.path.realpath(dest)
    for m in members if members is not None else tar.getmembers():
        target = os.path.realpath(os.path.join(dest, m.name))
        if not target.startswith(root + os.sep) or m.isdev():
            fail("refusing archive member %r" % m.name)
    tar.extractall(dest, members=members)


def ar_members(data, name):
    """The members of an `ar` archive (a .deb): (name, bytes)."""
    if data[:8] != b"!<arch>\n":
        fail("%s is not a Debian package (no ar signature)" % name)
    pos = 8
    while pos + 60 <= len(data):
        header = data[pos:pos + 60]
        member = header[:16].decode("ascii", "replace").strip().rstrip("/")
        try:
            size = int(header[48:58].decode("ascii").strip())
        except ValueError:
            fail("%s: damaged ar header at byte %d" % (name, pos))
        start = pos + 60
        if start + size > len(data):
            fail("%s: member %s runs past the end (byte %d)" % (name, member, start))
        yield member, data[start:start + size]
        pos = start + size + (size & 1)


def unpack_deb(path, gl_dir):
    with open(path, "rb") as f:
        data = f.read()
    payload = None
    for member, body in ar_members(data, path):
        if member.startswith("data.tar"):
            if member.endswith(".zst"):
                fail("%s: data.tar.zst needs zstd, which Python's standard library lacks" % path)
            payload = body
    if payload is None:
        fail("%s holds no data.tar" % path)
    with tarfile.open(fileobj=io.BytesIO(payload), mode="r:*") as tar:
        wanted = []
        for m in tar.getmembers():
            name = m.name[2:] if m.name.startswith("./") else m.name
            for d in LIB_DIRS:
                if name.startswith(d) and "/" not in name[len(d):] and (m.isfile() or m.issym()):
                    m.name = name[len(d):]
                    wanted.append(m)
        safe_extract(tar, gl_dir, wanted)
    return len(wanted)


def main():
    if len(sys.argv) != 3:
        print(__doc__.strip(), file=sys.stderr)
        sys.exit(2)
    bundle, dest = sys.argv[1], sys.argv[2]
    if not os.path.isfile(bundle):
        fail("no bundle at %s (make one with scripts/gpu-bundle.sh)" % bundle)
    os.makedirs(dest, exist_ok=True)
    top = os.path.join(dest, "nestlight-gpu")
    if os.path.exists(top):
        shutil.rmtree(top)
    try:
        with tarfile.open(bundle, "r:*") as tar:
            safe_extract(tar, dest)
    except (tarfile.TarError, lzma.LZMAError, EOFError) as e:
        fail("%s: %s (damaged or truncated bundle)" % (bundle, e))
    manifest = json.load(open(os.path.join(top, "MANIFEST.json")))
    for f in manifest["files"]:
        p = os.path.join(top, f["path"])
        if not os.path.isfile(p) or os.path.getsize(p) != f["bytes"]:
            fail("%s is missing or of the wrong size" % f["path"])
        with open(p, "rb") as fh:
            if hashlib.sha256(fh.read()).hexdigest() != f["sha256"]:
                fail("%s does not match its checksum" % f["path"])
    gl_dir = os.path.join(top, "gl")
    os.makedirs(gl_dir, exist_ok=True)
    libs = 0
    for deb in sorted(os.listdir(os.path.join(top, "debs"))):
        if deb.endswith(".deb"):
            libs += unpack_deb(os.path.join(top, "debs", deb), gl_dir)
    print("gpu-unpack: %d files checked, %d GL loader files from %s; commit %s%s" %
          (len(manifest["files"]), libs, ", ".join(sorted(os.listdir(os.path.join(top, "debs")))),
           manifest["commit"][:12], " (with uncommitted changes)" if manifest.get("dirty") == "true" else ""),
          file=sys.stderr)
    print(os.path.abspath(top))


if __name__ == "__main__":
    main()
