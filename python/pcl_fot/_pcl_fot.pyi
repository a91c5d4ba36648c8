"""Type hints of the extension module (python/src/*.cpp)."""

from typing import Any, Dict, Optional, Sequence, Tuple

import numpy as np
import numpy.typing as npt

Triple = Sequence[float]
KeyBox = Tuple[Tuple[int, int, int], Tuple[int, int, int]]

class MemoryLimitError(MemoryError): ...

class SensorModel:
    """OctoMap's sensor model: hit and miss probabilities, clamps and occupancy threshold."""
    def __init__(
        self,
        prob_hit: float = 0.7,
        prob_miss: float = 0.4,
        clamp_min: float = 0.1192,
        clamp_max: float = 0.971,
        occupancy: float = 0.5,
    ) -> None: ...
    @property
    def prob_hit(self) -> float: ...
    @property
    def prob_miss(self) -> float: ...
    @property
    def clamp_min(self) -> float: ...
    @property
    def clamp_max(self) -> float: ...
    @property
    def occupancy(self) -> float: ...

class FastOctTree:
    """An occupancy map of 4-byte nodes; rule 'binary' (the latest scan wins) or 'log_odds' (OctoMap's)."""
    def __init__(
        self,
        resolution: float,
        origin: Triple = (0.0, 0.0, 0.0),
        rule: str = "binary",
        sensor_model: SensorModel = ...,
    ) -> None: ...
    @property
    def resolution(self) -> float: ...
    @property
    def origin(self) -> Tuple[float, float, float]: ...
    @property
    def rule(self) -> str: ...
    @property
    def sensor_model(self) -> SensorModel: ...
    def insert_scan(
        self,
        points: npt.ArrayLike,
        origin: Triple,
        orientation: Optional[Sequence[float]] = None,
        *,
        max_range: float = -1.0,
        min_range: float = 0.0,
        discretize: bool = False,
        threads: int = 0,
        region: Optional[KeyBox] = None,
    ) -> Dict[str, int]:
        """Ray-traces one scan. Without orientation (w, x, y, z) the points are in the map frame and origin is
        the sensor; with it they are in the sensor frame. Only cells inside region (two keys, bounds
        included) are written. NaN, Inf and out-of-range points are skipped and counted."""
    def trace_scan(
        self,
        points: npt.ArrayLike,
        origin: Triple,
        orientation: Optional[Sequence[float]] = None,
        *,
        max_range: float = -1.0,
        min_range: float = 0.0,
        discretize: bool = False,
        threads: int = 0,
    ) -> Tuple[npt.NDArray[np.void], Dict[str, int]]:
        """Walks a scan's rays as insert_scan does and returns its cells (4x4x4 blocks: at, passed, hit)
        without writing this map; apply_scan writes them into any map of the same grid."""
    def apply_scan(self, blocks: npt.NDArray[np.void], *, region: Optional[KeyBox] = None) -> int:
        """Writes a traced scan with this map's rule; returns the cells marked free."""
    @staticmethod
    def block_keys(blocks: npt.NDArray[np.void]) -> npt.NDArray[np.int32]:
        """Each block's lowest key: a block lies in the level-L tile key >> L (L >= 2)."""
    def point_keys(self, points: npt.ArrayLike) -> npt.NDArray[np.int32]: ...
    def get_log_odds(self, keys: npt.ArrayLike) -> npt.NDArray[np.float32]:
        """Each key's log-odds; NaN for an unknown cell."""
    def get_state(self, keys: npt.ArrayLike) -> npt.NDArray[np.uint8]:
        """Each key's state: 0 unknown, 1 free, 2 occupied."""
    def cells(self) -> Tuple[npt.NDArray[np.int32], npt.NDArray[np.uint8], npt.NDArray[np.float32]]:
        """Every known cube in Morton order: its lowest key, its level (edge 2**level cells), its log-odds."""
    def occupied_centers(self) -> npt.NDArray[np.float64]: ...
    @property
    def occupied_count(self) -> int: ...
    @property
    def free_count(self) -> int: ...
    @property
    def node_count(self) -> int: ...
    @property
    def memory_bytes(self) -> int: ...
    @property
    def empty(self) -> bool: ...
    def merge(self, other: "FastOctTree") -> None:
        """Adds other's evidence: each cell other knows gets its log-odds as an update."""
    def save(self, path: str) -> None:
        """Writes .fot, .bt or .ot, by the extension, atomically."""
    @staticmethod
    def load(path: str) -> "FastOctTree": ...

class FastOctTreeSearch:
    """Exact k-NN and radius search on an (N, 3) array; squared Euclidean distances, as PCL's. Queries may
    run on many threads at once; add and remove need the search alone, as a write to a map does."""
    def __init__(self, points: Optional[npt.ArrayLike] = None, resolution: Optional[float] = None) -> None: ...
    def knn(
        self, queries: npt.ArrayLike, k: int
    ) -> Tuple[npt.NDArray[np.int32], npt.NDArray[np.float32]]:
        """(M, k) numbers and squared distances, nearest first; -1 and inf where fewer than k points exist."""
    def radius(
        self, query: Triple, radius: float, max_nn: int = 0
    ) -> Tuple[npt.NDArray[np.int32], npt.NDArray[np.float32]]: ...
    def add(self, points: npt.ArrayLike) -> npt.NDArray[np.int32]:
        """The numbers given to the points; -1 for those left out (not finite)."""
    def remove(self, numbers: npt.ArrayLike) -> int: ...
    @property
    def size(self) -> int: ...
    @property
    def memory_bytes(self) -> int: ...
    @property
    def resolution(self) -> float: ...

def psi(
    a: FastOctTree, b: FastOctTree, *, include_free: bool = False, cap: Optional[int] = None, threads: int = 1
) -> Dict[str, Any]:
    """The map similarity psi (Poppinga et al., eqs. 1-2) in cells: sum, cells, defined, mean, metres."""

def read_cloud(path: str) -> Dict[str, Any]:
    """A .pcd or .ply file: points (N, 3) float32, width, height, origin, orientation (w, x, y, z)."""
