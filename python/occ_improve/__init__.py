"""occ_improve: where should the range sensor look next?

Python bindings of the C++ library: range data from one viewpoint is fused into a spherical occupancy
grid, the surface of highest occupancy probability is extracted along every ray, and the expected
improvement of one more measurement is computed per ray and ranked into regions worth re-acquiring.

    import occ_improve as oi
    mapper = oi.Mapper(oi.kinect_v1_paper())
    depth, intrinsics = oi.sample_depth()
    mapper.insert_depth(depth, intrinsics)
    improvement = mapper.improvement()      # H x W float32
    regions = mapper.regions()              # list of Region, best first

See docs/PYTHON.md for input layouts (which ones are read in place), output lifetimes and threads.
"""
from ._core import (  # noqa: F401  (re-exported)
    MAP_FORMAT_VERSION,
    HAS_OCTOMAP,
    MAX_INTRINSICS_FIT_RESIDUAL_PX,
    AngularBinning,
    Cancelled,
    DepthBinning,
    DepthPredictionParams,
    DepthPredictionRule,
    Error,
    FormatError,
    GeometryParams,
    GridOptions,
    InsertionReport,
    IntrinsicsFit,
    InvalidInput,
    InvalidParameter,
    IoError,
    LocalModel,
    Mapper,
    MapperReport,
    PinholeIntrinsics,
    PinholePresetOptions,
    PlanMemory,
    PlanRequest,
    ProgressCriteria,
    RefineBy,
    Region,
    RegionOptions,
    ResourceLimit,
    ReturnModelParams,
    ReturnRecord,
    Segment,
    Segmentation,
    SegmentationParams,
    SensorModelParams,
    SensorPreset,
    Shot,
    ShotShape,
    StopCriteria,
    StopMonitor,
    StopSignal,
    UpdateMode,
    decimation_pattern,
    decimation_step,
    fit_intrinsics,
    fit_intrinsics_checked,
    kinect_v1,
    kinect_v1_intrinsics,
    kinect_v1_paper,
    kinect_v1_spherical,
    lidar_rings,
    LidarRingsOptions,
    registered_angular_binnings,
    registered_depth_binnings,
    load_map,
    load_map_and_returns,
    plan_next_shot,
    preset_by_name,
    preset_from_pinhole,
    predict_dense_depth,
    preset_names,
    record_return_rate,
    render_improvement_legend,
    render_segmentation,
    return_probability_map,
    sample_depth,
    segmentation_defaults,
    shot_scores,
)
from .frames import (  # noqa: F401
    depth_to_points,
    intrinsics_from_matrix,
    intrinsics_from_open3d,
    read_depth_png,
    read_intrinsics,
)
from .pcd import PcdCloud, read_pcd  # noqa: F401

if HAS_OCTOMAP:
    from ._core import FreeLeafRule, OctomapExportOptions, OctomapExportReport  # noqa: F401

__version__ = "0.1.0"
