"""Type stubs of the native extension; the ``splash_sph`` package re-exports all of it."""

import os
from typing import Any, Callable, Dict, List, Literal, Mapping, NamedTuple, Optional, Sequence, Tuple, TypedDict, Union, final, type_check_only

import numpy as np
import numpy.typing as npt

_Path = Union[str, "os.PathLike[str]"]
_Array = npt.ArrayLike

__all__ = [
    "reconstruct",
    "recon_sequence",
    "frame_number",
    "iso",
    "postprocess",
    "preview",
    "read_particles",
    "read_mesh",
    "MeshArrays",
    "level_set",
    "write_vdb",
    "LevelSetArrays",
    "estimate_spacing",
    "mesh_edges",
    "default_config",
    "config_toml",
    "Mesh",
    "Particles",
]

@final
class Particles:
    """One particle frame: positions and per-particle attributes.

    ``len(p)`` is the number of particles, ``p["velocity"]`` (or ``p.attributes["velocity"]``)
    an attribute by the name the file gives it, ``p.attribute("v")`` one by any usual spelling
    (the alias table of ``--attributes``), ``p.attribute_names`` their names, and
    ``"velocity" in p`` tells whether the file has one of that name.
    """

    @property
    def positions(self) -> npt.NDArray[np.float32]:
        """Particle positions, shape (N, 3), float32."""
    @property
    def attributes(self) -> Dict[str, npt.NDArray[np.float32]]:
        """Per-particle attributes by name (``velocity``, ``density``, ...): arrays of shape
        (N, 3) for vectors and (N,) for scalars, float32."""
    @property
    def attribute_names(self) -> List[str]:
        """The names of the attributes, as the file gives them, sorted."""
    def attribute(self, name: str) -> npt.NDArray[np.float32]:
        """The attribute that ``name`` names in any of its usual spellings, as ``--attributes``
        finds it: ``"v"``, ``"vel"`` and ``"velocities"`` find ``velocity``, ``"rho"`` finds
        ``density``, and three scalars ``vx vy vz`` (or ``velocity_x …``) come as one (N, 3)
        array. Raises KeyError, listing the frame's attributes, when it has none of these."""
    def __len__(self) -> int:
        """The number of particles."""
    def __getitem__(self, name: str, /) -> npt.NDArray[np.float32]:
        """The attribute ``name``; KeyError when the frame has none of that name."""
    def __contains__(self, name: str, /) -> bool:
        """Whether the frame has the attribute ``name``."""

@final
class Mesh:
    """A closed triangle mesh whose triangles wind counter-clockwise seen from outside the
    fluid.

    The arrays are the mesh: edit them in place (to move or scale it, say) and ``write``
    writes the edited mesh.
    """

    @property
    def vertices(self) -> npt.NDArray[np.float32]:
        """Vertex positions, shape (V, 3), float32."""
    @property
    def faces(self) -> npt.NDArray[np.uint32]:
        """Triangles as vertex indices, shape (F, 3), uint32."""
    @property
    def normals(self) -> npt.NDArray[np.float32]:
        """Unit vertex normals pointing out of the fluid, shape (V, 3), float32; shape (0, 3)
        when reconstructed with ``normals="none"``."""
    @property
    def attributes(self) -> Dict[str, npt.NDArray[np.float32]]:
        """Per-vertex values interpolated from the particles' ``attributes``: name -> array of
        shape (V, 3) or (V,), float32."""
    @property
    def report(self) -> Dict[str, Any]:
        """Counts, lengths and stage times of the reconstruction (see ``reconstruct``)."""
    def write(
        self,
        path: _Path,
        format: Optional[str] = None,
        up_axis: Optional[str] = None,
        voxel: Optional[float] = None,
    ) -> None:
        """Writes the mesh to ``path`` atomically (a reader sees the old file or the new one),
        creating missing directories.

        ``format``: ``"obj"``, ``"ply"`` (binary), ``"ply-ascii"``, ``"pov"``, ``"vtk"``,
        ``"vtu"``, ``"vtp"``, ``"usd"`` (a ``.usda`` layer) or ``"vdb"``; by default the
        configuration's ``output.format``, else the one the extension implies (``.obj``,
        ``.ply``, ``.inc``, ``.vtk``, ``.vtu``, ``.vtp``, ``.usda``, ``.vdb``), else OBJ.
        ``up_axis``: ``"z"`` or ``"y"`` turns the written coordinates so that that axis is up
        (the arrays are left as they are); by default the configuration's ``output.up_axis``.
        PLY, VTK and USD files get every attribute of the mesh (``velocity`` as the PLY
        properties ``vx vy vz``, USD's ``velocities``); OBJ and POV-Ray files leave them out. A
        VDB file holds the mesh's level set alone (``write_vdb`` also writes grids), on voxels
        of edge ``voxel``: by default the cell of the reconstruction that made the mesh. The
        GIL is released while writing.

        Raises OSError when the file cannot be written, ValueError for an unknown format or
        one that contradicts the extension, and for a VDB file without ``voxel`` of a mesh whose
        report has no cell.
        """

def read_particles(path: _Path, format: Optional[str] = None) -> Particles:
    """Reads one particle frame: PLY (ascii or binary), CSV/TXT tables, raw little-endian
    float32 x y z triples (``.bin``/``.raw``), legacy VTK (``.vtk``), VTK XML (``.vtu``,
    ``.vtp``), classic BGEO (``.bgeo``, ``.bgeo.gz``) or ``.xyz`` (raw triples, or text).

    ``format`` (``"ply"``, ``"csv"``, ``"raw"``, ``"vtk"``, ``"vtu"``, ``"bgeo"`` or ``"xyz"``)
    overrides the guess from the extension.
    The GIL is released while reading.

    Raises FileNotFoundError for a missing file, OSError when it cannot be read, and
    ValueError when its content is not a valid frame (the message names the file and says
    what is wrong where).
    """

class MeshArrays(NamedTuple):
    """A triangle mesh read from a file (``read_mesh``)."""

    #: Vertex positions, shape (V, 3), float32.
    vertices: npt.NDArray[np.float32]
    #: Triangles as vertex indices, shape (F, 3), uint32.
    faces: npt.NDArray[np.uint32]
    #: Unit vertex normals, shape (V, 3), float32; shape (0, 3) when the file has none.
    normals: npt.NDArray[np.float32]
    #: Per-vertex attributes by name (``velocity``: shape (V, 3); scalars: shape (V,)),
    #: float32.
    attributes: Dict[str, npt.NDArray[np.float32]]

def read_mesh(path: _Path) -> MeshArrays:
    """Reads a mesh written by ``splash recon`` or ``Mesh.write``, by its extension:
    ``.obj``, ``.ply`` (binary or ascii), ``.vtk`` (legacy), ``.vtu`` or ``.vtp``.

    PLY properties ``vx vy vz`` become the attribute ``velocity``, ``{name}_x {name}_y
    {name}_z`` the vector ``{name}``, other vertex properties scalars; VTK point data arrays
    keep their names (``Normals`` are the normals). Faces must be triangles. The GIL is
    released while reading.

    Raises FileNotFoundError for a missing file, OSError when it cannot be read, and
    ValueError naming the file when its content is not such a mesh.
    """

class LevelSetArrays(NamedTuple):
    """A narrow-band level set (``level_set``)."""

    #: Indices of the active voxels, shape (N, 3), int32; voxel ``ijk`` is centred at
    #: ``ijk * voxel``.
    ijk: npt.NDArray[np.int32]
    #: Signed distance to the mesh at each active voxel, negative inside, shape (N,), float32.
    values: npt.NDArray[np.float32]
    #: The voxels' edge, in world units.
    voxel: float
    #: The band's half width, in world units (3 voxels): inactive voxels hold ± this.
    half_width: float

def level_set(
    mesh: Union[Mesh, MeshArrays, Any, "tuple[_Array, _Array]"], voxel: float
) -> LevelSetArrays:
    """The narrow-band level set of a closed triangle mesh: its signed distance (negative
    inside) at the centres of the voxels within 3 voxels of it, voxel ``ijk`` centred at
    ``ijk * voxel``.

    ``mesh``: a ``Mesh``, a ``MeshArrays``, any object with ``vertices`` and ``faces`` arrays,
    or a ``(vertices, faces)`` pair; closed and wound counter-clockwise seen from outside, as
    every mesh splash makes. ``voxel``: the voxels' edge in world units (``splash recon
    --format vdb`` uses the cell). The GIL is released while computing. Raises ValueError for
    a bad mesh or voxel.
    """

def write_vdb(
    path: _Path,
    mesh: Union[Mesh, MeshArrays, Any, "tuple[_Array, _Array]"],
    voxel: float,
    grids: Optional[Mapping[str, _Array]] = None,
) -> None:
    """Writes the level set of ``mesh`` (as ``level_set`` makes it) to the OpenVDB file
    ``path`` atomically: the float grid ``surface`` (class level set, background the band's
    half width), and one grid per entry of ``grids`` over the same voxels, each an (N,) or
    (N, 3) float32 array with a value per voxel in the order of ``level_set(mesh, voxel).ijk``
    (``velocity`` is written as the vector grid ``v``, as Blender's and Houdini's motion blur
    read it). The GIL is released while computing and writing.

    Raises OSError when the file cannot be written, ValueError for a bad mesh, voxel or grid.
    """

def reconstruct(
    positions: _Array,
    spacing: Optional[float] = None,
    *,
    cell: Union[str, float, None] = None,
    field: Optional[str] = None,
    engine: Optional[str] = None,
    normals: Optional[str] = None,
    correct: Optional[int] = None,
    block: Optional[int] = None,
    threads: Optional[int] = None,
    max_memory: Union[str, int, None] = None,
    raw: Optional[bool] = None,
    decimate: Union[str, float, None] = None,
    min_component: Optional[float] = None,
    mesh_aabb: Optional[Sequence[float]] = None,
    volume_scope: Optional[Literal["frame", "component"]] = None,
    config: Union[_Path, Mapping[str, Any], None] = None,
    attributes: Optional[Mapping[str, _Array]] = None,
    ids: Optional[_Array] = None,
    neighbours: Optional[Tuple[Tuple[_Array, _Array], Tuple[_Array, _Array]]] = None,
) -> Mesh:
    """The closed surface mesh of SPH particles.

    ``positions``: an (N, 3) floating-point array, C- or F-ordered or a strided view. A
    C-contiguous float32 array is read in place (leave it unchanged until the call returns),
    others are copied once as float32; anything that ``numpy.asarray`` makes such an array
    of is accepted, integer arrays are refused. Coordinates must be finite. An empty (0, 3)
    array gives an empty mesh.

    ``spacing``: Particle spacing r, the simulator's equilibrium distance between particles,
    in world units. Required unless the config gives it: it is never guessed (see
    ``estimate_spacing``).

    Keyword arguments override the config (None leaves its value); each is the option of the
    command line's flag of the same name (``--max-memory`` for ``max_memory``), where a number
    is a length in world units:

    - ``cell``: Marching Cubes cell size: 2r, r, r/2, r/N, Kr or a length; at most 4r.
      Default ``"r/2"``.
    - ``field``: Scalar field: ssp07, zb05, density, blobby, metaball or anisotropic, with its
      default parameters unless the configuration gives the same kind. Default ``"ssp07"``.
    - ``engine``: Reconstruction engine: narrow-band, full-gather, scatter or slices. Default
      ``"narrow-band"``. full-gather, scatter and slices give the same surface, and the narrow
      band too but for the blobs of a cell or two beyond its band at small cells, which it
      misses (1 of 55 components on cbd-small frame 40 at cell r/2;
      docs/reference/recon.md, Engines).
    - ``normals``: Vertex normals: field (the field's gradient), grid (differences of the
      sampled grid: faster) or none. Default ``"field"``.
    - ``correct``: Newton steps moving each vertex along its cube edge onto the field's exact
      isosurface (Marching Correctors); 0 keeps Marching Cubes' linear interpolation. Default
      0; 3 is plenty.
    - ``block``: Cubes per side of a block of the slices engine. Default 64.
    - ``threads``: Worker threads, all cores when not given; the mesh does not depend on it.
      Each calling thread keeps its workers for its next calls.
    - ``max_memory``: Heap a frame may plan to use, e.g. 8G or 512M: every engine refuses a
      frame that needs more. In bytes or as ``"8G"``.
    - ``raw``: Keep the field's exact isosurface: no smoothing and no volume restoration.
      ``raw=True`` skips the default post-processing (smoothing, each part given its
      particles' volume N·r³; ``postprocess`` runs it on any mesh).
    - ``volume_scope``: What the volume restoration brings to N·r³: frame (the whole mesh, one
      offset) or component (each closed part to its own particles). Default ``"frame"``.
    - ``decimate``: Decimate with quadric edge collapses, keeping every vertex and triangle
      centre within this distance of the full surface: ``"0.1r"`` or a number.
    - ``min_component``: Drop the parts of the mesh enclosing less than this many particle
      volumes r³.
    - ``mesh_aabb``: Keep only the mesh inside this box (min x, min y, min z, max x, max y,
      max z); the cuts are capped, so it stays closed.

    ``config``: a TOML file's path (as ``splash recon --config`` reads) or a dict shaped like
    it (see ``default_config``). Its ``output.format`` and ``output.up_axis`` become the
    defaults of ``Mesh.write``.

    ``attributes``: per-particle values to carry onto the vertices, name -> (N, 3) or (N,)
    array, interpolated as ``splash recon --attributes velocity`` does (the mean of the
    particles within the field's support, weighted by the SSP07 kernel); they come back in
    ``Mesh.attributes``.

    ``ids`` and ``neighbours``: to make the surface follow the fluid from frame to frame, as
    ``recon_sequence(temporal=True)`` does (issue 38): ``ids`` an (N,) integer array of the
    particles' unique identities, ``neighbours`` the frames before and after as
    ``((positions, ids), (positions, ids))``. The three frames are reconstructed alike (about
    three times the work) and this frame's surface moves towards its neighbours' carried to its
    time by the particles matched by id; particles without a match do not carry it. With
    ``raw=True`` nothing follows. ``Mesh.report["followed"]`` gives the vertices ``moved`` and
    the ``rms`` and ``max`` move in world units.

    ``Mesh.report`` holds the counts (``particles``, ``surface_particles``, ``vertices``,
    ``triangles``, ...), ``spacing`` and ``cell`` in world units, ``engine``, ``field``,
    ``threads``, and ``times``: seconds per stage (``handler_array``, ``surface_particles``,
    ``band``, ``scalar_field``, ``triangulation``, ``post`` (the post-processing; 0 with
    ``raw=True`` and no ``decimate``, ``min_component`` or ``mesh_aabb``), their sum
    ``reconstruction``, ``attributes``, and ``total`` for all the native work).

    The GIL is released while the library works: Python threads can reconstruct frames in
    parallel. Raises ValueError for a bad array, bad settings (naming the key or value),
    non-finite coordinates (naming the particle) or a grid over the memory limit; OSError
    when the config file cannot be read.
    """

def postprocess(
    mesh: Union[Mesh, MeshArrays, Any, "tuple[_Array, _Array]"],
    *,
    particles: Union[Particles, _Array, None] = None,
    spacing: Optional[float] = None,
    cell: Union[str, float, None] = None,
    config: Union[_Path, Mapping[str, Any], None] = None,
    raw: Optional[bool] = None,
    smoothing_iterations: Optional[int] = None,
    lambda_: Optional[float] = None,
    mu: Optional[float] = None,
    relax_first: Optional[int] = None,
    volume_rounds: Optional[int] = None,
    volume_scope: Optional[Literal["frame", "component"]] = None,
    max_offset: Optional[float] = None,
    refine_angle: Optional[float] = None,
    relax_iterations: Optional[int] = None,
    volume_steps: Optional[int] = None,
    mesh_aabb: Optional[Sequence[float]] = None,
    min_component: Optional[float] = None,
    decimate: Union[str, float, None] = None,
    threads: Optional[int] = None,
) -> Mesh:
    """A post-processed copy of a closed triangle mesh: the default post-processing of
    ``reconstruct`` (Taubin smoothing, each closed part's volume restored, tangential
    relaxation), then the box, the small parts and the decimation where asked.

    ``mesh``: a ``Mesh`` (from ``reconstruct`` or ``iso``), a ``MeshArrays`` (``read_mesh``),
    any object with ``vertices`` and ``faces`` arrays, or a ``(vertices, faces)`` pair:
    vertices an (V, 3) floating-point array, faces an (F, 3) integer array of vertex indices.
    The mesh must be closed, manifold and consistently wound, as every mesh splash writes (the
    volume, the inside and the box caps of an open surface are not defined); ValueError says
    how many boundary, non-manifold and wrongly wound edges it has otherwise, or which
    triangle references a missing vertex, or which vertex is not finite.

    ``particles``: the particles the mesh encloses, an (N, 3) array or a ``Particles``: each
    closed part's volume is brought to N_c·r³ for the N_c particles inside it, as
    ``reconstruct`` does (``postprocess(reconstruct(x, r, raw=True), particles=x)`` gives
    ``reconstruct(x, r)``'s vertices and faces, bit for bit). Without particles each closed
    part keeps the volume it encloses on input: volume-true smoothing of any mesh.

    ``spacing``: the particle spacing r, the unit of ``max_offset``, ``decimate`` and
    ``min_component``; by default the config's, else the ``Mesh``'s ``report["spacing"]``.
    ``cell``: the reconstruction's cell (it places the particles' rays); by default the
    ``Mesh``'s ``report["cell"]``, else the config's (``"r/2"``).

    The post-processing settings (``[post]`` of the config; None keeps the config's, the
    defaults by default): ``raw=True`` skips smoothing and volume restoration;
    ``smoothing_iterations`` (0), ``lambda_`` (0.6) and ``mu`` (-0.64): Taubin's λ|μ pairs,
    after ``relax_first`` (4) tangential relaxation steps;
    ``volume_rounds`` (4), ``volume_scope`` (``"frame"``: one offset for the whole mesh;
    ``"component"``: each closed component to its own particles' volume), ``max_offset``
    (0.5 r per step), ``refine_angle`` (0: off; in
    degrees, bisects the edges where the surface bends more), ``relax_iterations`` (12),
    ``volume_steps`` (1); ``mesh_aabb``, ``min_component`` and ``decimate`` as in
    ``reconstruct``. ``config``: a TOML file's path or a dict, as ``reconstruct`` takes it.
    ``threads``: worker threads, all cores by default; the result does not depend on it.

    Returns a new ``Mesh``: normals when the input has them (area-weighted where vertices
    moved), the input ``Mesh``'s attributes when neither ``mesh_aabb``, ``min_component`` nor
    ``decimate`` is set (smoothing moves the vertices but keeps them; those three change
    them), and the ``Mesh``'s output format and up axis. Its ``report``: ``vertices``,
    ``triangles``, ``spacing``, ``cell`` (None without particles) and ``times`` (``post``,
    ``total``, seconds). The input is not changed. The GIL is released while working.
    """

def iso(
    particles: Union[Particles, _Array],
    attribute: Union[str, _Array],
    level: float,
    *,
    spacing: Optional[float] = None,
    magnitude: bool = False,
    vorticity: bool = False,
    lambda2: bool = False,
    cell: Union[str, float, None] = None,
    correct: Optional[int] = None,
    shepard: Optional[bool] = None,
    kernel_scale: Optional[float] = None,
    attributes: Optional[Sequence[str]] = None,
    threads: Optional[int] = None,
    config: Union[_Path, Mapping[str, Any], None] = None,
) -> Mesh:
    """The isosurface A = ``level`` of a particle quantity, exact with respect to the SPH
    interpolant A(x) = sum_j (m_j/rho_j) A_j W(x - x_j, 2h_j) (Marching Correctors), as
    ``splash iso`` computes it: the same settings give the same mesh.

    ``particles``: a ``Particles`` (from ``read_particles``) with ``attribute`` the name of
    one of its attributes (any spelling of the alias table: ``"v"`` finds ``velocity``,
    ``vx vy vz`` make one vector); or an (N, 3) positions array with ``attribute`` an (N,)
    or (N, 3) array of per-particle values. Volumes m/rho come from ``mass`` and ``density``
    attributes when the particles have both, else from the particles as the density field
    computes them.

    ``magnitude``: the isosurface of |A| of a vector attribute; ``vorticity``: of |curl v| of
    a velocity (SPH curl); ``lambda2``: of lambda2, the middle eigenvalue of S^2 + Omega^2 of a
    velocity's SPH gradient (vortex cores are where lambda2 < 0: take a negative level).
    ``spacing``: the particle spacing r (required unless the config
    gives it). ``cell``: the virtual grid's cell (``"r/2"`` by default, ``"r"``, a number).
    ``correct``: Newton steps per vertex along its cube edge (3 by default; 0 gives plain
    Marching Cubes vertices). ``shepard``: normalise by the sum of weights (plain SPH by
    default). ``kernel_scale``: multiplies every particle's kernel support; a UserWarning
    says when it leaves fewer than 10 particles in a support on average (the surface then
    breaks up). ``attributes``: names of the particles' attributes to interpolate onto the vertices
    (with a ``Particles`` only), with the quantity's sums (plain SPH unless ``shepard``,
    which makes them kernel-weighted means); they come back in ``Mesh.attributes``. ``threads``: worker
    threads (all cores by default; the mesh does not depend on it). ``config``: a TOML
    file's path or a dict as for ``reconstruct``; its ``[iso]`` table holds the thresholds,
    and the keyword arguments override it.

    Normals are the SPH gradient, pointing towards larger A; triangles are trimmed where the
    sum of weights falls, so surfaces are open at the free surface. ``Mesh.report`` holds
    the JSON log's ``iso`` figures (``level``, ``cell``, ``seed_cells``, ``visited_cells``,
    ``crossed_cells``, ``cache_hit_ratio``, ``vertices``, ``triangles``, ``correction``, ...)
    with ``particles``, ``spacing`` and ``times`` in seconds.

    Raises KeyError for an attribute the particles do not have (the message lists theirs),
    ValueError for a vector without ``magnitude``, ``vorticity`` or ``lambda2``, a bad array or bad
    settings, TypeError for an argument of the wrong kind.
    """

def preview(
    positions: _Array,
    spacing: Optional[float] = None,
    *,
    size: "tuple[int, int]" = ...,
    camera: Optional["tuple[float, float, float]"] = None,
    look_at: Optional["tuple[float, float, float]"] = None,
    up: Optional["tuple[float, float, float]"] = None,
    up_axis: str = "y",
    view: Optional["tuple[float, float, float]"] = None,
    fov: float = 40.0,
    background: str = "#eceef2",
    colour: str = "#3a7bd5",
    shadows: bool = True,
    bvh: str = "fitted",
    threads: Optional[int] = None,
    config: Union[None, _Path, Mapping[str, Any]] = None,
    samples: Optional[int] = None,
    ao: Optional[int] = None,
    values: Optional[_Array] = None,
    legend: Optional[bool] = None,
) -> "npt.NDArray[np.uint8]":
    """A ray-traced picture of the metaball surface of ``positions`` (the surface
    ``reconstruct(..., field="metaball")`` meshes) as an (H, W, 3) uint8 RGB array, as
    ``splash preview`` renders it: Fitted BVH, Phong shading, a hard shadow. ``size``:
    (width, height) in pixels, default (1280, 720). Without
    ``camera`` the particles' 0.5-99.5 % percentile box is framed automatically. ``samples``
    (stratified rays per pixel) and ``ao`` (ambient-occlusion rays per pixel, 0 off) default to
    the config's ``[preview]`` table; ``values`` ((N,), or (N, 3) by magnitude) colours the
    surface through viridis with a legend unless ``legend=False``. The image
    does not depend on ``threads``. Raises ValueError for bad settings, cameras or sizes.
    """

def mesh_edges(
    faces: npt.NDArray[np.uint32], vertex_count: int
) -> Tuple[npt.NDArray[np.uint32], npt.NDArray[np.uint32]]:
    """The edges of the triangles ``faces``, as Blender's meshes hold them beside the faces:
    ``(edges, corner_edges)``, ``edges`` each distinct edge once as an (E, 2) uint32 array of
    vertex indices, the lower first, and ``corner_edges`` an (3F,) uint32 array giving for
    corner ``3 f + k`` the edge from vertex ``faces[f, k]`` to ``faces[f, (k + 1) % 3]``.

    ``faces``: an (F, 3) uint32 array (``Mesh.faces``, ``MeshArrays.faces``) over
    ``vertex_count`` vertices. A closed mesh has 3F/2 edges. The GIL is released while
    counting. Raises ValueError when a face names a vertex beyond ``vertex_count``.
    """

def estimate_spacing(positions: _Array) -> float:
    """The particle spacing r estimated from the particles' number density.

    ``positions``: an (N, 3) floating-point array. Deterministic: the same particles give
    the same estimate. Raises ValueError when fewer than 2 particles are given or all of
    them coincide. The GIL is released while estimating.
    """

@type_check_only
class FrameReport(TypedDict, total=False):
    """One frame of ``recon_sequence``, as ``progress`` gets it and the run report lists it
    (the fields of ``splash recon --log-format json``'s ``frame`` events)."""

    frame: Optional[int]
    input: str
    output: str
    status: str  # "ok" or "error"
    particles: int  # the counts and seconds: status "ok" only
    triangles: int
    vertices: int
    seconds: float
    # read, reconstruction (of which post: 0 with raw=True alone), write; they add up to seconds
    times: Dict[str, float]
    error: str  # status "error" only

@type_check_only
class RunReport(TypedDict):
    """What ``recon_sequence`` returns: this job's share of the sequence and its frames."""

    selected: int
    shard: Optional[str]
    assigned: int
    skipped: List[str]
    to_do: int
    written: int
    failed: List[FrameReport]
    not_attempted: int
    ok: bool
    spacing: Optional[float]
    warnings: List[str]
    frames: List[FrameReport]

def recon_sequence(
    inputs: Union[_Path, Sequence[_Path]],
    output: _Path,
    *,
    progress: Optional[Callable[[int, int, FrameReport], Any]] = None,
    frames: Optional[str] = None,
    shard: Optional[str] = None,
    skip_existing: bool = False,
    fail_fast: bool = False,
    input_format: Optional[str] = None,
    spacing: Optional[float] = None,
    cell: Union[str, float, None] = None,
    field: Optional[str] = None,
    engine: Optional[str] = None,
    normals: Optional[str] = None,
    correct: Optional[int] = None,
    block: Optional[int] = None,
    threads: Optional[int] = None,
    max_memory: Union[str, int, None] = None,
    raw: Optional[bool] = None,
    decimate: Union[str, float, None] = None,
    min_component: Optional[float] = None,
    mesh_aabb: Optional[Sequence[float]] = None,
    volume_scope: Optional[Literal["frame", "component"]] = None,
    config: Union[_Path, Mapping[str, Any], None] = None,
    particle_aabb: Optional[Sequence[float]] = None,
    format: Optional[str] = None,
    up_axis: Optional[str] = None,
    attributes: Union[str, Sequence[str], None] = None,
    temporal: Optional[bool] = None,
) -> RunReport:
    """Reconstructs a sequence of particle files into mesh files, as ``splash recon`` does:
    the same frames, output names, shards, restarts and bytes.

    ``inputs``: a particle file, a directory (its frame sequence), a glob pattern
    (``"sim/frame_*.ply"``) or a list of these; frames run in frame-number order (the last
    run of digits in the name, see ``frame_number``). ``output``: a directory (ending in
    ``/``, or existing; numbers padded to 4 digits) or a pattern with ``{stem}``, ``{frame}``
    or ``{frame:04}``; the format comes from ``format``, else the extension, else OBJ.

    ``progress(done, total, frame_report)`` is called after each frame; an exception in it
    stops the run and is raised again. ``frames``: ``"1-10,20,30-40x5"``. ``shard``:
    ``"K/N"`` or ``"auto/N"`` (K from ``SLURM_ARRAY_TASK_ID``). ``skip_existing``: leave
    frames whose output exists alone. ``fail_fast``: stop at the first failing frame.
    ``input_format``: as the command line's ``--input-format``.

    The options of files and sequences, besides ``reconstruct``'s:

    - ``particle_aabb``: Drop the particles outside this box (min x, min y, min z, max x, max
      y, max z) before reconstructing.
    - ``format``: Mesh format: obj, ply, ply-ascii, pov, vtk, vtu, vtp, usd or vdb; from the
      output's extension when not given, else obj. ``format="usd"`` also writes, after the
      frames, the stage that plays their layers as one animated mesh, and takes the particles'
      velocities whenever they have them.
    - ``up_axis``: Rotate the mesh on output: z turns Y-up data Z-up, y turns Z-up data Y-up.
    - ``attributes``: Particle attributes interpolated onto the mesh's vertices, by name
      (velocity, density, …): a list of names or one comma-separated string; written to PLY,
      VTK, VTU, VTP and USD.
    - ``temporal``: In a sequence, average each frame's field and surface with its neighbouring
      frames' carried by the fluid's motion (experimental). Less flicker for about 1.9× the
      time; needs particle ids, or velocities with ``post.frame_time``; frames without both
      neighbours are post-processed alone, with a warning.

    The other keywords are ``reconstruct``'s; without ``spacing`` it is estimated once, on the
    first frame of the whole selection, so that every shard uses one grid.

    A failing frame does not raise: it is in the report's ``failed``. Raises ValueError for
    bad settings, inputs that select no frame or colliding outputs, OSError for an output
    directory that cannot be written, before any frame is reconstructed.
    """

def frame_number(path: _Path) -> Optional[int]:
    """The frame number of a file: the last run of digits of its name without the extension
    (``frame_0042.ply`` -> 42, ``fluid.0007.bgeo.gz`` -> 7), None without digits."""

def default_config() -> Dict[str, Any]:
    """The default configuration as a dict shaped like the TOML file (keys without a default,
    such as ``spacing``, ``threads`` and ``max_memory``, are absent). Edit it and pass it as
    ``reconstruct(..., config=d)``."""

def config_toml(
    config: Union[_Path, Mapping[str, Any], None] = None,
    *,
    spacing: Optional[float] = None,
    cell: Union[str, float, None] = None,
    field: Optional[str] = None,
    engine: Optional[str] = None,
    normals: Optional[str] = None,
    correct: Optional[int] = None,
    block: Optional[int] = None,
    threads: Optional[int] = None,
    max_memory: Union[str, int, None] = None,
    raw: Optional[bool] = None,
    decimate: Union[str, float, None] = None,
    min_component: Optional[float] = None,
    mesh_aabb: Optional[Sequence[float]] = None,
    volume_scope: Optional[Literal["frame", "component"]] = None,
    particle_aabb: Optional[Sequence[float]] = None,
    format: Optional[str] = None,
    up_axis: Optional[str] = None,
    attributes: Union[str, Sequence[str], None] = None,
    temporal: Optional[bool] = None,
) -> str:
    """The configuration that ``recon_sequence`` (and ``reconstruct``, which takes the same
    keyword arguments but the options of files and sequences) would use with the same
    ``config`` and keyword arguments, as TOML text (what ``splash config show`` prints with the
    flags of the same names; save it to reuse it with ``splash recon --config``). Raises
    ValueError as ``reconstruct`` does for bad settings."""
