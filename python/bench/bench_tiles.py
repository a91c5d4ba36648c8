"""Benchmarks of the Python package, written as the "Python and tiled mapping" section of doc/benchmarks.md:
the binding's overhead over the C++ call on one scan, and tiled mapping on a LocalCluster with 1 and 2 workers
against one process on the same scans, each measured side by side in this run (medians).

    PYTHONPATH=build/python /usr/bin/python3 python/bench/bench_tiles.py -data ../shared/data \\
        -timer build/python/insert_scan_timer -out doc/benchmarks.md

Reads PCL's Kinect frames (doc/user_guide.md names them) from -data; the run whose map exceeds a worker's
memory limit maps the tests' synthetic rooms (python/tests/synthetic_scans.py).
"""

import argparse
import os
import re
import shutil
import statistics
import subprocess
import tempfile
import time

import sys

import numpy as np

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "tests"))
import pcl_fot  # noqa: E402
from pcl_fot import tiles  # noqa: E402

SECTION = "## Python and tiled mapping on Dask"


def binding_overhead(scan, timer, repeats):
    """Median seconds of one insertion through the binding and through the C++ call, interleaved."""
    cloud = pcl_fot.read_cloud(scan)
    python, cpp = [], []
    for _ in range(repeats):
        out = subprocess.run([timer, scan, "0.02", "1"], check=True, capture_output=True, text=True)
        cpp.append(float(out.stdout.split()[0]))
        tree = pcl_fot.FastOctTree(0.02, rule="log_odds")
        start = time.perf_counter()
        tree.insert_scan(cloud["points"], cloud["origin"], threads=1)
        python.append(time.perf_counter() - start)
    return len(cloud["points"]), statistics.median(python), statistics.median(cpp)


def one_process(spec, paths):
    start = time.perf_counter()
    tree = spec.new_map()
    for p in paths:
        spec.insert(tree, tiles.load_scan(p))
    return time.perf_counter() - start, tree


def tiled(spec, paths, level, workers, memory_limit=None):
    """Seconds to the tile set, its records, seconds to stitch it into one map (open_tile_set), that map."""
    from dask.distributed import LocalCluster

    out = tempfile.mkdtemp()
    try:
        with LocalCluster(n_workers=workers, threads_per_worker=1, dashboard_address=":0",
                          memory_limit=memory_limit or "auto") as cluster:
            start = time.perf_counter()
            records = tiles.map_tiles(paths, out, spec, level, scheduler=cluster.scheduler_address)
            seconds = time.perf_counter() - start
        start = time.perf_counter()
        whole = tiles.open_tile_set(out)
        return seconds, records, time.perf_counter() - start, whole
    finally:
        shutil.rmtree(out)


def same(a, b):
    ca, cb = a.cells(), b.cells()
    return all(x.shape == y.shape and np.array_equal(x.view(np.uint8), y.view(np.uint8)) for x, y in zip(ca, cb))


def mb(n):
    return "%.0f MB" % (n / 1e6)


def run(args):
    frames = [os.path.join(args.data, "kinect_capture000%d.pcd" % i) for i in (1, 2, 3)]
    for f in frames:
        if not os.path.isfile(f):
            raise SystemExit("%s not found: the benchmark reads PCL's Kinect frames (doc/user_guide.md)" % f)
    lines = [SECTION, ""]
    points, python, cpp = binding_overhead(frames[0], args.timer, 7 * args.repeats)
    lines += ["Binding overhead: one Kinect frame (%d points, 2 cm cells, log-odds, one thread) inserted through "
              "`FastOctTree.insert_scan` and through `pcl::fot::insertRays` (python/bench/insert_scan_timer.cpp), "
              "interleaved, median of %d: Python %.1f ms, C++ %.1f ms, **%.3f×** (goal at most 1.05×)."
              % (points, 7 * args.repeats, python * 1e3, cpp * 1e3, python / cpp), ""]

    paths = frames * args.rounds
    spec = tiles.MapSpec(0.02, rule="log_odds")
    lines += ["Tiled mapping: the three Kinect frames %d times over (%d scans, 2 cm cells, log-odds), one process "
              "(`insert_scan` scan by scan, one thread) against `pcl_fot.tiles.map_tiles` on a LocalCluster (its "
              "start not counted), in turn in each of %d rounds, medians (each ratio the median of the rounds' "
              "ratios): the time to the tile set (tracing, the tiles' files and the index), and apart, the time "
              "to stitch the tiles into one map in one process "
              "(`open_tile_set`). "
              "Every stitched map was checked equal to the one-process map, cell for cell." % (
                  args.rounds, len(paths), args.repeats), "",
              "| tile level (edge) | tiles | one process | 1 worker | 2 workers | 1 worker / one process | "
              "1 worker / 2 workers | stitch | peak RSS per worker |",
              "| --- | --- | --- | --- | --- | --- | --- | --- | --- |"]
    for level in args.levels:
        # Side by side: each round maps the scans in one process, then tiled on 1 and on 2 workers.
        single, times, stitches = [], {1: [], 2: []}, []
        for _ in range(args.repeats):
            seconds, whole = one_process(spec, paths)
            single.append(seconds)
            for workers in (1, 2):
                seconds, records, stitch, tree = tiled(spec, paths, level, workers)
                if not same(tree, whole):
                    raise SystemExit("the tiled map differs from the one-process map at level %d" % level)
                times[workers].append(seconds)
                stitches.append(stitch)
        # Each ratio is the median of the rounds' own ratios: a burst of load on this shared machine slows
        # one round's runs, not the comparison within another round.
        overhead = statistics.median(t / s for t, s in zip(times[1], single))
        speedup = statistics.median(a / b for a, b in zip(times[1], times[2]))
        one = statistics.median(single)
        times = {w: statistics.median(t) for w, t in times.items()}
        rss = max(r["peak_rss_bytes"] for r in records)
        lines.append("| %d (%.2f m) | %d | %.2f s | %.2f s | %.2f s | %.2f× | %.2f× | %.2f s | %s |"
                     % (level, 0.02 * (1 << level), len(records), one, times[1], times[2], overhead, speedup,
                        statistics.median(stitches), mb(rss)))
    lines += ["", "Goals: 1 worker at most 1.3× one process; 2 workers at least 1.6× faster than 1.", ""]

    # A map larger than one worker's memory limit, built tile by tile: a street of rooms, one scan each.
    from synthetic_scans import depth_scan, write_pcd

    street = tempfile.mkdtemp()
    try:
        paths = []
        for i in range(args.street):
            points, origin, q = depth_scan(i, 320, 240)
            paths.append(os.path.join(street, "room%d.pcd" % i))
            write_pcd(paths[-1], points, (origin[0] + 10.0 * i, origin[1], origin[2]), q, 320, 240)
        fine = tiles.MapSpec(args.fine, rule="log_odds")
        seconds, whole = one_process(fine, paths)
        limit = int(args.limit_mb * 1e6)
        seconds_tiled, records, stitch, tree = tiled(fine, paths, args.fine_level, 2, memory_limit=limit)
    finally:
        shutil.rmtree(street)
    lines += ["A map larger than a worker's memory limit: %d synthetic depth scans (320×240) of rooms 10 m apart, "
              "%g m cells. One process: %.1f s, the map %s. Tiled at level %d, 2 workers each limited to %s by "
              "the LocalCluster: %.1f s to the tile set, %d tiles, peak RSS per worker at most %s, the largest "
              "tile file %s. Stitched into one map in one process (%.1f s), it %s the one-process map cell for "
              "cell." % (args.street, args.fine, seconds, mb(whole.memory_bytes), args.fine_level, mb(limit),
                         seconds_tiled, len(records), mb(max(r["peak_rss_bytes"] for r in records)),
                         mb(max(r["bytes"] for r in records)), stitch,
                         "equals" if same(tree, whole) else "DIFFERS FROM"), ""]
    return "\n".join(lines)


def splice(path, section):
    text = open(path).read() if os.path.isfile(path) else ""
    pattern = re.compile(re.escape(SECTION) + r".*?(?=^## |\Z)", re.S | re.M)
    text = pattern.sub(lambda _: section + "\n", text) if pattern.search(text) else text.rstrip() + "\n\n" + section + "\n"
    tmp = path + ".tmp"
    with open(tmp, "w") as f:
        f.write(text)
    os.replace(tmp, path)


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("-data", required=True)
    parser.add_argument("-timer", required=True)
    parser.add_argument("-out", required=True)
    parser.add_argument("-repeats", type=int, default=5)
    parser.add_argument("-rounds", type=int, default=4)
    parser.add_argument("-levels", type=int, nargs="+", default=[7, 9])
    parser.add_argument("-street", type=int, default=6)
    parser.add_argument("-fine", type=float, default=0.005)
    parser.add_argument("-fine_level", type=int, default=7)
    parser.add_argument("-limit_mb", type=float, default=300)
    args = parser.parse_args()
    section = run(args)
    print(section)
    splice(args.out, section)


if __name__ == "__main__":
    main()
