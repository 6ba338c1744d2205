"""lasercell: laser-triangulation metrology cell toolkit.

Units are millimetres and radians; transforms are 4x4 float64 arrays ``target_from_source``
(``p_target = T @ p_source``). Arrays returned by lasercell are read-only views into its own
storage; arrays passed in are copied, in any real dtype and memory order.

Errors: ``lasercell.InputError`` (also a ``ValueError``) for invalid input, with subclasses
``FileError`` (also an ``OSError``; ``.path``), ``OptionError`` and ``UnitError``;
``lasercell.InternalError`` for a bug in lasercell. All derive from ``lasercell.Error``.
"""

from ._lasercell import (  # noqa: F401
    __version__,
    Board,
    BoardDetections,
    BoardView,
    CadModel,
    CameraModel,
    Error,
    FileError,
    FrameGraph,
    HandEyeResult,
    InputError,
    IntrinsicsResult,
    InternalError,
    Job,
    JobResult,
    JobRunner,
    JointsResult,
    LaserHandEyeResult,
    LaserPlaneResult,
    LocalizationCandidate,
    LocalizationResult,
    OptionError,
    Part,
    PartInstance,
    PointCloud,
    PpfModel,
    ProfileSet,
    ReadReport,
    SpheresResult,
    Sweep,
    TransformWithCovariance,
    TriangleMesh,
    UnitError,
    align_icp,
    calibrate_handeye,
    calibrate_handeye_laser,
    calibrate_intrinsics,
    calibrate_joints,
    calibrate_laser_plane_from_heights,
    calibrate_laser_plane_from_stripes,
    calibrate_spheres,
    camera_calibration_dict,
    crop_box,
    detect_boards,
    estimate_normals,
    localize_in_cloud,
    read_cad_model,
    read_mesh,
    read_point_cloud,
    read_point_cloud_with_report,
    read_profiles,
    remove_small_clusters,
    run_job,
    scan_profiles,
    voxel_grid_downsample,
    write_point_cloud,
)
