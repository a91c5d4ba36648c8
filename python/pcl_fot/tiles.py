"""Tiled mapping: a map built one tile at a time, on Dask, equal cell for cell to the single-process map.

A tile is one node of the tree at a chosen level L (2 to 15): the cube of 2**L cells per axis whose keys
(i, j, k) * 2**L to (i, j, k) * 2**L + 2**L - 1 it holds, named "L-i-j-k" as Entwine's EPT names its nodes.
(Up to level 15 the tree's nodes lie on these boundaries: see tree/tree_coord.h.)

A run has two stages. First one task per scan walks the scan's rays, exactly as the whole-map insertion
walks them (FastOctTree.trace_scan), writes the cells it updates sorted by tile into one file, and returns
where each tile's run lies in it. Then one task per tile reads, scan by scan in time order, only its runs
and writes them into the tile's map (apply_scan).

A run writes its tiles into a folder of its own, tiles/<run>/, and only when every task has succeeded does it
replace tiles.json, atomically, and then remove the folders of earlier runs. So a run that fails, or a process
killed at any point, leaves the tile set that was there before whole. (A failed run removes its folder, but a
task still running on a cluster can write there afterwards; the next run that succeeds removes it.)

Why the result is exact: a cell's value depends only on the updates it receives and their order. Each
scan's cells are the whole-map insertion's, each cell is written by the one task of its tile, and the scans
come in time order, so each cell gets the same updates in the same order as in one process. Tiles share no
cell, so merging them (each cell of a tile is unknown in the others) copies every value unchanged.

Mapping scans apart and merging the maps is not exact in general: OctoMap's log-odds are clamped, so the sum
of two maps' evidence is not the evidence of the scans in sequence (a cell clamped free by the first scans
and hit later differs), and with the binary rule the latest scan wins, which a merge cannot know.

Command line: ``python3 -m pcl_fot.tiles map [options] scan1.pcd scan2.pcd ... -out DIR``.
"""

import argparse
import json
import os
import resource
import shutil
import sys
import time
import uuid

import numpy as np

from . import FastOctTree, SensorModel, read_cloud

MAX_TILE_LEVEL = 15
INDEX_NAME = "tiles.json"
INDEX_FORMAT = "pcl_fot tile set"
MIN_TILE_LEVEL = 2  # a tile holds whole 4x4x4 blocks of trace_scan


class TileSetError(RuntimeError):
    """A tile set that cannot be used, or a tiled run that failed; the message names the file or tile."""


def tile_name(level, index):
    return "%d-%d-%d-%d" % (level, index[0], index[1], index[2])


def tile_box(level, index):
    """The tile's keys, bounds included: ((x0, y0, z0), (x1, y1, z1))."""
    lo = tuple(int(i) << level for i in index)
    return lo, tuple(v + (1 << level) - 1 for v in lo)


class MapSpec:
    """What every tile's map shares: grid, update rule, sensor model and the scans' options."""

    def __init__(self, resolution=0.05, origin=(0.0, 0.0, 0.0), rule="log_odds", sensor_model=None,
                 max_range=-1.0, min_range=0.0, discretize=False):
        model = sensor_model or SensorModel()
        self.resolution = float(resolution)
        self.origin = tuple(float(o) for o in origin)
        self.rule = rule
        self.model = (model.prob_hit, model.prob_miss, model.clamp_min, model.clamp_max, model.occupancy)
        self.max_range = float(max_range)
        self.min_range = float(min_range)
        self.discretize = bool(discretize)
        self.new_map()  # bad values fail here, before any task runs

    def new_map(self):
        return FastOctTree(self.resolution, self.origin, self.rule, SensorModel(*self.model))

    def insert(self, tree, scan):
        """One scan into a whole map, as one process maps it."""
        points, origin, orientation = scan
        return tree.insert_scan(points, origin, orientation, max_range=self.max_range,
                                min_range=self.min_range, discretize=self.discretize, threads=1)

    def to_json(self):
        return {"resolution": self.resolution, "origin": list(self.origin), "rule": self.rule,
                "sensor_model": list(self.model)}


def read_poses(path):
    """One pose per line, tx ty tz qw qx qy qz, as fot_map's -poses file; '#' starts a comment."""
    poses = []
    with open(path) as f:
        for number, line in enumerate(f, 1):
            values = line.split("#", 1)[0].split()
            if not values:
                continue
            try:
                pose = [float(v) for v in values]
            except ValueError:
                pose = []
            if len(pose) != 7 or not all(np.isfinite(pose)):
                raise TileSetError("%s, line %d: a pose is seven finite numbers, tx ty tz qw qx qy qz"
                                   % (path, number))
            poses.append((tuple(pose[:3]), tuple(pose[3:])))
    return poses


def load_scan(path, pose=None):
    """(points in the sensor frame, sensor origin, orientation w, x, y, z): the file's VIEWPOINT or `pose`."""
    cloud = read_cloud(path)
    origin, orientation = pose if pose is not None else (cloud["origin"], cloud["orientation"])
    return cloud["points"], origin, orientation


def _scan_file(work_dir, i):
    return os.path.join(work_dir, "scan%06d.blocks" % i)


def _save_raw(path, array):
    """The array's bytes alone: a tile task reads its runs at their offsets, with no header to parse."""
    tmp = "%s.tmp.%d" % (path, os.getpid())
    array.tofile(tmp)
    os.replace(tmp, path)


def trace_task(spec, level, i, path, pose, work_dir):
    """Stage one: scan i's cells, sorted by tile, in one file; returns their dtype and {tile: (start, end)},
    each tile's run."""
    try:
        points, origin, orientation = load_scan(path, pose)
        blocks, _ = spec.new_map().trace_scan(points, origin, orientation, max_range=spec.max_range,
                                              min_range=spec.min_range, discretize=spec.discretize, threads=1)
        tiles = FastOctTree.block_keys(blocks) >> level
        order = np.lexsort((tiles[:, 2], tiles[:, 1], tiles[:, 0]))  # stable: each tile keeps the scan's order
        unique, starts = np.unique(tiles[order], axis=0, return_index=True)
        _save_raw(_scan_file(work_dir, i), blocks[order])
    except Exception as e:
        raise TileSetError("scan %d (%s): %s" % (i + 1, path, e)) from e
    ends = np.append(starts[1:], len(order))
    return blocks.dtype, {tuple(int(v) for v in t): (int(a), int(b)) for t, a, b in zip(unique, starts, ends)}


def peak_rss_bytes():
    """This process's peak resident memory: VmHWM, which starts anew at exec (ru_maxrss carries over the
    peak of the process that started a worker); ru_maxrss where /proc is missing."""
    try:
        with open("/proc/self/status") as f:
            for line in f:
                if line.startswith("VmHWM:"):
                    return int(line.split()[1]) * 1024
    except OSError:
        pass
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * 1024


def map_tile(spec, level, index, runs, dtype, work_dir, out_dir, run):
    """Stage two: the tile's runs of blocks of `dtype`, (scan, start, end) in time order, into the tile's map,
    written as tiles/<run>/<name>.fot. Returns the tile's record for the index, or None when no cell was
    written."""
    start = time.perf_counter()
    name = tile_name(level, index)
    try:
        tree = spec.new_map()
        for i, first, last in runs:
            tree.apply_scan(np.fromfile(_scan_file(work_dir, i), dtype=dtype, count=last - first,
                                        offset=first * dtype.itemsize))
        if tree.empty:
            return None
        file = os.path.join("tiles", run, name + ".fot")
        path = os.path.join(out_dir, file)
        tree.save(path)
    except Exception as e:
        raise TileSetError("tile %s: %s" % (name, e)) from e
    return {"name": name, "level": level, "index": list(index), "file": file,
            "bytes": os.path.getsize(path), "seconds": time.perf_counter() - start,
            "peak_rss_bytes": peak_rss_bytes()}


def _write_atomically(path, text):
    tmp = "%s.tmp.%d" % (path, os.getpid())
    with open(tmp, "w") as f:
        f.write(text)
        f.flush()
        os.fsync(f.fileno())
    os.replace(tmp, path)


def write_index(out_dir, spec, level, tiles):
    index = {"format": INDEX_FORMAT, "version": 1, "tile_level": level, "tiles": tiles}
    index.update(spec.to_json())
    _write_atomically(os.path.join(out_dir, INDEX_NAME), json.dumps(index, indent=1) + "\n")


def open_tile_set(path):
    """The map a tile set holds, its tiles merged; `path` is the directory or its tiles.json.

    Raises TileSetError naming the tile for a missing or damaged tile, or one of another grid or rule."""
    index_path = os.path.join(path, INDEX_NAME) if os.path.isdir(path) else path
    base = os.path.dirname(index_path)
    try:
        with open(index_path) as f:
            index = json.load(f)
        if index.get("format") != INDEX_FORMAT:
            raise ValueError("not a pcl_fot tile set index")
        spec = MapSpec(index["resolution"], index["origin"], index["rule"], SensorModel(*index["sensor_model"]))
        tiles = index["tiles"]
    except (OSError, ValueError, KeyError, TypeError, RecursionError) as e:
        raise TileSetError("%s: %s" % (index_path, e)) from e
    whole = spec.new_map()
    for tile in tiles:
        name = tile.get("name", "?")
        try:
            if os.path.isabs(tile["file"]) or ".." in tile["file"]:
                raise ValueError("its file '%s' lies outside the tile set" % tile["file"])
            part = FastOctTree.load(os.path.join(base, tile["file"]))
        except Exception as e:
            raise TileSetError("tile %s: %s" % (name, e)) from e
        if part.resolution != spec.resolution or part.origin != spec.origin:
            raise TileSetError("tile %s: its grid (resolution %g, origin %s) is not the tile set's (%g, %s)"
                               % (name, part.resolution, part.origin, spec.resolution, spec.origin))
        lo, hi = tile_box(int(tile["level"]), tile["index"])
        corners, levels, _ = part.cells()
        if len(corners) and ((corners < lo).any() or (corners + (1 << levels.astype(np.int64))[:, None] - 1 > hi)
                             .any()):
            raise TileSetError("tile %s: it holds cells outside its cube" % name)
        whole.merge(part)
    return whole


def _check_outputs(out_dir, inputs):
    outputs = {os.path.realpath(os.path.join(out_dir, n)) for n in ("map.fot", INDEX_NAME)}
    tiles_dir = os.path.realpath(os.path.join(out_dir, "tiles"))
    for p in inputs:
        real = os.path.realpath(p)
        if real in outputs or real.startswith(tiles_dir + os.sep):
            raise TileSetError("'%s' is an input; the output directory would write over it" % p)


def _client(scheduler, workers, memory_limit):
    from dask.distributed import Client, LocalCluster

    if scheduler and scheduler != "local":
        return Client(scheduler), None
    cluster = LocalCluster(n_workers=workers, threads_per_worker=1, processes=True,
                           memory_limit=memory_limit or "auto", dashboard_address=":0")
    return Client(cluster), cluster


def _run(client, function, args, keys, progress, what):
    """Runs function(*a) for each a in args on the cluster; the results in order. A task that fails (after
    Dask's retries, should its worker die) fails the run with its error, which names the scan or tile."""
    from dask.distributed import as_completed

    futures = client.map(function, *zip(*args), key=keys, retries=2, pure=False)
    for done, future in enumerate(as_completed(futures), 1):
        try:
            future.result()
        except TileSetError:
            raise
        except Exception as e:  # the worker died each time (KilledWorker), or the scheduler went away
            raise TileSetError("task %s: %s" % (future.key, e)) from e
        if progress:
            sys.stderr.write("\r%s: %d/%d" % (what, done, len(futures)))
    if progress:
        sys.stderr.write("\n")
    return [f.result() for f in futures]


def map_tiles(scan_paths, out_dir, spec, level, poses=None, scheduler=None, workers=1, memory_limit=None,
              stitch=False, progress=False):
    """Maps the scans tile by tile with Dask, on the cluster at `scheduler` or, without one, on a LocalCluster
    of `workers` processes. Writes the tiles and tiles.json: the tile set is the map (open_tile_set and the
    tools read it as one). With `stitch`, also the whole map as map.fot, which needs it in one process;
    without, an earlier run's map.fot is removed. Returns the index's tile records, in tile order."""
    if not MIN_TILE_LEVEL <= level <= MAX_TILE_LEVEL:
        raise TileSetError("the tile level must be %d to %d, not %d" % (MIN_TILE_LEVEL, MAX_TILE_LEVEL, level))
    if poses is not None and len(poses) != len(scan_paths):
        raise TileSetError("%d poses for %d scans" % (len(poses), len(scan_paths)))
    _check_outputs(out_dir, scan_paths)
    out_dir = os.path.abspath(out_dir)
    n = len(scan_paths)
    run = uuid.uuid4().hex[:8]  # task keys and a tile folder of their own: a cluster may hold another run's tasks
    tiles_dir = os.path.join(out_dir, "tiles")
    work_dir = os.path.join(out_dir, ".work-" + run)
    os.makedirs(os.path.join(tiles_dir, run))
    os.makedirs(work_dir)
    done, client, cluster = False, None, None
    try:
        client, cluster = _client(scheduler, workers, memory_limit)
        touched = _run(client, trace_task,
                       [(spec, level, i, p, poses[i] if poses else None, work_dir) for i, p in enumerate(scan_paths)],
                       ["trace-scan-%d-%s" % (i, run) for i in range(n)], progress, "scans traced")
        runs = {}  # tile: its runs in time order
        for i, (_, scan) in enumerate(touched):
            for t, (start, end) in scan.items():
                runs.setdefault(t, []).append((i, start, end))
        tiles = sorted(runs)
        dtype = touched[0][0] if touched else None
        records = _run(client, map_tile, [(spec, level, t, runs[t], dtype, work_dir, out_dir, run) for t in tiles],
                       ["tile-%s-%s" % (tile_name(level, t), run) for t in tiles], progress, "tiles mapped")
        records = [r for r in records if r is not None]
        write_index(out_dir, spec, level, records)
        done = True
    finally:
        if client is not None:
            client.close()
        if cluster is not None:
            cluster.close()
        shutil.rmtree(work_dir, ignore_errors=True)
        if not done:
            shutil.rmtree(os.path.join(tiles_dir, run), ignore_errors=True)
    # Earlier runs' tiles, which the index no longer names, and scratch folders of runs that were killed.
    leftovers = [os.path.join(tiles_dir, e) for e in os.listdir(tiles_dir) if e != run]
    leftovers += [os.path.join(out_dir, e) for e in os.listdir(out_dir) if e.startswith(".work-")]
    for path in leftovers:
        shutil.rmtree(path) if os.path.isdir(path) and not os.path.islink(path) else os.remove(path)
    stitched = os.path.join(out_dir, "map.fot")
    if stitch:
        open_tile_set(out_dir).save(stitched)
    elif os.path.isfile(stitched):  # an earlier run's, which no longer is this tile set's map
        os.remove(stitched)
    return records


def _main(argv=None):
    parser = argparse.ArgumentParser(prog="python3 -m pcl_fot.tiles",
                                     description="Tiled mapping on Dask, equal to fot_map's map cell for cell.")
    commands = parser.add_subparsers(dest="command", required=True)
    run = commands.add_parser("map", help="map scans (.pcd, .ply) tile by tile into a tile set")
    run.add_argument("scans", nargs="+")
    run.add_argument("-out", "--out", required=True, help="output directory: tiles/RUN/, tiles.json (map.fot)")
    run.add_argument("--tile-level", type=int, required=True, help="tile edge 2**L cells, L from 2 to 15")
    run.add_argument("--scheduler", default="local", help="a Dask scheduler's address, or local (default)")
    run.add_argument("--workers", type=int, default=os.cpu_count() or 1, help="local workers (default: cores)")
    run.add_argument("--memory-limit", default=None, help="each local worker's memory limit, as '2GB'")
    run.add_argument("-res", "--res", type=float, default=0.05, help="voxel edge in metres (default: 0.05)")
    run.add_argument("-poses", "--poses", help="one pose per scan: tx ty tz qw qx qy qz per line")
    run.add_argument("-max_range", "--max-range", type=float, default=-1.0)
    run.add_argument("-min_range", "--min-range", type=float, default=0.0)
    run.add_argument("-binary", "--binary", action="store_true", help="the latest scan wins, not log-odds")
    run.add_argument("--stitch", action="store_true", help="also write the tiles merged as map.fot")
    info = commands.add_parser("info", help="summarise a tile set")
    info.add_argument("tile_set")
    args = parser.parse_args(argv)
    try:
        if args.command == "info":
            tree = open_tile_set(args.tile_set)
            print("resolution %g, %d occupied and %d free cells, %d bytes"
                  % (tree.resolution, tree.occupied_count, tree.free_count, tree.memory_bytes))
            return 0
        spec = MapSpec(args.res, rule="binary" if args.binary else "log_odds", max_range=args.max_range,
                       min_range=args.min_range)
        poses = read_poses(args.poses) if args.poses else None
        start = time.perf_counter()
        tiles = map_tiles(args.scans, args.out, spec, args.tile_level, poses, args.scheduler, args.workers,
                          args.memory_limit, args.stitch, progress=True)
        print("%d tiles with cells in %s (%.1f s)" % (len(tiles), args.out, time.perf_counter() - start))
        return 0
    except (TileSetError, OSError, ValueError, RuntimeError) as e:
        print("error: %s" % e, file=sys.stderr)
        return 2


if __name__ == "__main__":
    # Run as `python3 -m pcl_fot.tiles`, this file is __main__, whose functions Dask would pickle by value
    # (with the extension module's objects they reach, which cannot be pickled). The package's own copy
    # is pickled by name, and the workers import it.
    from pcl_fot import tiles as _tiles

    sys.exit(_tiles._main())
