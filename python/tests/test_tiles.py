"""Tiled mapping on Dask: the tile set equals the single-process map cell for cell, log-odds bit for bit."""

import json
import os
import re
import shutil
import subprocess
import sys

import numpy as np
import pytest
from conftest import real_scan_dir

import pcl_fot
from pcl_fot import tiles
from synthetic_scans import same_cells


def single_process_map(spec, paths, poses=None):
    tree = spec.new_map()
    for i, path in enumerate(paths):
        spec.insert(tree, tiles.load_scan(path, poses[i] if poses else None))
    return tree


@pytest.fixture(scope="module", params=[1, 2, 4], ids=lambda w: "%d_workers" % w)
def cluster(request):
    from dask.distributed import LocalCluster

    with LocalCluster(n_workers=request.param, threads_per_worker=1, processes=True,
                      dashboard_address=":0") as c:
        yield c.scheduler_address


@pytest.mark.parametrize("level", [4, 6])
def test_tiles_equal_the_single_process_map(room_scans, tmp_path, cluster, level):
    spec = tiles.MapSpec(0.05, rule="log_odds")
    paths = [s[0] for s in room_scans]
    records = tiles.map_tiles(paths, str(tmp_path), spec, level, scheduler=cluster, stitch=True)
    assert len(records) > (1 if level == 6 else 20)
    whole = single_process_map(spec, paths)
    assert whole.occupied_count > 1000
    assert same_cells(pcl_fot.FastOctTree.load(str(tmp_path / "map.fot")), whole)
    assert same_cells(tiles.open_tile_set(str(tmp_path)), whole)
    # Each tile holds only its own cube.
    for r in records:
        lo, hi = tiles.tile_box(level, r["index"])
        corners, levels, _ = pcl_fot.FastOctTree.load(str(tmp_path / r["file"])).cells()
        assert (corners >= lo).all() and (corners + (1 << levels.astype(np.int64))[:, None] - 1 <= hi).all()


def test_binary_rule_and_poses_from_a_file(room_scans, tmp_path):
    # The scans' poses given apart, the files' VIEWPOINTs then ignored: the same map.
    spec = tiles.MapSpec(0.05, rule="binary", max_range=3.0)
    paths = [s[0] for s in room_scans]
    poses = [(s[2], s[3]) for s in room_scans]
    pose_file = tmp_path / "poses.txt"
    pose_file.write_text("# tx ty tz qw qx qy qz\n" + "".join(
        " ".join(repr(float(v)) for v in tuple(o) + tuple(q)) + "\n" for o, q in poses))
    assert tiles.read_poses(str(pose_file)) == [(tuple(map(float, o)), tuple(map(float, q))) for o, q in poses]
    tiles.map_tiles(paths, str(tmp_path / "out"), spec, 5, poses=tiles.read_poses(str(pose_file)), workers=2)
    whole = single_process_map(spec, paths)
    assert whole.rule == "binary" and same_cells(tiles.open_tile_set(str(tmp_path / "out")), whole)


def test_damaged_tile_sets_fail_naming_the_tile(room_scans, tmp_path):
    spec = tiles.MapSpec(0.05)
    out = tmp_path / "set"
    records = tiles.map_tiles([s[0] for s in room_scans[:2]], str(out), spec, 5, workers=1)
    assert not (out / "map.fot").exists()
    name = records[0]["name"]
    tile = out / records[0]["file"]
    data = tile.read_bytes()

    def broken(change):
        shutil.copytree(str(out), str(tmp_path / "copy"))
        change(tmp_path / "copy")
        with pytest.raises(tiles.TileSetError) as e:
            tiles.open_tile_set(str(tmp_path / "copy"))
        shutil.rmtree(str(tmp_path / "copy"))
        return str(e.value)

    assert name in broken(lambda d: os.remove(str(d / records[0]["file"])))
    assert name in broken(lambda d: (d / records[0]["file"]).write_bytes(data[: len(data) // 2]))
    other = pcl_fot.FastOctTree(0.1)
    other.insert_scan(room_scans[0][1], room_scans[0][2], room_scans[0][3])
    assert "grid" in broken(lambda d: other.save(str(d / records[0]["file"])))
    misplaced = dict(records[0], index=[i + 1000 for i in records[0]["index"]])

    def move(d):
        index = json.loads((d / "tiles.json").read_text())
        index["tiles"][0] = misplaced
        (d / "tiles.json").write_text(json.dumps(index))

    assert "outside its cube" in broken(move)
    assert "tiles.json" in broken(lambda d: (d / "tiles.json").write_text("{"))
    with pytest.raises(tiles.TileSetError, match="is an input"):
        tiles.map_tiles([str(out / "tiles.json")], str(out), spec, 5)
    with pytest.raises(tiles.TileSetError, match="tile level"):
        tiles.map_tiles([room_scans[0][0]], str(tmp_path / "x"), spec, 16)
    assert tiles._main(["map", room_scans[0][0], "-out", str(tmp_path / "y"), "--tile-level", "0"]) == 2


def test_command_line_maps_and_summarises(room_scans, tmp_path, capsys):
    out = str(tmp_path / "cli")
    args = ["map", "--workers", "2", "--tile-level", "6", "-res", "0.05", "--stitch", "-out", out]
    args += [s[0] for s in room_scans]
    # As a user runs it: the module as __main__, its tasks sent to worker processes.
    run = subprocess.run([sys.executable, "-m", "pcl_fot.tiles"] + args, capture_output=True, text=True)
    assert run.returncode == 0, run.stderr
    spec = tiles.MapSpec(0.05)
    assert same_cells(pcl_fot.FastOctTree.load(os.path.join(out, "map.fot")),
                      single_process_map(spec, [s[0] for s in room_scans]))
    assert tiles._main(["info", out]) == 0
    assert "occupied" in capsys.readouterr().out
    # A later run without --stitch leaves no stale map.fot beside its tile set.
    tiles.map_tiles([room_scans[0][0]], out, spec, 6, workers=1)
    assert sorted(os.listdir(out)) == ["tiles", "tiles.json"]
    assert same_cells(tiles.open_tile_set(out), single_process_map(spec, [room_scans[0][0]]))


def test_tools_read_a_tile_set_as_one_map(room_scans, tmp_path, tools_dir):
    spec = tiles.MapSpec(0.05)
    out = tmp_path / "set"
    tiles.map_tiles([s[0] for s in room_scans], str(out), spec, 5, workers=1)
    whole = single_process_map(spec, [s[0] for s in room_scans])
    for tile_set in (out, out / "tiles.json"):
        converted = str(tmp_path / "whole.fot")
        subprocess.run([os.path.join(tools_dir, "fot_convert"), str(tile_set), converted], check=True,
                       capture_output=True)
        assert same_cells(pcl_fot.FastOctTree.load(converted), whole)
        os.remove(converted)
    info = subprocess.run([os.path.join(tools_dir, "fot_info"), str(out)], capture_output=True, text=True)
    assert info.returncode == 0 and str(whole.occupied_count) in info.stdout + info.stderr
    # A tile set's own files are inputs; a damaged tile is named.
    tile = out / json.loads((out / "tiles.json").read_text())["tiles"][0]["file"]
    refused = subprocess.run([os.path.join(tools_dir, "fot_convert"), str(out), str(tile)], capture_output=True,
                             text=True)
    assert refused.returncode == 1
    tile.write_bytes(tile.read_bytes()[:40])
    damaged = subprocess.run([os.path.join(tools_dir, "fot_info"), str(out)], capture_output=True, text=True)
    assert damaged.returncode == 2 and "tile " + tile.stem in damaged.stderr
    good = (out / "tiles.json").read_text()
    index = json.loads(good)
    index["tiles"][0]["file"] = "../../outside.fot"
    (out / "tiles.json").write_text(json.dumps(index))
    outside = subprocess.run([os.path.join(tools_dir, "fot_info"), str(out)], capture_output=True, text=True)
    assert outside.returncode == 2 and "outside the tile set" in outside.stderr
    with pytest.raises(tiles.TileSetError, match="outside the tile set"):
        tiles.open_tile_set(str(out))
    (out / "tiles.json").write_text("[" * 100000)
    deep = subprocess.run([os.path.join(tools_dir, "fot_info"), str(out)], capture_output=True, text=True)
    assert deep.returncode == 2 and "nested too deeply" in deep.stderr
    (out / "tiles.json").write_text('{"format": "pcl_fot tile set", "tiles": [')
    bad = subprocess.run([os.path.join(tools_dir, "fot_info"), str(out)], capture_output=True, text=True)
    assert bad.returncode == 2 and "tiles.json" in bad.stderr
    index = json.loads(good)
    index["origin"] = ["1", 0, 0]  # a string where a number is due is refused, not read as 0
    (out / "tiles.json").write_text(json.dumps(index))
    typed = subprocess.run([os.path.join(tools_dir, "fot_info"), str(out)], capture_output=True, text=True)
    assert typed.returncode == 2 and "'origin' takes 3 numbers" in typed.stderr
    index["origin"] = [12345.5, 0, 0]
    for not_json in ("0x1p3", "NaN", "Infinity", "012", "1.", "1e"):  # numbers strtod would take
        (out / "tiles.json").write_text(json.dumps(index).replace("12345.5", not_json))
        odd = subprocess.run([os.path.join(tools_dir, "fot_info"), str(out)], capture_output=True, text=True)
        assert odd.returncode == 2 and "not valid JSON" in odd.stderr, not_json


class WorkerKiller:
    """A Dask worker plugin that ends its worker's process (as a crash or the OOM killer would) at a task's
    transition: the first task whose key starts with `prefix`, once in the whole cluster, or with `always`,
    that same task every time it runs. The task's key is written to `marker`."""

    def __init__(self, marker, prefix, finish, always=False):
        self.marker, self.prefix, self.finish, self.always = marker, prefix, finish, always

    def setup(self, worker):
        pass

    def teardown(self, worker):
        pass

    def transition(self, key, start, finish, **kwargs):
        if finish != self.finish or not str(key).startswith(self.prefix):
            return
        try:
            with open(self.marker, "x") as f:  # the first task to get here in any worker
                f.write(str(key))
        except FileExistsError:
            with open(self.marker) as f:
                if not self.always or f.read() != str(key):
                    return
        os._exit(1)


def killing_cluster(plugins, allowed_failures):
    from dask import config
    from dask.distributed import Client, LocalCluster

    with config.set({"distributed.scheduler.allowed-failures": allowed_failures}):
        cluster = LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=":0")
    with Client(cluster) as client:
        for i, plugin in enumerate(plugins):
            client.register_worker_plugin(plugin, name="killer%d" % i)
    return cluster


def test_workers_that_die_mid_task_change_nothing(room_scans, tmp_path):
    # One worker dies as a scan's trace starts, another after a tile's file is written but before its result
    # is reported: Dask runs both tasks again elsewhere, and the map is the single-process map.
    spec = tiles.MapSpec(0.05)
    paths = [s[0] for s in room_scans]
    plugins = [WorkerKiller(str(tmp_path / "trace.killed"), "trace-scan-", "executing"),
               WorkerKiller(str(tmp_path / "tile.killed"), "tile-", "memory")]
    with killing_cluster(plugins, allowed_failures=3) as cluster:
        tiles.map_tiles(paths, str(tmp_path / "out"), spec, 5, scheduler=cluster.scheduler_address)
    assert (tmp_path / "trace.killed").exists() and (tmp_path / "tile.killed").exists()
    assert same_cells(tiles.open_tile_set(str(tmp_path / "out")), single_process_map(spec, paths))
    assert sorted(os.listdir(str(tmp_path / "out"))) == ["tiles", "tiles.json"]


def test_a_failed_run_names_the_tile_and_keeps_the_earlier_tile_set(room_scans, tmp_path):
    spec = tiles.MapSpec(0.05)
    out = str(tmp_path / "out")
    tiles.map_tiles([room_scans[0][0]], out, spec, 5, workers=1)
    before = tiles.open_tile_set(out)
    index = (tmp_path / "out" / "tiles.json").read_bytes()
    marker = tmp_path / "tile.killed"
    with killing_cluster([WorkerKiller(str(marker), "tile-", "executing", always=True)], 0) as cluster:
        with pytest.raises(tiles.TileSetError) as e:
            tiles.map_tiles([s[0] for s in room_scans], out, spec, 5, scheduler=cluster.scheduler_address)
    # Dask gives up on the tasks the dead workers held (with no failures allowed, the killer's neighbours too),
    # and the error names the first of them.
    assert marker.exists() and re.match(r"task tile-5(-+\d+){3}-[0-9a-f]{8}: ", str(e.value))
    assert (tmp_path / "out" / "tiles.json").read_bytes() == index
    assert same_cells(tiles.open_tile_set(out), before)
    # A task still running when the run failed may leave files in the failed run's folder; the next run that
    # succeeds removes every folder its index does not name.
    records = tiles.map_tiles([room_scans[1][0]], out, spec, 5, workers=1)
    assert os.listdir(os.path.join(out, "tiles")) == [records[0]["file"].split(os.sep)[1]]
    assert sorted(os.listdir(out)) == ["tiles", "tiles.json"]


@pytest.mark.skipif(real_scan_dir() is None, reason="PCL's real scans not found (PCL_FOT_DATA_DIR)")
@pytest.mark.parametrize("level", [5, 7])
def test_tiles_equal_the_single_process_map_on_real_scans(tmp_path, cluster, level):
    paths = [os.path.join(real_scan_dir(), "kinect_capture000%d.pcd" % i) for i in (1, 2, 3)]
    spec = tiles.MapSpec(0.02, rule="log_odds")
    tiles.map_tiles(paths, str(tmp_path), spec, level, scheduler=cluster)
    whole = single_process_map(spec, paths)
    assert whole.occupied_count > 10000
    assert not (tmp_path / "map.fot").exists() and same_cells(tiles.open_tile_set(str(tmp_path)), whole)
