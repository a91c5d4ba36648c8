"""Scans the Python tests make themselves, seeded: depth cameras in a furnished room, written as PCD files
with their pose as the VIEWPOINT; and the comparison of two maps."""

import numpy as np

# The room and its furniture as boxes (lo, hi): a depth camera sees their faces.
ROOM = (np.array([-4.0, -3.0, 0.0]), np.array([4.0, 3.0, 3.0]))
BOXES = [(np.array([1.0, -1.0, 0.0]), np.array([2.2, 0.2, 0.8])),
         (np.array([-2.5, 1.2, 0.0]), np.array([-1.6, 2.6, 1.9])),
         (np.array([-0.4, -2.4, 0.0]), np.array([0.3, -1.8, 2.9]))]


def _ray_hits(origin, dirs):
    """Distance along each unit direction to the first surface of the room or a box."""
    with np.errstate(divide="ignore", invalid="ignore"):
        inv = 1.0 / dirs
        # Inside the room: the nearest wall ahead.
        far = np.where(inv > 0, (ROOM[1] - origin) * inv, (ROOM[0] - origin) * inv)
        t = far.min(axis=1)
        for lo, hi in BOXES:
            t0, t1 = (lo - origin) * inv, (hi - origin) * inv
            near, exit_ = np.minimum(t0, t1).max(axis=1), np.maximum(t0, t1).min(axis=1)
            hit = (near <= exit_) & (near > 0)
            t = np.where(hit & (near < t), near, t)
    return t


def quaternion_about(axis, angle):
    axis = np.asarray(axis, dtype=np.float64) / np.linalg.norm(axis)
    return (np.cos(angle / 2),) + tuple(np.sin(angle / 2) * axis)


def depth_scan(seed, width=96, height=72):
    """A depth camera in the room: organised points in its frame (z ahead), NaN where the ray goes
    beyond 4 m, and its pose (origin, orientation w, x, y, z)."""
    rng = np.random.default_rng(seed)
    origin = np.array([rng.uniform(-2.5, 2.5), rng.uniform(-1.5, 1.5), rng.uniform(1.0, 2.0)])
    yaw = rng.uniform(0, 2 * np.pi)
    # Camera frame: z ahead, x right, y down; a turn about the map's z after the optical convention.
    u, v = np.meshgrid(np.linspace(-0.6, 0.6, width), np.linspace(-0.45, 0.45, height))
    cam = np.stack([u, v, np.ones_like(u)], axis=-1).reshape(-1, 3)
    cam /= np.linalg.norm(cam, axis=1)[:, None]
    optical = quaternion_about([1, 0, 0], -np.pi / 2)
    q = _mul(quaternion_about([0, 0, 1], yaw), optical)
    dirs = cam @ _matrix(q).T
    t = _ray_hits(origin, dirs) + rng.normal(0, 0.005, len(dirs))
    points = (cam * t[:, None]).astype(np.float32)
    points[t > 4.0] = np.nan
    return points, tuple(origin), q


def _mul(a, b):
    w1, x1, y1, z1 = a
    w2, x2, y2, z2 = b
    return (w1 * w2 - x1 * x2 - y1 * y2 - z1 * z2, w1 * x2 + x1 * w2 + y1 * z2 - z1 * y2,
            w1 * y2 - x1 * z2 + y1 * w2 + z1 * x2, w1 * z2 + x1 * y2 - y1 * x2 + z1 * w2)


def _matrix(q):
    w, x, y, z = q
    return np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
                     [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
                     [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)]])


def write_pcd(path, points, origin, orientation, width=None, height=1):
    """A binary PCD file of float x, y, z with the pose as its VIEWPOINT."""
    points = np.ascontiguousarray(points, dtype=np.float32)
    width = width or len(points)
    header = ("# .PCD v0.7\nVERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\n"
              "WIDTH %d\nHEIGHT %d\nVIEWPOINT %s\nPOINTS %d\nDATA binary\n"
              % (width, height, " ".join(repr(float(v)) for v in tuple(origin) + tuple(orientation)),
                 len(points)))
    with open(path, "wb") as f:
        f.write(header.encode() + points.tobytes())



def same_cells(a, b):
    """The two maps hold the same cubes with the same log-odds, bit for bit."""
    ca, cb = a.cells(), b.cells()
    return (all(len(x) == len(y) for x, y in zip(ca, cb)) and np.array_equal(ca[0], cb[0])
            and np.array_equal(ca[1], cb[1]) and np.array_equal(ca[2].view(np.uint32), cb[2].view(np.uint32)))
