"""Reading Houdini's Blosc-compressed .bgeo.sc beside the same particles as binary-JSON .bgeo
and gzip-compressed .bgeo.gz: 1M random particles with velocity (3) and density (1), written
by the tests' writers (tests/cli/particle_files.py; the SCF as Houdini writes it: LZ4 chunks
of 64 KiB, level 9, byte shuffle), each read --runs times through the Python package, every
read checked equal to the written arrays. Writes its files into --folder (default: a
temporary folder, removed at the end).

    PM_PYTHON_PATH=build/python /usr/bin/python3 bench/bgeo_sc_read_bench.py [--points N] [--runs K]
"""
import argparse
import gzip
import os
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, os.environ.get("PM_PYTHON_PATH", "build/python"))
sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests" / "cli"))
import particlemesh as pm  # noqa: E402
from particle_files import scf, write_bgeo_json  # noqa: E402


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--points", type=int, default=1_000_000)
    parser.add_argument("--runs", type=int, default=3)
    parser.add_argument("--folder", help="where the files go (kept)")
    args = parser.parse_args()
    rng = np.random.default_rng(1)
    p = (rng.random((args.points, 3)) * 4).astype(np.float32)
    a = {"velocity": rng.normal(size=(args.points, 3)).astype(np.float32),
         "density": (1000 + rng.random(args.points)).astype(np.float32)}
    with tempfile.TemporaryDirectory() as scratch:
        folder = Path(args.folder or scratch)
        folder.mkdir(parents=True, exist_ok=True)
        plain = folder / "big.bgeo"
        write_bgeo_json(plain, p, a)
        raw = plain.read_bytes()
        (folder / "big.bgeo.gz").write_bytes(gzip.compress(raw, compresslevel=6, mtime=0))
        (folder / "big.bgeo.sc").write_bytes(scf(raw, cname="lz4"))
        print("| file | size | read |\n|---|---|---|")
        for name in ("big.bgeo", "big.bgeo.gz", "big.bgeo.sc"):
            times = []
            for _ in range(args.runs):
                t = time.perf_counter()
                cloud = pm.read_points(folder / name)
                times.append(time.perf_counter() - t)
            if not (np.array_equal(cloud.positions, p.astype(np.float64))
                    and np.array_equal(cloud.attributes["velocity"], a["velocity"])):
                sys.exit(f"{name}: the particles read differ from those written")
            size = (folder / name).stat().st_size / 1e6
            print(f"| {name} | {size:.1f} MB | {' / '.join(f'{x:.3f}' for x in times)} s |")


if __name__ == "__main__":
    main()
