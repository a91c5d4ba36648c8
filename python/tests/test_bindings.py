"""The bindings against the C++ library's results (its tools), brute force and bad input."""

import os
import subprocess

import numpy as np
import pytest

import pcl_fot
from synthetic_scans import same_cells, write_pcd


def python_map(scans, rule, resolution=0.05):
    tree = pcl_fot.FastOctTree(resolution, rule=rule)
    for _, points, origin, q in scans:
        tree.insert_scan(points, origin, q)
    return tree


@pytest.mark.parametrize("rule", ["log_odds", "binary"])
def test_scans_give_fot_maps_cells(room_scans, tools_dir, tmp_path, rule):
    prefix = str(tmp_path / "cpp")
    args = [os.path.join(tools_dir, "fot_map"), "-res", "0.05", "-out", prefix]
    args += ["-binary"] if rule == "binary" else []
    subprocess.run(args + [s[0] for s in room_scans], check=True, capture_output=True)
    cpp = pcl_fot.FastOctTree.load(prefix + ".fot")
    ours = python_map(room_scans, rule)
    assert ours.occupied_count > 1000 and ours.free_count > 10000
    assert (ours.occupied_count, ours.free_count) == (cpp.occupied_count, cpp.free_count)
    assert same_cells(ours, cpp)


def test_cells_and_lookups_agree(room_scans):
    tree = python_map(room_scans + room_scans[:1] * 5, "log_odds")
    corners, levels, values = tree.cells()
    model = tree.sensor_model
    clamps = [np.float32(np.log(p / (1 - p))) for p in (model.clamp_min, model.clamp_max)]
    settled = np.isin(values, clamps)
    assert settled.any() and (~settled).any()
    single = levels == 0
    keys = corners[single]
    assert np.array_equal(tree.get_log_odds(keys).view(np.uint32), values[single].view(np.uint32))
    occupied = values[single] >= np.float32(np.log(model.occupancy / (1 - model.occupancy)))
    assert np.array_equal(tree.get_state(keys), np.where(occupied, 2, 1).astype(np.uint8))
    far = np.array([[100000, 0, 0]], dtype=np.int64)
    assert np.isnan(tree.get_log_odds(far)[0]) and tree.get_state(far)[0] == 0
    centres = tree.occupied_centers()
    assert len(centres) == tree.occupied_count
    assert (tree.get_state(tree.point_keys(centres)) == 2).all()


def test_traced_scans_and_regions_give_the_whole_maps_cells(room_scans):
    whole = python_map(room_scans, "log_odds")
    traced = pcl_fot.FastOctTree(0.05, rule="log_odds")
    lo, hi = (0, -32, 0), (31, -1, 31)  # a level-5 node of the tree
    part = pcl_fot.FastOctTree(0.05, rule="log_odds")
    outside = 0
    for _, points, origin, q in room_scans:
        blocks, stats = traced.trace_scan(points, origin, q)
        assert stats["rays"] > 0 and len(blocks) > 0
        traced.apply_scan(blocks)
        outside += part.insert_scan(points, origin, q, region=(lo, hi))["outside_region"]
    assert same_cells(traced, whole)
    assert outside > 0  # rays that cannot reach the region are not walked
    keys = np.stack(np.meshgrid(*[np.arange(a, b + 1) for a, b in zip(lo, hi)], indexing="ij"), -1).reshape(-1, 3)
    inside = whole.get_log_odds(keys)
    assert (~np.isnan(inside)).sum() > 1000
    assert np.array_equal(part.get_log_odds(keys).view(np.uint32), inside.view(np.uint32))
    corners, levels, _ = part.cells()
    assert (corners >= lo).all() and (corners + (1 << levels.astype(np.int64))[:, None] - 1 <= hi).all()
    with pytest.raises(TypeError, match="trace_scan"):
        traced.apply_scan(np.zeros(4))
    bad = blocks[:1].copy()
    bad["at"] = 2 ** 31
    with pytest.raises(ValueError, match="key range"):
        traced.apply_scan(bad)


def test_points_as_float64_and_non_contiguous_give_the_same_map(room_scans):
    _, points, origin, q = room_scans[0]
    a, b = pcl_fot.FastOctTree(0.05), pcl_fot.FastOctTree(0.05)
    a.insert_scan(points, origin, q)
    wide = np.asfortranarray(np.repeat(points.astype(np.float64), 2, axis=0)[::2])
    assert not wide.flags.c_contiguous
    b.insert_scan(wide, origin, q)
    assert same_cells(a, b)


def test_nan_points_are_counted_not_traced(room_scans):
    _, points, origin, q = room_scans[0]
    stats = pcl_fot.FastOctTree(0.05).insert_scan(points, origin, q)
    nan = int(np.isnan(points).any(axis=1).sum())
    assert nan > 0 and stats["non_finite"] == nan and stats["rays"] == len(points) - nan


def brute_knn(points, query, k):
    d = points - query  # PCL's distance in float: (dx² + dy²) + dz²
    sq = (d[:, 0] * d[:, 0] + d[:, 1] * d[:, 1]) + d[:, 2] * d[:, 2]
    order = np.lexsort((np.arange(len(points)), sq))[:k]
    return order, sq[order]


def test_search_equals_brute_force_and_follows_updates():
    rng = np.random.default_rng(7)
    points = rng.uniform(-5, 5, (3000, 3)).astype(np.float32)
    queries = rng.uniform(-6, 6, (50, 3)).astype(np.float32)
    search = pcl_fot.FastOctTreeSearch(points)
    indices, distances = search.knn(queries, 8)
    for q, i, d in zip(queries, indices, distances):
        bi, bd = brute_knn(points, q, 8)
        assert np.array_equal(i, bi) and np.array_equal(d, bd)
    found, d = search.radius(queries[0], 1.5)
    diff = points - queries[0]
    sq = (diff[:, 0] * diff[:, 0] + diff[:, 1] * diff[:, 1]) + diff[:, 2] * diff[:, 2]
    assert sorted(found) == sorted(np.flatnonzero(sq <= np.float32(1.5 * 1.5)))
    # Updates in place: the answers of a fresh build of the points held.
    more = rng.uniform(-5, 5, (500, 3)).astype(np.float32)
    added = search.add(np.vstack([more, [[np.nan, 0, 0]]]))
    assert np.array_equal(added[:-1], np.arange(3000, 3500)) and added[-1] == -1
    gone = rng.choice(3500, 700, replace=False)
    assert search.remove(gone) == 700 and search.size == 2800
    held = np.setdiff1d(np.arange(3500), gone)
    everything = np.vstack([points, more])
    for q, i, d in zip(queries, *search.knn(queries, 5)):
        bi, bd = brute_knn(everything[held], q, 5)
        assert np.array_equal(i, held[bi]) and np.array_equal(d, bd)
    few = pcl_fot.FastOctTreeSearch(points[:2])
    i, d = few.knn(queries[:1], 4)
    assert list(i[0, 2:]) == [-1, -1] and np.isinf(d[0, 2:]).all()


def brute_psi(a, b):
    """ψ by brute force over the occupied cells: each cell's Manhattan distance to the other map's nearest."""
    ka, kb = a.point_keys(a.occupied_centers()), b.point_keys(b.occupied_centers())

    def one_way(x, y):
        return int(sum(np.abs(y - c).sum(axis=1).min() for c in x))

    return one_way(ka, kb) + one_way(kb, ka)


def test_psi_equals_brute_force():
    rng = np.random.default_rng(3)
    a, b = pcl_fot.FastOctTree(0.1), pcl_fot.FastOctTree(0.1)
    for tree in (a, b):
        points = rng.uniform(-1, 1, (300, 3)).astype(np.float32)
        tree.insert_scan(points, (0, 0, 0))
    result = pcl_fot.psi(a, b)
    assert result["defined"] and result["sum"] == brute_psi(a, b) > 0
    assert pcl_fot.psi(a, a)["sum"] == 0 and pcl_fot.psi(b, a)["sum"] == result["sum"]


def test_files_round_trip(room_scans, tmp_path):
    tree = python_map(room_scans, "log_odds")
    for name in ("map.fot", "map.ot"):
        tree.save(str(tmp_path / name))
        assert same_cells(pcl_fot.FastOctTree.load(str(tmp_path / name)), tree)
    tree.save(str(tmp_path / "map.bt"))  # states only
    bt = pcl_fot.FastOctTree.load(str(tmp_path / "map.bt"))
    assert (bt.occupied_count, bt.free_count) == (tree.occupied_count, tree.free_count)


def test_read_cloud_gives_points_and_pose(tmp_path):
    points = np.array([[1, 2, 3], [np.nan, np.nan, np.nan], [4, 5, 6], [7, 8, 9]], dtype=np.float32)
    path = str(tmp_path / "c.pcd")
    write_pcd(path, points, (1.5, 2.5, 3.5), (0.0, 1.0, 0.0, 0.0), width=2, height=2)
    cloud = pcl_fot.read_cloud(path)
    assert np.array_equal(cloud["points"], points, equal_nan=True)
    assert (cloud["width"], cloud["height"]) == (2, 2)
    assert cloud["origin"] == (1.5, 2.5, 3.5) and cloud["orientation"] == (0.0, 1.0, 0.0, 0.0)


def test_bad_input_raises_and_changes_nothing(room_scans, tmp_path):
    tree = python_map(room_scans[:1], "log_odds")
    before = tree.cells()
    _, points, origin, q = room_scans[0]
    with pytest.raises(ValueError, match=r"\(N, 3\)"):
        tree.insert_scan(np.zeros((4, 2)), origin)
    with pytest.raises(TypeError, match="float32 or float64"):
        tree.insert_scan(np.zeros((4, 3), dtype=np.int32), origin)
    with pytest.raises(TypeError):
        tree.insert_scan("points", origin)
    with pytest.raises(ValueError, match="finite"):
        tree.insert_scan(points, (np.nan, 0, 0))
    with pytest.raises(ValueError, match="orientation"):
        tree.insert_scan(points, origin, (0, 0, 0, 0))
    with pytest.raises(ValueError, match="region"):
        tree.insert_scan(points, origin, q, region=((5, 5, 5), (0, 0, 0)))
    with pytest.raises(IndexError):  # a sensor beyond the key range
        tree.insert_scan(points, (1e9, 0, 0))
    with pytest.raises(ValueError, match="key range"):
        tree.get_state(np.array([[2 ** 30, 0, 0]]))
    for resolution in (0.0, -1.0, float("nan"), float("inf")):
        with pytest.raises(ValueError, match="resolution"):
            pcl_fot.FastOctTree(resolution)
    with pytest.raises(ValueError, match="rule"):
        pcl_fot.FastOctTree(0.05, rule="bayes")
    other = pcl_fot.FastOctTree(0.1)
    with pytest.raises(ValueError):
        tree.merge(other)
    with pytest.raises(ValueError):
        pcl_fot.psi(tree, other)
    with pytest.raises(ValueError, match="k must be positive"):
        pcl_fot.FastOctTreeSearch(points).knn(points[:1], 0)
    assert all(np.array_equal(x, y, equal_nan=True) for x, y in zip(tree.cells(), before))
    # Files: missing, truncated, damaged; a failed save leaves the old file.
    with pytest.raises(RuntimeError):
        pcl_fot.FastOctTree.load(str(tmp_path / "missing.fot"))
    path = str(tmp_path / "map.fot")
    tree.save(path)
    data = open(path, "rb").read()
    for damaged in (data[: len(data) // 2], data[:20] + bytes(len(data) - 20)):
        open(str(tmp_path / "bad.fot"), "wb").write(damaged)
        with pytest.raises(RuntimeError):
            pcl_fot.FastOctTree.load(str(tmp_path / "bad.fot"))
    with pytest.raises(ValueError, match=".fot, .bt or .ot"):
        tree.save(str(tmp_path / "map.txt"))
    with pytest.raises(RuntimeError):
        tree.save(str(tmp_path / "no_such_dir" / "map.fot"))
    assert open(path, "rb").read() == data
    open(str(tmp_path / "bad.pcd"), "wb").write(b"# .PCD v0.7\nFIELDS x y z\nSIZE 4 4")
    with pytest.raises(RuntimeError, match="bad.pcd"):
        pcl_fot.read_cloud(str(tmp_path / "bad.pcd"))
