#!/usr/bin/env python3
"""Binding overhead of the Python module, measured in one process on the same data:

1. localize_in_cloud on UWA rs1 + parasaurolophus (one thread, prebuilt model): the Python call
   (options dict parsed, GIL released, result wrapped) against the C++ LocalizeInCloud timed
   inside C++ around the same call. Runs alternate between the two; medians.
2. NumPy -> PointCloud of 1M points (float64 C-ordered, float32, Fortran-ordered; with normals)
   and PointCloud -> NumPy (views).

Usage: PYTHONPATH=build/python /usr/bin/python3 python/bench/bench_bindings.py
           [--source-dir .] [--runs 20] [--json OUT.json] [--markdown OUT.md]
The Markdown is the BENCHMARKS.md section, generated from the JSON numbers.
"""

import argparse
import json
import os
import platform
import statistics
import time

import numpy as np

import lasercell


def median_ms(function, runs):
    times = []
    for _ in range(runs):
        start = time.perf_counter()
        function()
        times.append((time.perf_counter() - start) * 1e3)
    return statistics.median(times)


def bench_localize(source_dir, runs):
    uwa = os.path.join(source_dir, "datasets/real/uwa")
    model = lasercell.PpfModel.build(
        lasercell.read_point_cloud(os.path.join(uwa, "parasaurolophus_6700.bin.ply")))
    scene = lasercell.read_point_cloud(os.path.join(uwa, "rs1_normals.bin.ply"))
    options = {"threads": 1}
    python_ms, cpp_ms = [], []
    lasercell.localize_in_cloud(scene, model, options)  # warm-up (caches, pages)
    for _ in range(runs):
        cpp_ms.append(lasercell._lasercell._time_localize_in_cloud_ms(scene, model, options))
        start = time.perf_counter()
        result = lasercell.localize_in_cloud(scene, model, options)
        python_ms.append((time.perf_counter() - start) * 1e3)
        assert result.found
    cpp, py = statistics.median(cpp_ms), statistics.median(python_ms)
    return {"scene_points": len(scene), "runs": runs, "cpp_median_ms": cpp,
            "python_median_ms": py, "overhead_percent": 100.0 * (py / cpp - 1.0)}


def bench_arrays(runs, n=1_000_000):
    rng = np.random.default_rng(1)
    positions = rng.uniform(-500.0, 500.0, (n, 3))
    normals = rng.normal(size=(n, 3))
    normals /= np.linalg.norm(normals, axis=1, keepdims=True)
    cases = {
        "positions float64 C-order -> PointCloud": lambda: lasercell.PointCloud(positions),
        "positions float32 -> PointCloud": (
            lambda p32=positions.astype(np.float32): lasercell.PointCloud(p32)),
        "positions float64 Fortran-order -> PointCloud": (
            lambda pf=np.asfortranarray(positions): lasercell.PointCloud(pf)),
        "positions + normals float64 -> PointCloud": (
            lambda: lasercell.PointCloud(positions, normals=normals)),
    }
    rows = [{"case": name, "points": n, "median_ms": median_ms(f, runs)}
            for name, f in cases.items()]
    cloud = lasercell.PointCloud(positions, normals=normals)
    rows.append({"case": "PointCloud -> positions + normals arrays (views)", "points": n,
                 "median_ms": median_ms(lambda: (cloud.positions, cloud.normals), runs)})
    rows.append({"case": "np.copy of the positions (reference: one 24 MB copy)", "points": n,
                 "median_ms": median_ms(lambda: positions.copy(), runs)})
    return rows


def markdown(report):
    loc = report["localize_in_cloud"]
    lines = [
        "| call | C++ median | Python median | overhead | target |",
        "|---|---|---|---|---|",
        f"| `localize_in_cloud`, rs1 ({loc['scene_points']} points), 1 thread, "
        f"{loc['runs']} alternating runs | {loc['cpp_median_ms']:.2f} ms | "
        f"{loc['python_median_ms']:.2f} ms | {loc['overhead_percent']:+.1f} % | within 5 % |",
        "",
        "| conversion (1M points) | median | target |",
        "|---|---|---|",
    ]
    for row in report["arrays"]:
        target = "<= 5 ms" if row["case"].startswith("positions float64 C-order") else ""
        lines.append(f"| {row['case']} | {row['median_ms']:.2f} ms | {target} |")
    return "\n".join(lines) + "\n"


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--source-dir", default=os.path.join(os.path.dirname(__file__), "../.."))
    parser.add_argument("--runs", type=int, default=20)
    parser.add_argument("--json")
    parser.add_argument("--markdown")
    args = parser.parse_args()
    report = {"machine": platform.processor() or platform.machine(), "cores": os.cpu_count(),
              "lasercell": lasercell.__version__, "numpy": np.__version__,
              "localize_in_cloud": bench_localize(args.source_dir, args.runs),
              "arrays": bench_arrays(args.runs)}
    text = markdown(report)
    print(text)
    if args.json:
        with open(args.json, "w", encoding="utf-8") as f:
            json.dump(report, f, indent=2)
    if args.markdown:
        with open(args.markdown, "w", encoding="utf-8") as f:
            f.write(text)


if __name__ == "__main__":
    main()
