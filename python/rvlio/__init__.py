"""rvlio: LiDAR-inertial odometry with reinforced vectors (RV-LIO).

The estimator, the recording readers, the evaluation and the simulator of the
`rvlio` command, from Python. See docs/python.md.
"""
from ._rvlio import (  # noqa: F401
    BagReader,
    Config,
    LIDAR_POINT_BYTES,
    ImuSample,
    LidarScan,
    MergeResult,
    Odometry,
    RefineResult,
    RunResult,
    RvReport,
    ScanResult,
    __version__,
    compare,
    evaluate,
    evaluate_degeneracy,
    evaluate_map,
    merge,
    read_bag,
    read_map,
    refine,
    run,
    simulate,
    tum_array,
)
