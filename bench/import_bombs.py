#!/usr/bin/env python3
"""The import bombs of issue "Safe to share" at their full size, each run in a child
`anatomy-tutor` whose peak resident memory (ru_maxrss from wait4) and wall time are printed:

  * a course package (the shipped temporal_bone course, exported) with 64 presets of 16 MiB of
    spaces each, re-checksummed and gzip-compressed (~1 GiB inflated);
  * an .inv3 with 10,000 members of 100 KB names before main.plist (~1 GB inflated);
  * an .inv3 whose main.plist nests 60,000 (XML) or 100,000 (binary) levels: as deep as fits the
    1 MiB main.plist cap (the issue's 200,000 levels are now refused by that cap first).

usage: bench/import_bombs.py [--app build/app/anatomy-tutor] [--work DIR]
Every case must end in a one-line refusal (exit 1) under 200 MB; the script says so and exits 1
otherwise. The files are written to --work (default: a temporary folder, removed at the end).
"""
import argparse
import gzip
import hashlib
import io
import json
import os
import shutil
import struct
import subprocess
import sys
import tarfile
import tempfile
import time

LIMIT_KIB = 200 * 1024


def run(app, args):
    # GNU time reports the program's own peak (a child forked from this Python process would
    # count Python's pages as its own until it execs).
    start = time.monotonic()
    proc = subprocess.run(["/usr/bin/time", "-f", "%M", app] + args, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)
    seconds = time.monotonic() - start
    lines = proc.stderr.decode(errors="replace").splitlines()
    peak = int(lines[-1])
    err = "".join(l + "\n" for l in lines[:-1] if not l.startswith("Command exited"))
    return proc.returncode, peak, seconds, err


def add(tar, name, data):
    info = tarfile.TarInfo(name)
    info.size = len(data)
    tar.addfile(info, io.BytesIO(data))


def package_bomb(app, work):
    db = os.path.join(work, "author.db")
    base = os.path.join(work, "temporal_bone.atcourse")
    subprocess.run([app, "course", "export", "temporal_bone", "--out", base, "--db", db], check=True,
                   stdout=subprocess.DEVNULL)
    entries = []
    with tarfile.open(base) as t:
        for m in t.getmembers():
            entries.append((m.name, t.extractfile(m).read()))
    padding = b"{" + b" " * (16 << 20) + b"}"
    entries += [(f"presets/bomb{i}.json", padding) for i in range(64)]
    manifest = json.loads(dict(entries)["manifest.json"])
    manifest["files"] = [{"path": n, "size": len(d), "sha256": hashlib.sha256(d).hexdigest()}
                         for n, d in entries if n != "manifest.json"]
    entries[0] = ("manifest.json", json.dumps(manifest).encode())
    out = os.path.join(work, "bomb.atcourse")
    with tarfile.open(out, "w:gz", format=tarfile.PAX_FORMAT, compresslevel=9) as t:
        for n, d in entries:
            add(t, n, d)
    return out


def plist_xml(depth):
    return (b'<?xml version="1.0" encoding="UTF-8"?>\n<plist version="1.0"><dict><key>matrix</key>' +
            b"<array>" * depth + b"</array>" * depth + b"</dict></plist>\n")


def plist_binary(depth):
    body, offsets = bytearray(b"bplist00"), []
    for i in range(depth):
        offsets.append(len(body))
        body += (b"\xa1" + struct.pack(">I", i + 1)) if i + 1 < depth else b"\xa0"
    table = len(body)
    for o in offsets:
        body += struct.pack(">I", o)
    body += bytes(6) + bytes([4, 4]) + struct.pack(">QQQ", depth, 0, table)
    return bytes(body)


def inv3(path, members):
    with tarfile.open(path, "w:gz", format=tarfile.PAX_FORMAT, compresslevel=1) as t:
        for n, d in members:
            add(t, n, d)
    return path


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--app", default="build/app/anatomy-tutor")
    parser.add_argument("--work")
    a = parser.parse_args()
    work = a.work or tempfile.mkdtemp(prefix="at-bombs-")
    os.makedirs(work, exist_ok=True)
    matrix = bytes(3 * 5 * 7 * 2)
    plist_ok = (b'<?xml version="1.0"?><plist version="1.0"><dict><key>matrix</key><dict><key>dtype</key>'
                b"<string>int16</string><key>filename</key><string>matrix.dat</string><key>shape</key><array>"
                b"<integer>3</integer><integer>5</integer><integer>7</integer></array></dict><key>spacing</key>"
                b"<array><real>1</real><real>1</real><real>1</real></array></dict></plist>")
    cases = []
    t0 = time.monotonic()
    bomb = package_bomb(a.app, work)
    cases.append(("package: 64 presets of 16 MiB spaces", bomb,
                  ["course", "import", bomb, "--db", os.path.join(work, "student.db")]))
    names = inv3(os.path.join(work, "names.inv3"),
                 [("n%05d" % i + "a" * 100000, b"") for i in range(10000)] +
                 [("p/main.plist", plist_ok), ("p/matrix.dat", matrix)])
    cases.append((".inv3: 10,000 members with 100 KB names", names, ["info", names]))
    # As deep as fits the 1 MiB main.plist cap (deeper ones are refused by their size first).
    for kind, data in (("XML", plist_xml(60000)), ("binary", plist_binary(100000))):
        path = inv3(os.path.join(work, f"deep-{kind}.inv3"), [("p/main.plist", data), ("p/matrix.dat", matrix)])
        cases.append((f".inv3: main.plist nested {'60,000' if kind == 'XML' else '100,000'} levels ({kind})", path, ["info", path]))
        cases.append((f"import of the same", path, ["import", "--volume", path, "--name", "deep", "--db",
                                                    os.path.join(work, "student.db")]))
    print(f"(bomb files written in {time.monotonic() - t0:.1f} s)")
    ok = True
    for what, file, args in cases:
        code, peak, seconds, err = run(a.app, args)
        good = code == 1 and err.count("\n") == 1 and peak < LIMIT_KIB
        ok = ok and good
        print(f"{what}: {os.path.getsize(file)} bytes; exit {code}; peak {peak / 1024:.1f} MiB; {seconds:.2f} s; "
              f"{'ok' if good else 'FAILED'}\n    {err.strip()[:200]}")
    if not a.work:
        shutil.rmtree(work)
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
