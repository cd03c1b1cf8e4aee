"""Type stubs of the photopose module (python/src/*.cc); tests/test_stub.py keeps them in step."""

import os
from typing import Any, Callable, Optional, Union

import numpy
from numpy.typing import ArrayLike, NDArray

_PathLike = Union[str, os.PathLike]

class Error(ValueError): ...

__version__: str
kDegreesPerRadian: float

class ExteriorOrientation:
    """The pose of an image in the seed convention: the projection centre in the ground frame (m) and
    the angles (omega, phi, kappa) (rad) of R_camera_from_ground = Rx(omega) Ry(phi) Rz(kappa), so that
    (u, v, w) = R_camera_from_ground (X - X0). The camera frame (u, v, w) has u along film x, v along
    film y and w towards the viewer: visible points have w < 0."""
    def __init__(self, center_in_ground: ArrayLike = (0.0, 0.0, 0.0), angles_rad: ArrayLike = (0.0, 0.0, 0.0), convention: str = 'rxryrz') -> None: ...
    @staticmethod
    def from_matrix(R_camera_from_ground: ArrayLike, center_in_ground: ArrayLike) -> ExteriorOrientation: ...
    @staticmethod
    def from_pose_matrix(T_camera_from_ground: ArrayLike) -> ExteriorOrientation: ...
    parameters: numpy.ndarray  # [X0, Y0, Z0 (m), omega, phi, kappa (rad, seed)], a copy.
    center_in_ground: numpy.ndarray  # Projection centre X0, Y0, Z0 (m, ground frame).
    angles_seed_rad: numpy.ndarray  # omega, phi, kappa (rad) of R = Rx(omega) Ry(phi) Rz(kappa) ('rxryrz').
    @property
    def R_camera_from_ground(self) -> numpy.ndarray: ...
    @property
    def T_camera_from_ground(self) -> numpy.ndarray: ...
    def angles_rad(self, convention: str = 'rxryrz', angle_direction: int = -1) -> numpy.ndarray: ...
    def angles_deg(self, convention: str = 'rxryrz', angle_direction: int = -1) -> numpy.ndarray: ...

def rotation_from_angles(angles_rad: ArrayLike, convention: str = 'rxryrz') -> numpy.ndarray: ...
def angles_from_rotation(R_camera_from_ground: ArrayLike, convention: str = 'rxryrz') -> numpy.ndarray: ...
def convention_angles_from_seed(seed_angles_rad: ArrayLike, convention: str, angle_direction: int = -1) -> numpy.ndarray: ...
def seed_angles_from_convention(convention_angles_rad: ArrayLike, convention: str, angle_direction: int = -1) -> numpy.ndarray: ...
def project_to_normalized(eo: ExteriorOrientation, points_in_ground: ArrayLike) -> numpy.ndarray: ...
def project_to_image_plane(eo: ExteriorOrientation, points_in_ground: ArrayLike, focal_length: float) -> numpy.ndarray: ...
class FrameCamera:
    """One row of an ArcGIS frame-camera table (docs/formats.md): focal length, principal point and
    distortion in micrometres and the table's mm-based coefficients, the pixel -> film mapping, flags."""
    def __init__(self, **kwargs: Any) -> None: ...
    camera_id: str
    focal_length_um: float
    principal_x_um: float
    principal_y_um: float
    pixel_size_um: float
    n_rows: int
    n_columns: int
    film_coordinate_system: int  # FilmCoordinateSystem 1-4 (1: x right, y up).
    has_affine: bool
    affine_a: list[float]  # A0, A1, A2
    affine_b: list[float]  # B0, B1, B2
    affine_direction: int
    radial_k: list[float]  # K0 (1), K1 (mm^-2), K2 (mm^-4), K3 (mm^-6)
    tangential_p: list[float]  # P1, P2 (mm^-1)
    distortion_table: bool  # DistortionType: True for DistortionTable (radial_distances_um / radial_distortions_um).
    radial_distances_um: list[float]
    radial_distortions_um: list[float]
    angle_direction: int
    polarity: int
    average_z_m: Optional[float]
    apply_ecc: bool
    earth_radius_m: float
    srs: str
    block_name: str
    def validate(self) -> None: ...
    def film_from_pixel(self, column_row: ArrayLike, pixel_origin: str = 'corner') -> numpy.ndarray: ...
    def pixel_from_film(self, film_um: ArrayLike, pixel_origin: str = 'corner') -> numpy.ndarray: ...
    def project(self, eo: ExteriorOrientation, points_in_ground: ArrayLike, pixel_origin: str = 'corner') -> numpy.ndarray: ...

class Camera:
    """The interior orientation of one camera of a block: a model of core/camera_models.h ('FRAME', the
    camera table's backward model with observations in film um; or COLMAP's 'SIMPLE_PINHOLE',
    'PINHOLE', 'SIMPLE_RADIAL', 'RADIAL', 'OPENCV' with observations in pixels, (0, 0) the top-left
    corner of the image) and its parameters in that model's order and units."""
    def __init__(self, model: str, params: ArrayLike, camera_id: str = '', width: int = 0, height: int = 0) -> None: ...
    @staticmethod
    def from_frame_camera(frame_camera: FrameCamera) -> Camera: ...
    camera_id: str
    @property
    def model(self) -> str: ...
    params: numpy.ndarray  # The model's parameters (a copy; assign an array to change them).
    @property
    def param_names(self) -> list[str]: ...
    @property
    def frame_camera(self) -> FrameCamera: ...  # The camera-table row (FRAME; a copy).
    @property
    def width(self) -> int: ...
    @property
    def height(self) -> int: ...
    @property
    def observation_unit(self) -> str: ...  # 'um' (film micrometres) for FRAME, 'px' for the COLMAP models.
    def project(self, eo: ExteriorOrientation, points_in_ground: ArrayLike) -> numpy.ndarray: ...
    def normalized_from_observations(self, observations: ArrayLike) -> numpy.ndarray: ...

class RansacOptions:
    """The consensus' sampling (solvers/resection/ransac.h)."""
    def __init__(self, **kwargs: Any) -> None: ...
    max_trials: int  # count, >= 1
    min_trials: int  # count
    confidence: float  # (0, 1)
    seed: int
    local_optimization: bool
    max_lo_iterations: int  # count
    max_exhaustive_samples: int  # count
    stop_enumeration_when_all_inliers: bool
    def validate(self) -> None: ...

class AbsolutePoseRansacOptions:
    """The consensus over P3P and DLT samples (solvers/resection/absolute_pose.h); the threshold and score are set per image by the resection from its tests."""
    def __init__(self, **kwargs: Any) -> None: ...
    ransac: RansacOptions
    inlier_threshold: float
    lo_gauss_newton_iterations: int  # count, >= 1
    final_gauss_newton_iterations: int  # count, >= 0
    def validate(self) -> None: ...

class OutlierTestOptions:
    """The confidence of every test of the resection."""
    def __init__(self, **kwargs: Any) -> None: ...
    confidence: float  # 1 - alpha, (0, 1)
    def validate(self) -> None: ...

class CeresPoseOptions:
    """How Ceres minimises one image's problem."""
    def __init__(self, **kwargs: Any) -> None: ...
    minimizer: str  # 'tiny_solver' or 'problem'
    max_iterations: int  # count
    max_reweighting_rounds: int  # count
    step_tolerance_sigmas: float  # the pose's standard deviations
    function_tolerance: float
    parameter_tolerance: float
    def validate(self) -> None: ...

class TaylorResectionOptions:
    """The seed's Taylor Gauss-Newton (solvers/resection/taylor_resection.h)."""
    def __init__(self, **kwargs: Any) -> None: ...
    partials: str
    max_iterations: int  # count
    position_tolerance_m: float  # m
    angle_tolerance_rad: float  # rad
    collinearity_tolerance: float
    min_reciprocal_condition: float
    divergence_distance_factor: float
    def validate(self) -> None: ...

class PoseRefinementOptions:
    """The least-squares refinement: solver ('ceres', 'taylor', 'taylor_as_printed'), Jacobian ('analytic', 'autodiff'), loss ('none', 'huber', ...) and its scale (sigmas)."""
    def __init__(self, **kwargs: Any) -> None: ...
    solver: str
    jacobian: str
    loss: str
    loss_scale: float  # sigmas of the marks
    ceres: CeresPoseOptions
    taylor: TaylorResectionOptions
    def validate(self) -> None: ...

class ResectionOptions:
    """The robust resection's options, composed as in C++: consensus (RANSAC), test (confidence),
    refinement (solver, Jacobian, loss), and the verdict's limits."""
    def __init__(self, **kwargs: Any) -> None: ...
    consensus: AbsolutePoseRansacOptions
    test: OutlierTestOptions
    refinement: PoseRefinementOptions
    allow_no_redundancy: bool
    ambiguous_pose_sigmas: float  # the accepted pose's standard deviations
    detection_power: float  # (0, 1)
    weak_pose_shift_sigmas: float  # standard deviations of a pose parameter
    refuse_weak: bool
    consensus_after_approximate: bool  # try the consensus start when the approximate pose does not solve the image
    def validate(self) -> None: ...

class ResectionInput:
    """One image's control marks: N x 2 ideal image-plane points (distortion removed, principal point at
    the origin, x right, y up, in the unit of focal_length: um for film cameras, px for the COLMAP
    models), their N x 3 ground points (m), per-mark sigma in the mark's own unit (0 or None: not
    stated), observation_units_per_unit (image-plane units per mark unit, e.g. um per px) and units
    ('px' or 'um'), an optional approximate pose. Block.resection_input builds it from a block."""
    def __init__(self, image_plane: ArrayLike, points_in_ground: ArrayLike, focal_length: float, *, sigma: Optional[ArrayLike] = None, observation_units_per_unit: Optional[ArrayLike] = None, units: Optional[Union[str, list[str]]] = None, point_ids: Optional[list[str]] = None, approximate: Optional[ExteriorOrientation] = None, raster: str = '', earth_radius_m: float = 0.0) -> None: ...
    raster: str
    focal_length: float
    @property
    def image_plane(self) -> numpy.ndarray: ...
    @property
    def points_in_ground(self) -> numpy.ndarray: ...
    @property
    def sigma(self) -> numpy.ndarray: ...
    @property
    def observation_units_per_unit(self) -> numpy.ndarray: ...
    @property
    def units(self) -> list[str]: ...
    @property
    def point_ids(self) -> list[str]: ...
    approximate: Optional[ExteriorOrientation]
    earth_radius_m: float
    def __len__(self) -> int: ...

class ResectionSummary:
    """How the resection of one image went."""
    @property
    def termination(self) -> str: ...  # 'converged', 'no_convergence', 'failure' or 'cancelled'
    @property
    def message(self) -> str: ...  # why it failed, with its numbers
    @property
    def used_approximate(self) -> bool: ...
    @property
    def consensus_after_approximate(self) -> bool: ...  # the approximate pose was tried first and abandoned for the consensus start
    @property
    def approximate_message(self) -> str: ...  # what the abandoned approximate start gave
    @property
    def ransac_trials(self) -> int: ...
    @property
    def ransac_exhaustive(self) -> bool: ...
    @property
    def ransac_stopped_early(self) -> bool: ...
    @property
    def adjustments(self) -> int: ...
    @property
    def iterations(self) -> int: ...
    @property
    def initial_cost(self) -> float: ...
    @property
    def final_cost(self) -> float: ...
    @property
    def ransac_seconds(self) -> float: ...
    @property
    def refinement_seconds(self) -> float: ...
    @property
    def total_seconds(self) -> float: ...
    def brief_report(self) -> str: ...
    def is_solution_usable(self) -> bool: ...

class ResectionResult:
    """The resection of one image: success (never a pose on failure: summary.message says why), the pose
    (seed angles), its 6 x 6 covariance (m, rad: a-priori with stated accuracies, sigma0^2 times it
    without; covariance_factor says which) and standard deviations, sigma0, and per mark (input
    order) residuals (N x 2, the mark's unit, image-plane axes), normalized residuals, redundancy
    numbers, minimal detectable blunders, pose shifts (sigmas) and status."""
    @property
    def success(self) -> bool: ...
    @property
    def eo(self) -> ExteriorOrientation: ...
    @property
    def has_covariance(self) -> bool: ...
    @property
    def covariance(self) -> numpy.ndarray: ...  # 6 x 6 (m^2, rad^2; X0, Y0, Z0, seed omega, phi, kappa)
    @property
    def standard_deviations(self) -> numpy.ndarray: ...  # 6 (m, rad)
    @property
    def covariance_factor(self) -> float: ...  # the covariance over N^-1: 1 with stated accuracies, sigma0^2 without
    @property
    def sigma_upper_factor(self) -> float: ...  # how many times the true sigmas may exceed the reported ones at 95 % (1 with stated accuracies)
    @property
    def accuracy_stated(self) -> bool: ...
    @property
    def sigma0(self) -> float: ...
    @property
    def degrees_of_freedom(self) -> int: ...
    @property
    def num_inliers(self) -> int: ...
    @property
    def residuals(self) -> numpy.ndarray: ...
    @property
    def normalized_residuals(self) -> numpy.ndarray: ...
    @property
    def redundancy_numbers(self) -> numpy.ndarray: ...
    @property
    def minimal_detectable_blunders(self) -> numpy.ndarray: ...
    @property
    def pose_shifts_sigmas(self) -> numpy.ndarray: ...
    @property
    def mark_status(self) -> list[str]: ...  # per mark: 'accepted', 'outlier' or 'rejected'
    @property
    def inliers(self) -> NDArray[numpy.bool_]: ...
    @property
    def critical_normalized_residual(self) -> float: ...
    @property
    def max_pose_shift_sigmas(self) -> float: ...
    @property
    def weakest_mark(self) -> int: ...
    @property
    def weak(self) -> bool: ...
    @property
    def accuracy_disagrees(self) -> bool: ...
    @property
    def ambiguous(self) -> bool: ...
    @property
    def competing_eo(self) -> ExteriorOrientation: ...
    @property
    def competing_inliers(self) -> NDArray[numpy.bool_]: ...
    @property
    def warnings(self) -> list[str]: ...
    @property
    def cancelled(self) -> bool: ...  # not resected: the batch was cancelled before this image started
    @property
    def summary(self) -> ResectionSummary: ...

def resect(input: ResectionInput, options: Optional[ResectionOptions] = None) -> ResectionResult: ...
class ResectionProgress:
    """resect_images' progress, given to its callback as the batch goes."""
    @property
    def images_done(self) -> int: ...  # count, increasing to images_total
    @property
    def images_total(self) -> int: ...  # count
    @property
    def elapsed_seconds(self) -> float: ...  # s since the call started

def resect_images(inputs: list[ResectionInput], options: Optional[ResectionOptions] = None, num_threads: int = 0, *, progress: Optional[Callable[[ResectionProgress], Optional[bool]]] = None) -> list[ResectionResult]: ...
class GroundPoint:
    """A row of the ground points table."""
    def __init__(self, **kwargs: Any) -> None: ...
    point_id: str
    position: numpy.ndarray  # X, Y, Z (m)
    accuracy_m: Optional[numpy.ndarray]  # AccuracyX/Y/Z (m) or None
    role: str  # 'control', 'check' or 'tie'
    line: int

class ImageMark:
    """A row of the image marks table."""
    def __init__(self, **kwargs: Any) -> None: ...
    raster: str
    point_id: str
    column_row: Optional[numpy.ndarray]  # Column, Row (px) or None
    film_um: Optional[numpy.ndarray]  # FilmX, FilmY (um) or None
    accuracy: Optional[float]  # one sigma in the mark's unit, or None
    camera_id: str
    line: int

class FrameRecord:
    """A row of the frames table: the exterior orientation (seed angles inside; the file's convention is
    applied on reading and writing), optional covariance (6 x 6, m and rad), sigma0, measured
    accuracies AccuracyX/Y/Z (m) and AccuracyOmega/Phi/Kappa (deg)."""
    def __init__(self, **kwargs: Any) -> None: ...
    raster: str
    camera_id: str
    eo: ExteriorOrientation
    srs: str
    covariance: Optional[numpy.ndarray]
    sigma0: Optional[float]
    center_accuracy_m: Optional[numpy.ndarray]
    attitude_accuracy_deg: Optional[numpy.ndarray]
    extra_columns: list[tuple[str, str]]
    line: int

class GcpList:
    """OpenDroneMap's gcp_list.txt: CRS, points, marks."""
    def __init__(self, **kwargs: Any) -> None: ...
    crs: str
    points: list[GroundPoint]
    marks: list[ImageMark]

def read_camera_table(path: _PathLike) -> list[FrameCamera]: ...
def write_camera_table(path: _PathLike, cameras: list[FrameCamera]) -> None: ...
def read_frames_table(path: _PathLike, rotation: str = 'rxryrz', cameras: Optional[list[FrameCamera]] = None) -> list[FrameRecord]: ...
def write_frames_table(path: _PathLike, frames: list[FrameRecord], rotation: str = 'rxryrz', cameras: Optional[list[FrameCamera]] = None) -> None: ...
def read_ground_points(path: _PathLike) -> list[GroundPoint]: ...
def write_ground_points(path: _PathLike, points: list[GroundPoint]) -> None: ...
def read_image_marks(path: _PathLike) -> list[ImageMark]: ...
def write_image_marks(path: _PathLike, marks: list[ImageMark]) -> None: ...
def read_gcp_list(path: _PathLike) -> GcpList: ...
class Block:
    """A photogrammetric block: cameras, images (with their exterior orientation when known), ground
    points (control, check, tie) and image marks. Arrays come out as copies: N x 3 points (m, ground
    frame), N x 2 marks in their own unit (px: Column/Row, (0, 0) the image's top-left corner, Row
    down, also when read with pixel_rows='up'; um: film), N x 6 poses [X0, Y0, Z0 (m), omega, phi, kappa (rad, seed: R_camera_from_ground
    = Rx Ry Rz)], NaN where a value is unset. Build one with Block.from_arrays, Block.from_tables,
    read_block, read_colmap_model, read_bal_problem, read_bundler_file or simulate_block."""
    @staticmethod
    def from_tables(cameras: list[FrameCamera], points: list[GroundPoint], marks: list[ImageMark], frames: list[FrameRecord] = [], frames_rotation: str = 'rxryrz', pixel_origin: str = 'corner', crs: str = '', pixel_rows: str = 'down') -> Block: ...
    @staticmethod
    def from_arrays(cameras: list[FrameCamera], point_ids: list[str], points_in_ground: ArrayLike, mark_rasters: list[str], mark_point_ids: list[str], marks: ArrayLike, *, point_roles: Optional[Union[str, list[str]]] = None, point_accuracy_m: Optional[ArrayLike] = None, mark_unit: str = 'px', mark_accuracy: Optional[ArrayLike] = None, mark_camera_ids: Optional[list[str]] = None, frames: list[FrameRecord] = [], frames_rotation: str = 'rxryrz', pixel_origin: str = 'corner', pixel_rows: str = 'down', crs: str = '') -> Block: ...
    def copy(self) -> Block: ...
    def check(self) -> None: ...
    @property
    def num_cameras(self) -> int: ...
    @property
    def num_images(self) -> int: ...
    @property
    def num_points(self) -> int: ...
    @property
    def num_marks(self) -> int: ...
    @property
    def crs(self) -> str: ...
    @property
    def pixel_origin(self) -> str: ...
    @property
    def cameras(self) -> list[Camera]: ...  # The cameras (copies; set_camera_params changes the block's).
    @property
    def image_names(self) -> list[str]: ...
    @property
    def image_cameras(self) -> numpy.ndarray: ...  # Per image, the index of its camera.
    @property
    def image_parameters(self) -> numpy.ndarray: ...  # N x 6 [X0, Y0, Z0 (m), omega, phi, kappa (rad, seed)]; NaN rows: no orientation.
    @property
    def image_centers(self) -> numpy.ndarray: ...  # N x 3 projection centres (m); NaN rows: no orientation.
    @property
    def T_camera_from_ground(self) -> numpy.ndarray: ...
    @property
    def measured_centers(self) -> numpy.ndarray: ...  # N x 3 measured (GNSS) centres (m); NaN rows: none.
    @property
    def center_accuracies_m(self) -> numpy.ndarray: ...  # N x 3 per-image accuracy of the measured centres (m); NaN rows: the adjustment's default.
    @property
    def point_ids(self) -> list[str]: ...
    @property
    def point_roles(self) -> list[str]: ...  # Per point: 'control', 'check' or 'tie'.
    @property
    def point_positions(self) -> numpy.ndarray: ...  # N x 3 current estimates (m); NaN rows: unknown.
    @property
    def surveyed_positions(self) -> numpy.ndarray: ...  # N x 3 surveyed coordinates of control and check points (m); NaN rows: tie points.
    @property
    def mark_images(self) -> numpy.ndarray: ...
    @property
    def mark_points(self) -> numpy.ndarray: ...
    @property
    def mark_measured(self) -> numpy.ndarray: ...  # M x 2 as read, in each mark's unit (mark_units).
    @property
    def mark_units(self) -> list[str]: ...
    @property
    def mark_observations(self) -> numpy.ndarray: ...  # M x 2 in the camera model's unit (film um for FRAME, px for the COLMAP models).
    def find_image(self, name: str) -> int: ...
    def find_point(self, point_id: str) -> int: ...
    def image_eo(self, image: int) -> Optional[ExteriorOrientation]: ...
    def set_image_eo(self, image: int, eo: Optional[ExteriorOrientation]) -> None: ...
    def set_image_parameters(self, parameters: ArrayLike) -> None: ...
    def set_point_positions(self, positions: ArrayLike) -> None: ...
    def set_measured_centers(self, centers: ArrayLike, accuracy_m: Optional[ArrayLike] = None) -> None: ...
    def set_camera_params(self, camera: int, params: ArrayLike) -> None: ...
    def resection_input(self, image: int, *, default_accuracy: float = 1.0, default_film_accuracy_um: float = 5.0, include_tie_points_with_positions: bool = False) -> ResectionInput: ...
    def resection_inputs(self, *, default_accuracy: float = 1.0, default_film_accuracy_um: float = 5.0) -> tuple: ...

def read_block(cameras: _PathLike, points: Optional[_PathLike] = None, marks: Optional[_PathLike] = None, *, gcp_list: Optional[_PathLike] = None, frames: Optional[_PathLike] = None, fiducials: Optional[_PathLike] = None, rotation: str = 'rxryrz', pixel_origin: str = 'corner', pixel_rows: str = 'down', max_fiducial_residual_um: float = 30.0) -> Block: ...
def read_colmap_model(directory: _PathLike) -> Block: ...
def read_bal_problem(path: _PathLike) -> Block: ...
def read_bundler_file(path: _PathLike) -> Block: ...
def write_colmap_model(block: Block, directory: _PathLike) -> None: ...
def write_block_tables(block: Block, *, cameras: Optional[_PathLike] = None, points: Optional[_PathLike] = None, marks: Optional[_PathLike] = None, frames: Optional[_PathLike] = None, rotation: str = 'rxryrz', write_tie_points: bool = True) -> None: ...
class SyntheticBlockOptions:
    """The seeded synthetic aerial block of tests, benchmarks and `photopose simulate --scenario=block`
    (core/simulation/synthetic_block.h): flight lines, terrain, camera, points, noise, blunders, a
    perturbed start."""
    def __init__(self, **kwargs: Any) -> None: ...
    seed: int
    num_lines: int
    images_per_line: int
    forward_spacing_m: float
    side_spacing_m: float
    forward_overlap: float
    side_overlap: float
    flying_height_m: float
    origin_m: numpy.ndarray
    serpentine: bool
    position_jitter_m: float
    attitude_jitter_deg: float
    nominal_angles_deg: numpy.ndarray
    ground_height_m: float
    terrain_relief_m: float
    camera_model: str
    focal_length_mm: float
    pixel_size_um: float
    image_width_px: int
    image_height_px: int
    camera_params: list[float]
    earth_curvature: bool
    num_tie_points: int
    tie_point_density_per_m2: float
    min_tie_views: int
    num_control_points: int
    num_check_points: int
    control_sigma_m: float
    control_accuracy_m: float
    mark_sigma_px: float
    mark_accuracy_px: float
    gnss: bool
    gnss_sigma_m: numpy.ndarray
    gnss_accuracy_m: numpy.ndarray
    attitude: bool
    attitude_sigma_deg: float
    attitude_accuracy_deg: float
    num_tie_blunders: int
    tie_blunder_px: float
    num_control_blunders: int
    control_blunder_m: float
    num_gnss_blunders: int
    gnss_blunder_m: float
    start_position_sigma_m: float
    start_angle_sigma_deg: float
    start_point_sigma_m: float
    tie_point_start: bool
    def validate(self) -> None: ...

class SyntheticBlockTruth:
    """The truth of a synthetic block."""
    @property
    def image_parameters(self) -> numpy.ndarray: ...  # N x 6 true orientations (m, rad, seed).
    @property
    def points_m(self) -> numpy.ndarray: ...
    @property
    def blunder_marks(self) -> numpy.ndarray: ...
    @property
    def blunder_control_points(self) -> numpy.ndarray: ...
    @property
    def blunder_gnss_images(self) -> numpy.ndarray: ...

def simulate_block(options: Optional[SyntheticBlockOptions] = None, **kwargs: Any) -> tuple: ...
class BundleAccuracies:
    """The stated accuracies of the objective's groups (one sigma; Metashape's reference settings by
    default). A per-row accuracy of the tables overrides its row's default."""
    def __init__(self, **kwargs: Any) -> None: ...
    tie_px: float  # px
    marker_projection_px: float  # px
    tie_film_um: float  # um
    marker_projection_film_um: float  # um
    marker_m: float  # m, per axis
    camera_m: numpy.ndarray  # m, X, Y, Z
    camera_positions_are_priors: bool
    attitude_deg: Optional[float]  # deg per angle, or None

class BundleRobustnessOptions:
    """Robust loss on tie marks, rejection rounds, data snooping."""
    def __init__(self, **kwargs: Any) -> None: ...
    tie_loss: str  # 'none', 'huber', 'cauchy', 'softl1'
    tie_loss_scale_sigmas: float  # sigmas
    rejection_threshold: float  # unitless
    max_rejection_rounds: int  # count
    snoop: bool
    max_snooping_removals: int  # count
    snooping_batch: bool  # several removals per round where the round's statistics decide them
    def validate(self) -> None: ...

class BundleStatisticsOptions:
    """Covariances, verdicts, diagnostics, variance components."""
    def __init__(self, **kwargs: Any) -> None: ...
    covariances: str  # 'full' (selected inversion), 'dense' (the test oracle) or 'none'
    weak_sigma_inflation: float  # unitless: sigma inflation above which a parameter is listed as weakly determined
    relative_covariance: str  # a relative block's covariance datum: 'points', 'centres' or 'first_image'
    overfit_ratio: float
    overfit_redundancy_share: float
    checked_redundancy_share: float  # above it a prior group's small RMS is a loose accuracy, not over-fitting
    high_correlation: float
    observation_diagnostics: bool
    snooping_alpha: float
    snooping_family_wise: bool
    snooping_power: float
    uncontrolled_redundancy: float
    estimate_accuracies: bool
    max_variance_iterations: int
    variance_tolerance: float
    min_variance_redundancy: float
    cross_validation: str  # 'update' (one linearised step per left-out point from the full adjustment) or 'refit' (one adjustment per point)
    def validate(self) -> None: ...

class BundleSolverOptions:
    """How the minimum is found. The progress hook is bundle_adjust's `progress` argument."""
    def __init__(self, **kwargs: Any) -> None: ...
    jacobian: str  # 'analytic' or 'autodiff'
    max_iterations: int  # per round
    function_tolerance: float
    parameter_tolerance: float
    gradient_tolerance: float
    linear_solver: str
    free_gauge_for_relative_blocks: bool
    num_threads: int  # 0: all cores
    def validate(self) -> None: ...

class BundleAdjustmentOptions:
    """The options of bundle_adjust, composed as in C++: accuracies, robustness, statistics, solver."""
    def __init__(self, **kwargs: Any) -> None: ...
    accuracies: BundleAccuracies
    robustness: BundleRobustnessOptions
    statistics: BundleStatisticsOptions
    solver: BundleSolverOptions
    def validate(self) -> None: ...

class BundleAdjustmentConfig:
    """What the adjustment holds constant or estimates: per camera the parameter indices to calibrate,
    constant images and points, the GNSS lever arm (camera frame u, v, w; m)."""
    def __init__(self, **kwargs: Any) -> None: ...
    calibrated_params: list[list[int]]
    constant_images: set[int]
    constant_points: set[int]
    lever_arm_m: Optional[numpy.ndarray]
    estimate_lever_arm: bool
    @staticmethod
    def from_calibration_names(block: Block, names: list[str]) -> BundleAdjustmentConfig: ...

class BundleIterationInfo:
    """One iteration, as progress reports it."""
    @property
    def round(self) -> int: ...
    @property
    def iteration(self) -> int: ...
    @property
    def cost(self) -> float: ...
    @property
    def sigma0(self) -> float: ...
    @property
    def step_norm(self) -> float: ...
    @property
    def elapsed_seconds(self) -> float: ...
    @property
    def free_gauge(self) -> bool: ...
    @property
    def trust_region_radius(self) -> float: ...
    @property
    def step_quality(self) -> float: ...
    @property
    def step_successful(self) -> bool: ...
    @property
    def linear_solver_seconds(self) -> float: ...
    @property
    def iteration_seconds(self) -> float: ...

class BundleAdjustmentSummary:
    @property
    def termination(self) -> str: ...  # 'converged', 'no_convergence', 'failure' or 'cancelled'
    @property
    def message(self) -> str: ...
    @property
    def datum(self) -> str: ...  # 'absolute' or 'relative'
    @property
    def datum_description(self) -> str: ...
    @property
    def rounds(self) -> int: ...
    @property
    def snooping_rounds(self) -> int: ...  # count
    @property
    def snooping_seconds(self) -> float: ...  # s
    @property
    def iterations(self) -> int: ...
    @property
    def initial_cost(self) -> float: ...
    @property
    def final_cost(self) -> float: ...
    @property
    def sigma0(self) -> float: ...
    @property
    def redundancy(self) -> int: ...
    @property
    def num_images(self) -> int: ...
    @property
    def num_points(self) -> int: ...
    @property
    def num_marks(self) -> int: ...
    @property
    def num_rejected_marks(self) -> int: ...
    @property
    def tie_points_left_out(self) -> list[str]: ...
    @property
    def time_seconds(self) -> float: ...
    @property
    def statistics_seconds(self) -> float: ...
    @property
    def problem_build_seconds(self) -> float: ...
    @property
    def solver_preprocessing_seconds(self) -> float: ...
    @property
    def residual_evaluation_seconds(self) -> float: ...
    @property
    def jacobian_evaluation_seconds(self) -> float: ...
    @property
    def linear_solver_seconds(self) -> float: ...
    @property
    def schur_structure(self) -> str: ...
    @property
    def solver(self) -> str: ...  # 'ceres', 'taylor' or 'taylor_as_printed'
    @property
    def plan_seconds(self) -> float: ...  # s
    @property
    def round_seconds(self) -> list[float]: ...  # s per round
    @property
    def rejection_seconds(self) -> float: ...  # s
    @property
    def factorization_seconds(self) -> float: ...  # s
    @property
    def inversion_seconds(self) -> float: ...  # s
    @property
    def covariance_entries(self) -> int: ...  # count
    @property
    def covariance_memory_bytes(self) -> int: ...  # bytes
    @property
    def covariance_datum(self) -> str: ...  # what the covariances refer to, in words
    def is_solution_usable(self) -> bool: ...
    def brief_report(self) -> str: ...

class BundleImageResult:
    @property
    def adjusted(self) -> bool: ...
    @property
    def message(self) -> str: ...
    @property
    def covariance(self) -> numpy.ndarray: ...  # 6 x 6 (m, rad; seed)
    @property
    def has_covariance(self) -> bool: ...
    @property
    def num_marks(self) -> int: ...
    @property
    def rms_residual(self) -> float: ...
    @property
    def unit(self) -> str: ...  # rms_residual's unit: 'px', 'um', or 'sigma' for an image with pixel and film marks

class BundlePointResult:
    @property
    def num_observations(self) -> int: ...
    @property
    def covariance(self) -> numpy.ndarray: ...  # 3 x 3 (m^2)
    @property
    def has_covariance(self) -> bool: ...
    @property
    def covariance_complete(self) -> bool: ...  # False: a check point's intersection alone (no statistics)
    @property
    def error_m(self) -> Optional[numpy.ndarray]: ...  # adjusted or intersected - surveyed (m)
    @property
    def message(self) -> str: ...

class BundleGroupStatistics:
    """One group of the objective."""
    @property
    def group(self) -> str: ...
    @property
    def count(self) -> int: ...
    @property
    def unit(self) -> str: ...
    @property
    def stated_accuracy(self) -> numpy.ndarray: ...
    @property
    def num_axes(self) -> int: ...
    @property
    def rms(self) -> numpy.ndarray: ...
    @property
    def rms_total(self) -> float: ...
    @property
    def ratio(self) -> float: ...
    @property
    def redundancy_share(self) -> float: ...
    # False also when not judged: a prior group whose redundancy_share is NaN (statistics
    # 'none') and whose ratio alone does not flag it; the JSON report writes null there.
    @property
    def overfit(self) -> bool: ...
    @property
    def message(self) -> str: ...
    @property
    def num_fixed(self) -> int: ...
    @property
    def fixed(self) -> bool: ...
    @property
    def estimated_accuracy(self) -> numpy.ndarray: ...
    @property
    def estimated_accuracy_standard_error(self) -> float: ...
    @property
    def estimation_message(self) -> str: ...

class BundleCalibrationResult:
    @property
    def camera(self) -> int: ...
    @property
    def names(self) -> list[str]: ...
    @property
    def indices(self) -> list[int]: ...
    @property
    def values(self) -> list[float]: ...
    @property
    def sigmas(self) -> list[float]: ...
    @property
    def correlation(self) -> numpy.ndarray: ...
    @property
    def high_correlations(self) -> list[str]: ...

class BundleRejectedMark:
    @property
    def mark(self) -> int: ...
    @property
    def round(self) -> int: ...
    @property
    def whitened_residual(self) -> float: ...

class BundleWeakParameter:
    """A parameter that trades off nearly exactly with others (weakly determined)."""
    @property
    def parameter(self) -> str: ...  # in words, e.g. "image 'IMG_3': omega"
    @property
    def sigma_inflation(self) -> float: ...  # its sigma over what its own observations give it (unitless)

class BundleRejectedCheckMark:
    """A check point's mark rejected by the w-test of its intersection."""
    @property
    def mark(self) -> int: ...  # index into the block's marks
    @property
    def normalized(self) -> float: ...  # the larger |w| of x and y
    @property
    def residual(self) -> numpy.ndarray: ...  # 2: observed - computed at the intersection that still held it, in the mark's own unit (px or um; x right, y up)

class BundleSnoopingStep:
    @property
    def group(self) -> str: ...
    @property
    def item(self) -> int: ...
    @property
    def axis(self) -> int: ...
    @property
    def normalized(self) -> float: ...
    @property
    def residual(self) -> float: ...
    @property
    def round(self) -> int: ...  # 1-based

class BundleAdjustmentResult:
    """The adjustment's result: summary (termination, sigma0, redundancy, timings), per image and per
    point results, the groups' statistics and over-fitting verdicts, calibration, rejected marks,
    check- and control-point RMSE, mark residuals, per-observation diagnostics. The block passed to
    bundle_adjust holds the adjusted values."""
    @property
    def summary(self) -> BundleAdjustmentSummary: ...
    @property
    def images(self) -> list[BundleImageResult]: ...
    @property
    def points(self) -> list[BundlePointResult]: ...
    @property
    def groups(self) -> list[BundleGroupStatistics]: ...
    @property
    def calibration(self) -> list[BundleCalibrationResult]: ...
    @property
    def rejected_marks(self) -> list[BundleRejectedMark]: ...
    @property
    def rejected_check_marks(self) -> list[BundleRejectedCheckMark]: ...
    @property
    def weakly_determined(self) -> list[BundleWeakParameter]: ...  # weakly determined parameters of an absolute block, the worst first
    @property
    def lever_arm_m(self) -> Optional[numpy.ndarray]: ...
    @property
    def num_check_points(self) -> int: ...
    @property
    def check_rmse_m(self) -> numpy.ndarray: ...  # x, y, z (m); NaN without a point
    @property
    def check_rmse_total_m(self) -> float: ...  # m; NaN without a point
    @property
    def num_control_points(self) -> int: ...
    @property
    def control_rmse_m(self) -> numpy.ndarray: ...  # x, y, z (m); NaN without a point
    @property
    def control_rmse_total_m(self) -> float: ...  # m; NaN without a point
    @property
    def mark_residuals(self) -> numpy.ndarray: ...  # M x 2 observed - computed (the mark's unit); NaN rows: not used.
    @property
    def variance_iterations(self) -> int: ...
    @property
    def observations(self) -> dict: ...  # Per-observation diagnostics as columns (dict of equal-length arrays): group (0 tie marks, 1 control marks, 2 control points, 3 camera positions, 4 attitudes), item, axis, residual, sigma, redundancy, normalized, mdb, external_m, rejected. residual, sigma, mdb and external_m are float32 (stored in single precision), redundancy and normalized float64. Empty arrays when not computed.
    @property
    def critical_value(self) -> float: ...
    @property
    def alpha_per_observation(self) -> float: ...
    @property
    def delta0(self) -> float: ...
    @property
    def num_uncontrolled(self) -> int: ...
    @property
    def snooping(self) -> list[BundleSnoopingStep]: ...
    @property
    def image_adjusted(self) -> NDArray[numpy.bool_]: ...
    @property
    def image_covariances(self) -> numpy.ndarray: ...  # N x 6 x 6 (m, rad; seed); NaN without covariance.
    @property
    def image_standard_deviations(self) -> numpy.ndarray: ...  # N x 6 (m, rad; seed); NaN without covariance.
    @property
    def point_errors_m(self) -> numpy.ndarray: ...  # N x 3 adjusted (control) or intersected (check) - surveyed (m); NaN for tie points.
    def full_report(self, block: Block) -> str: ...

def bundle_adjust(block: Block, options: Optional[BundleAdjustmentOptions] = None, config: Optional[BundleAdjustmentConfig] = None, *, progress: Optional[Callable[[BundleIterationInfo], Optional[bool]]] = None, solver: str = 'ceres') -> BundleAdjustmentResult: ...
class BlockInitializationOptions:
    """Initial values of a block: resection and intersection."""
    def __init__(self, **kwargs: Any) -> None: ...
    resection: ResectionOptions
    min_marks_for_resection: int
    min_intersection_angle_rad: float  # rad
    max_ray_misfit_rad: float  # rad
    default_sigma_px: float  # px
    default_sigma_um: float  # um
    max_rounds: int

class BlockInitializationSummary:
    @property
    def images_given(self) -> int: ...
    @property
    def images_resected(self) -> int: ...
    @property
    def points_given(self) -> int: ...
    @property
    def points_triangulated(self) -> int: ...
    @property
    def rounds(self) -> int: ...
    @property
    def not_oriented(self) -> list[tuple[int, str]]: ...  # [(image, reason)]
    @property
    def points_not_triangulated(self) -> int: ...
    def brief_report(self) -> str: ...

def initialize_block(block: Block, options: Optional[BlockInitializationOptions] = None) -> BlockInitializationSummary: ...
class BundleCrossValidationPoint:
    @property
    def point(self) -> int: ...
    @property
    def ok(self) -> bool: ...
    @property
    def message(self) -> str: ...
    @property
    def error_m(self) -> numpy.ndarray: ...
    @property
    def num_images(self) -> int: ...
    @property
    def normalized(self) -> float: ...
    @property
    def stands_out(self) -> bool: ...

class BundleCrossValidationResult:
    @property
    def points(self) -> list[BundleCrossValidationPoint]: ...
    @property
    def count(self) -> int: ...
    @property
    def rmse_m(self) -> numpy.ndarray: ...
    @property
    def rmse_total_m(self) -> float: ...
    @property
    def threshold(self) -> float: ...
    @property
    def time_seconds(self) -> float: ...
    @property
    def method(self) -> str: ...  # 'update' or 'refit': how the left-out adjustments were found

def cross_validate_control_points(adjusted: Block, full: BundleAdjustmentResult, options: Optional[BundleAdjustmentOptions] = None, config: Optional[BundleAdjustmentConfig] = None, num_threads: int = 0) -> BundleCrossValidationResult: ...

# ---------------------------------------------------------------- georeferencing
class GeoTxtRecord:
    """A line of ODM's geo.txt."""
    def __init__(self, **kwargs: Any) -> None: ...
    image: str
    position: numpy.ndarray  # x, y, z in the file's CRS (GIS order: easting or longitude first); z NaN without height
    has_height: bool  # False for a line 'image x y': horizontal only
    yaw_pitch_roll_deg: Optional[numpy.ndarray]  # deg, or None
    horizontal_accuracy_m: Optional[float]  # m, or None
    vertical_accuracy_m: Optional[float]  # m, or None
    line: int

class GeoTxt:
    """OpenDroneMap's geo.txt: CRS and camera positions."""
    def __init__(self, **kwargs: Any) -> None: ...
    crs: str
    records: list[GeoTxtRecord]

def read_geo_txt(path: _PathLike) -> GeoTxt: ...
class ExifGps:
    """The GPS position an image file carries (EXIF or DJI XMP)."""
    @property
    def lon_lat_height(self) -> numpy.ndarray: ...  # longitude, latitude (deg), height (m, as written)
    @property
    def source(self) -> str: ...  # 'exif' or 'dji_xmp'
    @property
    def rtk_sigma_enu_m(self) -> Optional[numpy.ndarray]: ...  # DJI RTK one sigma east, north, up (m)
    @property
    def rtk_flag(self) -> Optional[int]: ...  # DJI RtkFlag (50 fixed)

def read_image_gps(path: _PathLike) -> ExifGps: ...
def parse_image_gps(data: bytes, name: str = '<bytes>') -> ExifGps: ...
def read_images_gps(directory: _PathLike, names: list[str]) -> tuple: ...
class CameraPositionMeasurement:
    """A measured projection centre (GNSS) of an image, named as the block names it."""
    def __init__(self, **kwargs: Any) -> None: ...
    image: str
    position: numpy.ndarray  # in GeoreferenceInputs.positions_crs
    has_height: bool  # False: position[2] is not read; the position constrains the horizontal only
    accuracy_m: Optional[numpy.ndarray]  # one sigma east, north, up (m), or None
    line: int

class GeoreferenceInputs:
    """What ties a model to the ground: camera positions in positions_crs and control / check points in
    control_crs with their marks (px, (0, 0) the top-left corner of the image)."""
    def __init__(self, **kwargs: Any) -> None: ...
    positions_crs: str
    positions_source: str
    positions: list[CameraPositionMeasurement]
    control_crs: str
    control_source: str
    control_points: list[GroundPoint]
    control_marks: list[ImageMark]
    attitudes_not_used: int  # geo.txt yaw/pitch/roll read and not used (count)
    def set_positions(self, crs: str, images: list[str], positions: ArrayLike, accuracies_m: Optional[ArrayLike] = None, source: str = 'arrays') -> None: ...
    def set_positions_from_geo_txt(self, geo: GeoTxt, source: str = 'geo.txt') -> None: ...
    def set_positions_from_frames(self, frames: list[FrameRecord], crs: str = '', source: str = 'frames table') -> None: ...
    def set_positions_from_images_gps(self, images: list[str], gps: list[Optional[ExifGps]], crs: str = 'EPSG:4979') -> None: ...
    def set_control_from_gcp_list(self, gcp_list: GcpList, check_points: list[str] = [], source: str = 'gcp_list.txt') -> None: ...

class GeoreferenceOptions:
    """How a model is georeferenced."""
    def __init__(self, **kwargs: Any) -> None: ...
    out_crs: str  # empty: the control's CRS, else the positions' when projected, else the UTM zone of the centre
    default_camera_accuracy_m: float  # m
    default_marker_accuracy_m: float  # m

class GeoreferenceResult:
    """How the model was tied to the ground; the block itself is in the local ENU frame."""
    @property
    def out_crs(self) -> str: ...
    @property
    def out_crs_name(self) -> str: ...
    @property
    def out_crs_reason(self) -> str: ...
    @property
    def heights_notes(self) -> list[str]: ...
    @property
    def inputs_not_used(self) -> list[str]: ...  # inputs read and not used, each with the reason
    @property
    def positions_matched(self) -> int: ...
    @property
    def positions_without_height(self) -> int: ...  # of the matched positions, those without height
    @property
    def positions_unmatched(self) -> list[str]: ...
    @property
    def images_without_position(self) -> int: ...
    @property
    def control_marks_matched(self) -> int: ...
    @property
    def control_marks_unmatched(self) -> list[str]: ...
    @property
    def control_points_without_marks(self) -> list[str]: ...
    @property
    def similarity_scale(self) -> float: ...
    @property
    def similarity_rotation(self) -> numpy.ndarray: ...  # R_local_from_model (3 x 3)
    @property
    def similarity_translation(self) -> numpy.ndarray: ...  # m
    @property
    def similarity_inliers(self) -> int: ...
    @property
    def similarity_pairs(self) -> list[str]: ...
    @property
    def similarity_residuals_m(self) -> numpy.ndarray: ...
    @property
    def control_after_similarity(self) -> dict: ...  # count; rmse_m (level axes, m), total_m (m): None when count is 0
    @property
    def check_after_similarity(self) -> dict: ...  # as control_after_similarity
    @property
    def control_after_adjustment(self) -> dict: ...  # as control_after_similarity
    @property
    def check_after_adjustment(self) -> dict: ...  # as control_after_similarity
    @property
    def error_points(self) -> numpy.ndarray: ...  # indices into the block's points
    @property
    def errors_after_similarity_m(self) -> numpy.ndarray: ...  # K x 3, NaN where not computed
    @property
    def errors_after_adjustment_m(self) -> numpy.ndarray: ...  # K x 3, NaN where not computed
    @property
    def model_points(self) -> int: ...  # the block's first points are the model's; control follows
    @property
    def model_marks(self) -> int: ...
    @property
    def evaluated(self) -> bool: ...
    @property
    def prepare_seconds(self) -> float: ...
    @property
    def evaluate_seconds(self) -> float: ...
    def to_output_crs(self, points_local: ArrayLike) -> numpy.ndarray: ...
    def output_poses(self, block: Block) -> numpy.ndarray: ...

def prepare_georeference(block: Block, inputs: GeoreferenceInputs, options: Optional[GeoreferenceOptions] = None) -> GeoreferenceResult: ...
def evaluate_georeference(block: Block, adjustment: BundleAdjustmentResult, result: GeoreferenceResult) -> None: ...
def georeference_block(block: Block, inputs: GeoreferenceInputs, options: Optional[GeoreferenceOptions] = None, bundle_options: Optional[BundleAdjustmentOptions] = None, config: Optional[BundleAdjustmentConfig] = None, *, progress: Optional[Callable[[BundleIterationInfo], Optional[bool]]] = None) -> tuple: ...
def write_adjusted_colmap_model(block: Block, directory: _PathLike, adjustment: BundleAdjustmentResult, georeference: Optional[GeoreferenceResult] = None, *, format: str = 'text') -> None: ...
