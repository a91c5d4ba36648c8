"""Fixtures of the Python tests: the scans of synthetic_scans.py as files, PCL's real scans where they are
found (PCL_FOT_DATA_DIR, else ../shared/data), and the C++ tools the bindings are checked against."""

import os

import pytest

from synthetic_scans import depth_scan, write_pcd

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))


@pytest.fixture(scope="session")
def room_scans(tmp_path_factory):
    """Four depth scans of the room, as PCD files: [(path, points, origin, orientation)]."""
    directory = tmp_path_factory.mktemp("room")
    scans = []
    for seed in range(4):
        points, origin, q = depth_scan(seed)
        path = str(directory / ("scan%d.pcd" % seed))
        write_pcd(path, points, origin, q, width=96, height=72)
        scans.append((path, points, origin, q))
    return scans


def real_scan_dir():
    directory = os.environ.get("PCL_FOT_DATA_DIR") or os.path.join(ROOT, "..", "shared", "data")
    return directory if os.path.isfile(os.path.join(directory, "kinect_capture0001.pcd")) else None


@pytest.fixture(scope="session")
def tools_dir():
    """The C++ tools of the build tree beside the module (PCL_FOT_TOOLS_DIR overrides)."""
    import pcl_fot

    directory = os.environ.get("PCL_FOT_TOOLS_DIR") or os.path.join(
        os.path.dirname(os.path.dirname(os.path.dirname(pcl_fot.__file__))), "tools")
    if not os.path.isfile(os.path.join(directory, "fot_map")):
        pytest.fail("fot_map is not in %s: build the tools, or set PCL_FOT_TOOLS_DIR" % directory)
    return directory


def pytest_report_header(config):
    if real_scan_dir() is None:
        return ("real scans not found (PCL_FOT_DATA_DIR, else ../shared/data): their tests are skipped; "
                "doc/user_guide.md names the files of PCL's data repository")
    return "real scans: " + real_scan_dir()
