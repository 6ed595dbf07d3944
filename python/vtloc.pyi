"""Type stub of the vtloc Python module (python/module.cpp, python/model.cpp)."""

from typing import Any, Dict, List, Optional, Sequence, Tuple, Union, overload

import numpy as np
import numpy.typing as npt

Image = Union[str, npt.NDArray[np.uint8]]          # path, or H x W x 3 uint8 RGB
Vec3 = Union[Sequence[float], npt.NDArray[np.floating]]

class Error(Exception):
    """Every engine failure: its message is one line naming the problem."""

def version() -> str: ...
def list_devices() -> List[Dict[str, Any]]: ...
def device_profile(index: int) -> str: ...
def inspect_model(path: str) -> Dict[str, Any]: ...
def load_tactile_image(path: str) -> npt.NDArray[np.uint8]: ...
# vtloc check: ok, nodes, outputs, first_failure (a node's name or None), tolerance, ms
def check(context: "Context", model: str, tactile: str, object: str) -> Dict[str, Any]: ...
# vtloc check --tracker: the same and touches (each touch's belief against the CPU reference's); with
# shapes, shape_terms (each frame's gel shape nodes, first_failure among them) and first_shape_failure
# ({"frame", "node"} of the first frame whose shape graph failed, or None)
def check_tracker(context: "Context", touches: str, object: str = "", hypotheses: int = 120000,
                  there_and_back: bool = True, touch_terms: bool = False,
                  shapes: bool = False, rendered_frames: bool = False, calibration: str = "",
                  background: str = "", codebook_cache: str = "",
                  codebook_samples: int = 0) -> Dict[str, Any]: ...

class Context:
    def __init__(self, device: str = "", validation: Optional[bool] = None) -> None: ...
    @property
    def device(self) -> Dict[str, Any]: ...
    @property
    def validation_enabled(self) -> bool: ...
    def take_validation_messages(self) -> List[str]: ...

class Symmetry:
    def __init__(self, axis_point: Vec3, axis_dir: Vec3, order: int) -> None: ...
    @property
    def axis_point(self) -> npt.NDArray[np.float64]: ...
    @property
    def axis_dir(self) -> npt.NDArray[np.float64]: ...
    @property
    def order(self) -> int: ...

class Object:
    @property
    def source(self) -> str: ...
    @property
    def cloud(self) -> npt.NDArray[np.float32]: ...        # N x 6
    @property
    def candidates(self) -> npt.NDArray[np.float32]: ...   # M x 3
    @property
    def candidate_count(self) -> int: ...
    @property
    def centre(self) -> npt.NDArray[np.float64]: ...
    @property
    def scale(self) -> float: ...
    @property
    def normals_estimated(self) -> bool: ...
    @property
    def source_points(self) -> int: ...

class TouchResult:
    @property
    def contact(self) -> npt.NDArray[np.float64]: ...              # (3,)
    @property
    def contact_normalised(self) -> npt.NDArray[np.float64]: ...
    @property
    def iterates(self) -> npt.NDArray[np.float64]: ...             # (N, 3)
    @property
    def iterates_normalised(self) -> npt.NDArray[np.float64]: ...
    @property
    def topk_index(self) -> npt.NDArray[np.int32]: ...
    @property
    def topk_score(self) -> npt.NDArray[np.float32]: ...
    @property
    def topk_point(self) -> npt.NDArray[np.float64]: ...           # (K, 3)
    @property
    def heatmap(self) -> npt.NDArray[np.float32]: ...              # per cloud point
    @property
    def alignment(self) -> Optional[float]: ...
    @property
    def timings(self) -> Dict[str, Any]: ...
    @property
    def tensors(self) -> Dict[str, np.ndarray]: ...

class Tracker:
    """The multi-touch filter (SPEC section 6). Motions and poses: 4 x 4 arrays, object units."""
    def __init__(self, context: Context, object: Union[str, npt.NDArray[np.floating]], press_mm: float = 0.8,
                 sigma_d_mm: float = 1.0, sigma_a_deg: float = 6.0, odometry_mm: float = 0.0,
                 odometry_deg: float = 0.0, window: int = 8, n_spin: int = 36, hypotheses: int = 120000,
                 network_weight: float = 0.5, object_units: float = 1.0,
                 candidates: Optional[npt.NDArray[np.floating]] = None,  # C x 3: hypotheses only there
                 render_weight: float = 0.25, codebook_cache: str = "",
                 render_quadratic: bool = True, render_press_percentile: float = 70.0,
                 render_cell_mm: float = 3.0,
                 threads: int = 0,  # host threads an estimate may use (0: up to 4)
                 free_space_mm: float = 1.5,  # the pad's clearance behind the gel (0: off)
                 render_refined_weight: float = 16.0,  # render-and-compare at the refined poses (0: off)
                 render_slack_rounds: int = 2,  # with odometry noise: earlier shapes aligned within it (0: off)
                 field_slack: bool = False,  # with odometry noise: the grid reads earlier terms within it
                 render_refined_floor: float = -5.0,  # one touch's floor at the refined poses (-inf: none)
                 profile: bool = False) -> None: ...  # each GPU step node by node, timed: step_nodes
    def add_touch(self, motion: Optional[npt.NDArray[np.floating]] = None, result: Optional[TouchResult] = None,
                  object: Optional[Object] = None,
                  shape: Optional[Dict[str, Any]] = None) -> None: ...  # GelShapeReader.read's dict
    def check_motion(self, motion: npt.NDArray[np.floating], touch: int) -> None: ...  # raises what add_touch would
    @property
    def max_hop(self) -> float: ...  # the farthest motion between two touches it accepts
    def shape_term(self, shape: Dict[str, Any]) -> npt.NDArray[np.float32]: ...  # render-and-compare, belief order
    def estimate(self) -> Dict[str, Any]: ...   # contact, pose (4x4), pose_contact, window_poses, modes, ...
    def evaluate_window(self, motions: List[npt.NDArray[np.floating]],
                        terms: Optional[List[Optional[npt.NDArray[np.float32]]]] = None,
                        shapes: Optional[List[Optional[Dict[str, Any]]]] = None) -> Dict[str, Any]: ...
    def window_fit(self, motions: List[npt.NDArray[np.floating]],
                   pose: npt.NDArray[np.floating]) -> float: ...  # against estimate()['fit']: search or ambiguity
    def add_touch_term(self, motion: Optional[npt.NDArray[np.floating]] = None,
                       term: Optional[npt.NDArray[np.float32]] = None,  # a precomputed shape_term
                       shape: Optional[Dict[str, Any]] = None) -> None: ...  # and the shape, for the refined poses
    def reset(self) -> None: ...  # forgets every touch; the object's tables stay
    def with_options(self, **options: Any) -> "Tracker": ...  # options' names but candidates; the surface reused
    @property
    def options(self) -> Dict[str, Any]: ...  # every option by name (the search's knobs too)
    @property
    def touches(self) -> int: ...
    @property
    def belief(self) -> npt.NDArray[np.float32]: ...       # over samples x spins, sums to 1
    @property
    def sample_points(self) -> npt.NDArray[np.float32]: ...  # S x 3
    @property
    def n_spin(self) -> int: ...
    @property
    def spacing_mm(self) -> float: ...
    @property
    def device_bytes(self) -> int: ...
    @property
    def host_bytes(self) -> int: ...  # the surface, its tables, the search's tree and index, the binned points once made
    @property
    def step_nodes(self) -> List[Tuple[str, float]]: ...  # the last step's GPU ms per node (profile=True)

class GelShapeReader:
    """The gel's shape from a GelSight frame (SPEC section 9), on the GPU."""
    def __init__(self, context: Context, calibration: str = "", mask_threshold: float = 0.7,
                 iterations: int = 50, match_lighting: bool = True, levels: int = 0,
                 coarse_iterations: int = 30, threads: int = 0) -> None: ...
    # levels > 0: the solve from a coarse start; threads: the tables' host threads (0: up to 4)
    def read(self, frame: Union[str, npt.NDArray[np.uint8]],
             empty: Optional[Union[str, npt.NDArray[np.uint8]]] = None) -> Dict[str, Any]: ...
    # depth_mm, grad_row, grad_col: H x W float32; mask: H x W uint8; mm_per_px: float
    # errors about a frame begin with its path where it is given as one ("frame" / "empty frame" otherwise)
    def check_frame(self, frame: Union[str, npt.NDArray[np.uint8]],
                    empty: Optional[Union[str, npt.NDArray[np.uint8]]] = None) -> None: ...
    # raises what read() would for these frames, without the GPU
    @property
    def height(self) -> int: ...
    @property
    def width(self) -> int: ...

class Model:
    @overload
    def __init__(self, context: Context, path: str) -> None: ...
    @overload
    def __init__(self, path: str) -> None: ...
    @property
    def info(self) -> Dict[str, Any]: ...
    def encode_object(self, source: Union[str, npt.NDArray[np.floating]],
                      candidates: Union[None, str, npt.NDArray[np.floating]] = None,
                      backend: str = "gpu", viewpoint: Optional[Vec3] = None) -> Object: ...
    def encode_depth(self, depth: str, intrinsics: Sequence[float], mask: Optional[str] = None,
                     unit_mm: float = 1.0, candidates: Union[None, str, npt.NDArray[np.floating]] = None,
                     backend: str = "gpu") -> Object: ...
    @overload
    def localize(self, object: Object, image: Image, iters: int = -1, top_k: int = 0, gma: bool = True,
                 symmetry: Optional[Symmetry] = None, backend: str = "gpu", keep_tensors: bool = False,
                 profile: bool = False, mm_per_px: Optional[float] = None) -> TouchResult: ...
    @overload
    def localize(self, object: Object, image: List[Image], iters: int = -1, top_k: int = 0, gma: bool = True,
                 symmetry: Optional[Symmetry] = None, backend: str = "gpu", keep_tensors: bool = False,
                 profile: bool = False, mm_per_px: Optional[float] = None) -> List[TouchResult]: ...

def write_heatmap_ply(path: str, object: Object, heat: npt.NDArray[np.floating]) -> None: ...
def render_heatmap_png(path: str, object: Object, heat: npt.NDArray[np.floating], width: int = 1280,
                       height: int = 720, contact: Optional[Vec3] = None, ground_truth: Optional[Vec3] = None,
                       up: Vec3 = (0, 1, 0), caption: str = "", tactile: Optional[Image] = None,
                       display_points: int = 30000) -> None: ...
