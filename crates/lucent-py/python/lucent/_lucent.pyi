"""Type stubs of lucent's compiled module (crates/lucent-py/src). Units: mesh units for
positions (the model ``scale`` maps the rest mesh's largest bounding-box side to metres),
mm^-1 for scattering coefficients, degrees for angles; radiance in the lights' irradiance units
per steradian (a light of intensity 1 gives irradiance 1 facing it)."""

import os
from typing import Mapping, Optional, Sequence, Union

import numpy as np
import numpy.typing as npt

PathLike = Union[str, os.PathLike]
ArrayLike = npt.ArrayLike

class LucentError(Exception):
    """An error lucent reports, with its one-line message: bad input (mesh, material, light, a
    number out of its range), a missing file, or no GPU adapter."""

class Material:
    """A homogeneous scattering material (Jensen et al. 2001 dipole parameters)."""

    def __init__(
        self,
        sigma_s_prime: Sequence[float],
        sigma_a: Sequence[float],
        eta: float = 1.3,
        name: str = "custom",
    ) -> None:
        """From the reduced scattering and absorption coefficients per RGB channel (mm^-1, each
        within 1e-12..=1e4) and the relative index of refraction ``eta`` (1..=3)."""
    @staticmethod
    def preset(name: str) -> "Material":
        """A preset by name, case-insensitively (see ``presets()``); eta 1.3."""
    @staticmethod
    def from_albedo_mfp(
        albedo: Sequence[float], mfp: Sequence[float], eta: float = 1.3, name: str = "custom"
    ) -> "Material":
        """From the slab albedo per channel (0.001..=0.999: the colour of a thick flat slab under
        uniform light) and the reduced mean free path 1/sigma_t' per channel (mm, 1e-4..=1e3)."""
    def albedo_mfp(self) -> tuple[list[float], list[float]]:
        """``(albedo, mfp)``: the inverse of ``from_albedo_mfp``."""
    @property
    def name(self) -> str: ...
    @property
    def sigma_s_prime(self) -> list[float]:
        """Reduced scattering coefficient per RGB channel, mm^-1."""
    @property
    def sigma_a(self) -> list[float]:
        """Absorption coefficient per RGB channel, mm^-1."""
    @property
    def eta(self) -> float:
        """Relative index of refraction."""

def presets() -> list[str]:
    """Names of the material presets: apple, chicken1, chicken2, cream, ketchup, marble, potato,
    skimmilk, skin1, skin2, wholemilk, wax."""

def render(
    mesh: Optional[PathLike] = None,
    *,
    vertices: Optional[ArrayLike] = None,
    faces: Optional[ArrayLike] = None,
    scene: Optional[PathLike] = None,
    material: Union[str, Material, None] = None,
    scale: Optional[float] = None,
    lights: Optional[Sequence[str]] = None,
    shadows: bool = True,
    env: Optional[str] = None,
    env_rotation: Optional[float] = None,
    camera: Optional[Mapping[str, float]] = None,
    width: int = 800,
    height: int = 600,
    profile: Optional[str] = None,
    single_scattering: Optional[str] = None,
    transmission: Optional[str] = None,
    method: Optional[str] = None,
    mode: Optional[str] = None,
    bounces: Optional[int] = None,
    refine: Union[str, int, None] = None,
    deform: Optional[str] = None,
    surface: bool = True,
    exposure: Optional[float] = None,
) -> npt.NDArray[np.float32]:
    """Renders a translucent object: the image ``lucent render --out x.exr`` writes, as a
    float32 array of shape (height, width, 4): RGB linear radiance premultiplied by A, the
    pixel's coverage of the object (0..1, 4 MSAA samples); the background is 0 with alpha 0.
    The GPU target is half float: values carry about 3 significant digits.

    Every argument is the ``lucent render`` flag of the same name; None leaves the scene file's
    value, else lucent's default.

    mesh: a mesh file (OBJ, PLY, OFF, glTF/GLB). Default: the scene file's, else the bunny.
    vertices, faces: a mesh as arrays instead, (N, 3) float positions in mesh units and (M, 3)
        integer indices, faces counter-clockwise seen from outside; validated as a file is
        (degenerate and repeated faces dropped).
    scene: a scene file (TOML, examples/scenes/); the other arguments override it.
    material: a preset name or a ``Material``. Default skimmilk.
    scale: the rest mesh's largest bounding-box side, metres (1e-4..=100). Default 0.05.
    lights: ``"point:x,y,z"`` or ``"dir:x,y,z"`` (mesh units; intensity 1); any replaces the
        scene's lights. Default: two lights, unless there is an environment.
    shadows: False turns off every shadow (lights and environment).
    env: environment light: ``"courtyard"``, ``"forest"`` or an .hdr/.exr path.
    env_rotation: the environment's rotation about +Y, degrees.
    camera: ``{"yaw": deg, "pitch": deg (-89..89), "distance": bounding-sphere radii (> 1)}``,
        any subset. Default yaw 0, pitch 15, the object just fitting the image.
    width, height: image size, pixels (1..=16384). Default 800 x 600.
    profile: ``"pbd"`` (default), ``"dipole"`` or ``"mertens"``.
    single_scattering: ``"view"`` (default), ``"profile"`` or ``"off"``.
    transmission: light that crosses the body to a face on its far side: ``"curved"``
        (default: the exact transmittance of a slab of the face's thickness on slab-like parts,
        of a sphere of that diameter, by random walk, on curved ones), ``"slab"`` (the slab's
        alone) or ``"halfspace"`` (the profile at the chord, as before issue 50).
    method: ``"hierarchical"`` (default) or ``"exact"`` (O(N^2), the reference). HTSM is not
        offered here.
    mode: ``"render"``, ``"incremental"`` or ``"on-the-fly"``. Default as ``lucent render``:
        render with bounces (on the fly if the links would not fit in half the free memory),
        on-the-fly without.
    bounces: bounces of subsurface light between facing parts, 0..=4. Default 3 (0 with the
        mertens profile).
    refine: ``"auto"`` (default) or 0..=3 splits of every face into four before the solve.
    deform: ``"twist:DEGREES"``, ``"bump:x,y,z,radius,height"`` or ``"noise:amplitude,frequency"``,
        applied in full before the solve.
    surface: False leaves only the subsurface term (no reflection, no highlight).
    exposure: exposure multiplier (1e-6..=1e6); the returned HDR frame is before exposure.

    Raises LucentError with lucent's one-line message on bad input or without a GPU adapter.
    The GIL is released while it solves and renders."""

class Solution:
    """What one ``Session.solve()`` produced."""

    face_b: npt.NDArray[np.float32]
    """Radiosity B per face, (faces, 3) RGB: the light leaving each face after subsurface
    transport."""
    vertex_radiance: npt.NDArray[np.float32]
    """Diffuse exitant radiance B / (c pi) per vertex, (vertices, 3), area-weighted over the
    faces around the vertex (Mertens 2003 section 3.2), before the exit Fresnel factor."""
    vertex_single: npt.NDArray[np.float32]
    """Single-scattered radiance along the view ray per vertex, (vertices, 3), before the exit
    Fresnel factor; (0, 3) when single scattering is not along the view ray."""
    timings: dict[str, float]
    """Milliseconds: irradiance_ms, body_ms, link_ms, pull_ms, gather_ms, single_scattering_ms, push_ms,
    bounces_ms (0 for a stage that did not run), total_ms (their sum) and wall_ms (the call)."""
    links: Optional[int]
    """Links of the hierarchical solve (None for the exact solver)."""
    fresh: bool
    """False when nothing changed since the last solve (the last result again, timings 0)."""

class Session:
    """A translucent object kept across solves (lucent's frame session, Mertens 2003 section
    5.5): set a pose, lights or a material, and ``solve()`` redoes only what they change."""

    def __init__(
        self,
        mesh: Optional[PathLike] = None,
        *,
        vertices: Optional[ArrayLike] = None,
        faces: Optional[ArrayLike] = None,
        scene: Optional[PathLike] = None,
        material: Union[str, Material, None] = None,
        scale: Optional[float] = None,
        lights: Optional[Sequence[str]] = None,
        shadows: bool = True,
        env: Optional[str] = None,
        env_rotation: Optional[float] = None,
        camera: Optional[Mapping[str, float]] = None,
        width: int = 800,
        height: int = 600,
        profile: Optional[str] = None,
        single_scattering: Optional[str] = None,
        transmission: Optional[str] = None,
        method: Optional[str] = None,
        mode: Optional[str] = None,
        bounces: Optional[int] = None,
        refine: Union[str, int, None] = None,
        deform: Optional[str] = None,
        surface: bool = True,
        exposure: Optional[float] = None,
    ) -> None:
        """The arguments of ``render``. The camera framed for ``width`` x ``height`` gives the
        eye of view-ray single scattering and the image of ``render()``. ``mode`` defaults to
        ``"incremental"`` (links made on the rest pose and updated to each pose, as an
        animation of ``lucent render --frames``); ``deform`` poses the mesh at the start."""
    def solve(self) -> Solution:
        """Solves what changed since the last solve (everything the first time), with the GIL
        released."""
    def set_pose(self, positions: ArrayLike) -> None:
        """Moves the mesh's vertices to ``positions``, (vertices, 3) mesh units, the shape of
        ``vertices`` (the topology is fixed)."""
    def deform(self, spec: str, t: float = 1.0) -> None:
        """Poses the mesh by a deformation of its rest pose (as ``render``'s ``deform``) at
        animation parameter ``t`` (0 rest, 1 as given)."""
    def set_lights(self, lights: Sequence[str], shadows: bool = True) -> None:
        """Replaces the lights (``"point:x,y,z"`` or ``"dir:x,y,z"``, mesh units)."""
    def set_material(self, material: Union[str, Material], scale: Optional[float] = None) -> None:
        """Replaces the material and, if given, the model scale (metres)."""
    def render(self) -> npt.NDArray[np.float32]:
        """Draws the last solve (solving first if anything changed) as ``lucent.render`` does:
        (height, width, 4) float32, RGB premultiplied by coverage."""
    @property
    def vertices(self) -> npt.NDArray[np.float32]:
        """The vertices in the current pose, (vertices, 3) mesh units. With ``refine`` (auto by
        default) these are the split mesh's: pass ``refine=0`` to keep the input's."""
    @property
    def rest_vertices(self) -> npt.NDArray[np.float32]:
        """The rest pose's vertices, (vertices, 3) mesh units."""
    @property
    def faces(self) -> npt.NDArray[np.uint32]:
        """The faces, (faces, 3) indices into ``vertices``."""
    @property
    def material(self) -> Material: ...
    @property
    def scale(self) -> float:
        """The rest mesh's largest bounding-box side, metres."""
    @property
    def refine_levels(self) -> int:
        """Times every input face was split into four before the solve."""
    @property
    def mode(self) -> str:
        """The solve mode: render, incremental, refit or on-the-fly."""

def read_exr(path: PathLike) -> npt.NDArray[np.float32]:
    """The first RGBA layer of an OpenEXR file, (height, width, 4) float32."""

def write_exr(path: PathLike, image: ArrayLike) -> None:
    """Writes a (height, width, 4) array as a 32-bit float RGBA OpenEXR file, atomically."""
