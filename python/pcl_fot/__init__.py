"""pcl_fot: the FastOctTree occupancy map, its nearest-neighbour search and the map similarity psi.

The classes and functions come from the C++ library through the extension module ``_pcl_fot``; arrays
are numpy arrays, (N, 3) for points and keys. ``pcl_fot.tiles`` maps scans tile by tile on Dask.
"""

from ._pcl_fot import (
    FastOctTree,
    FastOctTreeSearch,
    MemoryLimitError,
    SensorModel,
    psi,
    read_cloud,
)

__all__ = ["FastOctTree", "FastOctTreeSearch", "MemoryLimitError", "SensorModel", "psi", "read_cloud"]
