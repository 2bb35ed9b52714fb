"""The VDB writer's speed under two builds of firncore (e.g. its io files at -O3 and at -O1), in one run, and whether
they write the same bytes. Each FILE (a baked .vdb: the car's, a suite case's from bench/suite_grids.py) is rewritten
by `firncore.remove_grids` (all of it read, then every grid but the last written back through the core's VDB archive,
writeVdbArchive, as a bake writes its grids); the same call naming no grid it holds reads the file and writes nothing,
so the write's own seconds are the difference. Builds alternate A B B A ..., each run in a fresh process.

    /usr/bin/python3 bench/vdb_write_bench.py --builds A_PYTHONPATH,B_PYTHONPATH [--repeats N] FILE [FILE ...]

Prints per run and file the read, read + write and write seconds (wall, and processor: all threads), then per file each
build's median write and B/A, and whether the two builds' rewritten files are byte-identical but for the header's
UUID (21 bytes in, 36 long: OpenVDB writes a fresh one per file; tests/cpp/io/vdb_archive_test.cpp).
"""

import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile

HERE = os.path.dirname(os.path.abspath(__file__))
UUID_START, UUID_LENGTH = 21, 36

# One build's run on every file: its timings as a JSON line; the rewritten files kept in `out`.
CHILD = r"""
import json, os, shutil, sys, time
import firncore
out, paths = sys.argv[1], sys.argv[2:]
rows = []
for path in paths:
    copy = os.path.join(out, os.path.basename(path))
    shutil.copy(path, copy)
    w0, c0 = time.perf_counter(), time.process_time()
    assert firncore.remove_grids(copy, ["no grid of this name"]) == []
    w1, c1 = time.perf_counter(), time.process_time()
    last = firncore.grid_names(copy)[-1]
    assert firncore.remove_grids(copy, [last]) == [last]
    w2, c2 = time.perf_counter(), time.process_time()
    rows.append({"file": path, "read": [w1 - w0, c1 - c0], "both": [w2 - w1, c2 - c1]})
print(json.dumps(rows))
"""


def run(pythonpath, paths, out):
    env = dict(os.environ, PYTHONPATH=pythonpath)
    done = subprocess.run([sys.executable, "-c", CHILD, out, *paths], env=env, check=True, capture_output=True,
                          text=True)
    return json.loads(done.stdout.strip().splitlines()[-1])


def without_uuid(path):
    with open(path, "rb") as f:
        data = bytearray(f.read())
    data[UUID_START:UUID_START + UUID_LENGTH] = b"-" * UUID_LENGTH
    return bytes(data)


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--builds", required=True, help="A,B: two PYTHONPATHs holding firncore")
    parser.add_argument("--repeats", type=int, default=3, help="runs of each build (alternating)")
    parser.add_argument("files", nargs="+")
    args = parser.parse_args()
    builds = args.builds.split(",")
    assert len(builds) == 2, "--builds takes two PYTHONPATHs"
    paths = [os.path.abspath(p) for p in args.files]
    order = [k for r in range(args.repeats) for k in ((0, 1) if r % 2 == 0 else (1, 0))]
    writes = {(k, p): [] for k in (0, 1) for p in paths}
    with tempfile.TemporaryDirectory(prefix="vdb_write_bench_") as tmp:
        outs = [os.path.join(tmp, "A"), os.path.join(tmp, "B")]
        for out in outs:
            os.makedirs(out)
        for k in order:
            for row in run(builds[k], paths, outs[k]):
                (rw, rc), (bw, bc) = row["read"], row["both"]
                writes[(k, row["file"])].append((bw - rw, bc - rc))
                print(f"{'AB'[k]}  {os.path.basename(row['file']):24s} read {rw:6.2f} s ({rc:6.2f} cpu)  "
                      f"read+write {bw:6.2f} s ({bc:6.2f} cpu)  write {bw - rw:6.2f} s ({bc - rc:6.2f} cpu)",
                      flush=True)
        for p in paths:
            a = [statistics.median(x[i] for x in writes[(0, p)]) for i in (0, 1)]
            b = [statistics.median(x[i] for x in writes[(1, p)]) for i in (0, 1)]
            name = os.path.basename(p)
            same = without_uuid(os.path.join(outs[0], name)) == without_uuid(os.path.join(outs[1], name))
            print(f"{name}: median write A {a[0]:.2f} s ({a[1]:.2f} cpu), B {b[0]:.2f} s ({b[1]:.2f} cpu); "
                  f"B/A {b[0] / a[0]:.3f} wall, {b[1] / a[1]:.3f} cpu; bytes but the UUID "
                  f"{'IDENTICAL' if same else 'DIFFER'}")


if __name__ == "__main__":
    main()
