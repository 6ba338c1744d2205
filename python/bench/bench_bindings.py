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
import resource
import statistics
import time

import numpy as np

import lasercell


def median_ms(function, runs):
    """Median wall time of `function`, ms, and the minor page faults per run (fresh pages the
    kernel hands out: the cost that dominates large first-touch copies on this VM)."""
    function()  # warm-up: steady state, as in a loop over sweeps
    times = []
    faults = resource.getrusage(resource.RUSAGE_SELF).ru_minflt
    for _ in range(runs):
        start = time.perf_counter()
        function()
        times.append((time.perf_counter() - start) * 1e3)
    faults = resource.getrusage(resource.RUSAGE_SELF).ru_minflt - faults
    return statistics.median(times), faults / runs


def alternate(scene, model, options, runs):
    """Per run: the C++ call timed inside C++, then the Python call timed in Python."""
    cpp_ms, python_ms = [], []
    lasercell.localize_in_cloud(scene, model, options)  # warm-up (caches, pages)
    for _ in range(runs):
        cpp_ms.append(lasercell._lasercell._time_localize_in_cloud_ms(scene, model, options))
        start = time.perf_counter()
        lasercell.localize_in_cloud(scene, model, options)
        python_ms.append((time.perf_counter() - start) * 1e3)
    return cpp_ms, python_ms


def bench_localize(source_dir, runs):
    uwa = os.path.join(source_dir, "datasets/real/uwa")
    model = lasercell.PpfModel.build(
        lasercell.read_point_cloud(os.path.join(uwa, "parasaurolophus_6700.bin.ply")))
    scene = lasercell.read_point_cloud(os.path.join(uwa, "rs1_normals.bin.ply"))
    options = {"threads": 1}
    assert lasercell.localize_in_cloud(scene, model, options).found
    cpp_ms, python_ms = alternate(scene, model, options, runs)
    cpp, py = statistics.median(cpp_ms), statistics.median(python_ms)
    paired = statistics.median(p - c for p, c in zip(python_ms, cpp_ms))
    # The fixed cost of a call (options dict parsed, GIL, result wrapped) on a scene so small
    # that the work itself takes microseconds.
    tiny = lasercell.PointCloud(scene.positions[:200], normals=scene.normals[:200])
    tiny_cpp, tiny_py = alternate(tiny, model, options, 5 * runs)
    fixed_us = 1e3 * statistics.median(p - c for p, c in zip(tiny_py, tiny_cpp))
    return {"scene_points": len(scene), "runs": runs, "cpp_median_ms": cpp,
            "python_median_ms": py, "overhead_percent": 100.0 * (py / cpp - 1.0),
            "paired_difference_median_ms": paired,
            "paired_overhead_percent": 100.0 * paired / cpp,
            "fixed_call_overhead_us": fixed_us}


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
    cloud = lasercell.PointCloud(positions, normals=normals)
    cases["PointCloud -> positions + normals arrays (views)"] = (
        lambda: (cloud.positions, cloud.normals))
    cases["np.copy of the positions (reference: one 24 MB copy)"] = lambda: positions.copy()
    cases["np.copy of positions and normals (reference: two 24 MB copies)"] = (
        lambda: (positions.copy(), normals.copy()))
    rows = []
    for name, function in cases.items():
        ms, faults = median_ms(function, runs)
        rows.append({"case": name, "points": n, "median_ms": ms, "page_faults_per_run": faults})
    return rows


def markdown(report):
    loc = report["localize_in_cloud"]
    lines = [
        "| call | C++ median | Python median | overhead of the medians | median paired "
        "difference | target |",
        "|---|---|---|---|---|---|",
        f"| `localize_in_cloud`, rs1 ({loc['scene_points']} points), 1 thread, "
        f"{loc['runs']} alternating runs | {loc['cpp_median_ms']:.2f} ms | "
        f"{loc['python_median_ms']:.2f} ms | {loc['overhead_percent']:+.1f} % | "
        f"{loc['paired_difference_median_ms']:+.3f} ms ({loc['paired_overhead_percent']:+.2f} %) "
        "| within 5 % |",
        "",
        f"Fixed cost of one Python call (options dict parsed, GIL released and retaken, result "
        f"wrapped), median paired difference on a 200-point scene: "
        f"{loc['fixed_call_overhead_us']:.0f} us.",
        "",
        "| conversion (1M points) | median | minor page faults per run | target |",
        "|---|---|---|---|",
    ]
    for row in report["arrays"]:
        target = "<= 5 ms" if row["case"].startswith("positions float64 C-order") else ""
        lines.append(f"| {row['case']} | {row['median_ms']:.2f} ms | "
                     f"{row['page_faults_per_run']:.0f} | {target} |")
    return "\n".join(lines) + "\n"


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--source-dir", default=os.path.join(os.path.dirname(__file__), "../.."))
    parser.add_argument("--runs", type=int, default=40)
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
