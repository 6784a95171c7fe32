"""Type stubs of the brdftab package (the Rust extension `brdftab._native` and its wrappers)."""

from os import PathLike
from typing import Any, Iterator, Literal, Sequence, Union, final, overload

import numpy as np
import numpy.typing as npt
from typing_extensions import Buffer

__version__: str

__all__ = [
    "Brdf",
    "Database",
    "Error",
    "Table",
    "bake",
    "bake_cached",
    "check",
    "convert",
    "fit",
    "info",
    "open",
    "rgb_basis",
]

# Aliases of the stubs only (private: not names of the package).
_ArrayLike = npt.ArrayLike
_Wavelengths = Union[None, str, Sequence[float]]
# A SOURCE: a str (a spec, a path, DB#NAME) or a path as os.fspath gives one, bytes included (a
# file name need not be UTF-8). Every OUTPUT and other path is one too (_Path).
_Source = Union[str, bytes, PathLike[str], PathLike[bytes]]
_Path = _Source

class Error(Exception):
    """An error of the brdftab library; the message is the library's."""

@final
class Brdf:
    """A BRDF opened from a SOURCE (spec, table, DB#NAME, MERL .binary, RGL .bsdf).

    Array arguments are anything numpy reads as real numbers (any float, int or bool dtype,
    either byte order, any strides; complex, object and string dtypes are a TypeError). A
    numpy.ma masked array with masked entries is a ValueError (fill or drop them first); one
    without is read as its data. A result beyond memory is numpy's MemoryError. Pickles by its
    source (its file's path made absolute, so a copy opens the same file from any working
    directory) and options; `copy.copy` and `copy.deepcopy` give the object itself (immutable).

    eval, pdf and sample run with the GIL released and to their end, as numpy's ufuncs do:
    Ctrl-C raises KeyboardInterrupt when the call returns (10^7 pairs: seconds); albedo stops
    between angles."""

    def device_layout(self) -> dict[str, Any]:
        """A table SOURCE's device layout for its interpolation (`Table.device_layout`), the
        decoded table moved into it; brdftab.Error for any other source."""

    @property
    def channels(self) -> list[str]:
        """Channel names as the CLI prints them: ["R", "G", "B"] or ["450nm", ...]."""
    @property
    def wavelengths(self) -> list[float] | None:
        """Wavelengths in nm of a spectral BRDF, or None for RGB."""
    @property
    def flags(self) -> dict[str, Any]:
        """{"delta", "reciprocal", "isotropic", "bilateral", "transmission": bool,
        "lobes": {"diffuse", "glossy", "delta": bool}}."""
    @property
    def source(self) -> str:
        """The SOURCE string this BRDF was opened from (a file name that is not UTF-8 as
        os.fsdecode gives it)."""
    @property
    def interp(self) -> str:
        """The interpolation lookups use: a table's ("linear" or "nearest"; with interp="auto",
        the one its grid chose), a MERL file's ("nearest", its cells, unless "linear" was
        asked), an RGL file's ("linear", its format's own, whatever was asked); for an analytic
        model, which interpolates nothing, the interpolation asked for."""
    def describe(self) -> str:
        """A one-line description (model and parameters, or table and source)."""
    def eval(self, wi: _ArrayLike, wo: _ArrayLike) -> npt.NDArray[np.float32]:
        """f_r(wi, wo) in 1/sr: (..., c) float32 for wi and wo of shapes (..., 3) whose leading
        shapes broadcast by numpy's rules ((n, 3) against (n, 3) or (3,), an image (h, w, 3),
        wi[:, None] against wo[None, :]); (c,) for one pair of shape (3,).

        NaN, infinite or zero directions give 0 (not an error), as in every host."""
    def eval_spectral(self, wi: _ArrayLike, wo: _ArrayLike, nm: _ArrayLike) -> npt.NDArray[np.float32]:
        """f_r at wavelengths nm ((k,), or (..., k) one set per pair; each finite and > 0, else
        ValueError): (..., k) float32 in the pairs' shape as in `eval`, (k,) for one pair. Spectral channels are interpolated,
        models use their spectral data, RGB channels become a spectrum of their colour
        (`rgb_basis`)."""
    def pdf(self, wi: _ArrayLike, wo: _ArrayLike) -> npt.NDArray[np.float64]:
        """Density of `sample` drawing wi given wo: float64 in the pairs' shape as in `eval`
        ((n,), or 0-d for one pair of shape (3,))."""
    @overload
    def sample(
        self, wo: _ArrayLike, u: _ArrayLike, *, nm: _ArrayLike | None = None,
        delta: Literal[False] = False
    ) -> tuple[npt.NDArray[np.float64], npt.NDArray[np.float64], npt.NDArray[np.float32]]:
        """(wi (..., 3), pdf (...), weight = f cos θi / pdf (..., c)) for wo (..., 3) and u in
        [0, 1)² (..., 2), their leading shapes broadcast as in `eval`; with `nm` (k,) or
        (..., k) the weights at those wavelengths, (..., k) (a delta draw: its
        lobe's reflectance there over its pdf, the probability of choosing that lobe).

        One wo of shape (3,) with u of shape (2,): wi (3,), pdf 0-d, weight (c,) — one pair's
        shapes, as in `eval`. A wo below the horizon, NaN, infinite or zero draws nothing (wi,
        pdf and weight 0); a u outside [0, 1) (NaN included) is a ValueError."""
    @overload
    def sample(
        self, wo: _ArrayLike, u: _ArrayLike, *, nm: _ArrayLike | None = None, delta: Literal[True]
    ) -> tuple[npt.NDArray[np.float64], npt.NDArray[np.float64], npt.NDArray[np.float32],
               npt.NDArray[np.bool_]]:
        """The same and a bool (...): the draws of a delta lobe (their pdf is the probability
        of choosing that lobe; `pdf()` does not contain them)."""
    def albedo(self, theta: _ArrayLike, phi: float = 0.0) -> npt.NDArray[np.float64]:
        """Directional albedo at θ′ in radians, 0 ≤ θ′ < π/2 (light above the horizon; else
        ValueError naming theta), for light at azimuth `phi` (radians from the local x axis,
        along which an anisotropic model's α_x runs; default 0; not finite: ValueError naming
        phi): float64 of θ′'s shape then c: (k, c) for k angles, (c,) for a scalar θ′. The
        azimuth matters for anisotropic sources only (GGX α = (0.01, 1) at θ′ = 89°: 0.517 at
        phi = 0, 0.904 at phi = 0.3).

        A closed form where the model has one, else adaptive quadrature: 1e-6 relative for
        models, 1e-4 for tables and measured data (a tenth of a second an angle for an RGL
        file; Ctrl-C stops the curve between angles).
        """
    def sampling_resolution(self, adjoint: bool = False, nearest: bool = False) -> dict[str, int]:
        """The resolution the library samples this source at: {"theta_h", "phi_h", "theta_o",
        "phi_o"}, the keywords of `sampling_nodes` — twice the θh nodes for a peak at normal
        incidence too sharp for 64, half again the views and φh nodes for a lobe that changes
        shape between the grazing views faster than they follow (the Phong family);
        nearest=True for a table read by cell. Decides by building a sampler (tens of ms)."""
    def table(self, **options: Any) -> Table:
        """The decoded table (other sources are baked with the keywords of `bake`); unpacks as
        `values, grid = b.table()`."""
    def sampling_nodes(
        self,
        adjoint: bool = False,
        theta_h: int = 64,
        phi_h: int = 64,
        theta_o: int = 32,
        phi_o: int = 16,
    ) -> dict[str, Any]:
        """The node densities of the library's importance sampler: {"version": 3, "linear" (a of
        the θh map (π/2)(a s + (1 − a) s²)), "nx", "ny", "nt", "np", "isotropic", "data": float32
        (nt·np, ny, nx), "alias": {"other_bits",
        "pdf": float32 (nt·np, ny, nx) normalized, "strips": uint32 (nt·np, 2(ny − 1)),
        "cells": uint32 (nt·np, ny, nx − 1)}} — "alias" is the library's constant-time draw
        (Rust ``brdftab::table::AliasTables``); adjoint=True conditions on wi (Mitsuba's
        convention)."""
    def __reduce__(self) -> tuple[Any, tuple[Any, ...]]: ...
    def __copy__(self) -> Brdf: ...
    def __deepcopy__(self, memo: Any, /) -> Brdf: ...

@final
class Table:
    """A decoded table: `values` shares its memory (read-only float32, stored axes + channels,
    λ innermost; flat when packed), `grid` describes it. The values are the stored quantity
    (`info(...)["tables"][k]["quantity"]`: "fr", "fr_cos_out" or "fr_cos_cos", i.e. f_r, f_r cos θo
    or f_r cos θi cos θo), before any albedo calibration (`"calibrated"`) a lookup applies.
    Edited values go back in with `with_values`; `save` writes the table, `open` looks it up.
    Immutable: `copy.copy` and `copy.deepcopy` give the object itself; it does not pickle
    (`save` it)."""
    @property
    def values(self) -> npt.NDArray[np.float32]:
        """float32 values shaped by the stored axes and the channels (grid["stored_shape"] +
        [c], λ innermost), or flat for a packed layout; read-only, no copy."""
    @property
    def grid(self) -> dict[str, Any]:
        """{"param", "theta1", "phi1", "theta2", "phi2" (the full axes), "symmetry",
        "stored_axes" (their mappings and node placement), "stored_shape", "packed",
        "channels", "channel_names", "quantity", "calibration", "description"}."""
    def device_layout(self, interp: str = "linear") -> dict[str, Any]:
        """The table as a GPU or JIT host evaluates it for lookups with `interp` ("linear",
        "nearest", or "auto": nearest on a grid of MERL cells, linear otherwise): the library's
        device layout, a dict with "version", "kind" ("kernel" or "grid"), "channels",
        "channel_names", "quantity", "calibration", "kernel" and "grid" (None or the layout's
        fields, each with its float32 "values")."""
    def with_values(self, values: _ArrayLike, *, calibration: bool = True) -> Table:
        """The same table (grid: stored layout, symmetry, quantity, albedo calibration) holding
        `values`: any array-like of real numbers the size of `values` — shaped as it is (stored
        axes + channels), flat, (nodes, c) (a row per stored node, as
        `eval(*node_directions())` gives for a packed table), or for a packed table the
        rectangle `brdftab export --npy` writes (unstored nodes ignored) — converted to float32
        in C order. Values are the stored
        quantity before the calibration, as `values` gives them; negative values mark unmeasured
        nodes of an f_r table (lookups read 0). `calibration=False` drops the grid's albedo
        calibration (for another material's values on this grid). A wrong size or shape, or a
        NaN or infinite stored value, is a ValueError naming `values` and the index."""
    def save(
        self,
        output: _Path,
        *,
        codec: str | None = ...,
        codec_tolerance: float | None = ...,
        floor: float | None = ...,
        level: int | None = ...,
        exhaustive: bool = ...,
        name: str | None = ...,
        replace: bool = ...,
    ) -> dict[str, Any]:
        """Writes the table to OUTPUT, a .btdb file (replaced atomically) or DB#NAME (an
        existing name needs replace=True), with the storage keywords of `bake` (codec "f32"
        keeps the values bit for bit; default "log16", 1e-3 relative; `name` names a .btdb
        file's table, and with DB#NAME may only repeat NAME). Returns
        `brdftab info --json OUTPUT`."""
    def open(self, interp: str = "auto") -> Brdf:
        """The table as a Brdf, in memory ("auto": nearest on a grid of MERL cells, linear
        otherwise). It has no SOURCE: it does not pickle, and `table(**options)` refuses to
        bake it again."""
    def node_angles(self) -> npt.NDArray[np.float64]:
        """The coordinates of every stored node in radians, shaped like `values` with the
        channels replaced by the parameterization's four angles ("halfdiff": θh, φh, θd, φd;
        "inout": θi, φi, θo, φo, an isotropic table's φi 0 and φo the azimuth difference);
        flat (nodes × 4) for a packed table."""
    def node_directions(
        self,
    ) -> tuple[npt.NDArray[np.float64], npt.NDArray[np.float64]]:
        """(wi, wo) of every stored node: unit vectors shaped like `node_angles` with 3
        components, as `Brdf.eval` takes them (nodes outside the physical domain have a
        direction at or below the horizon, where eval gives 0)."""
    def __iter__(self) -> Iterator[Any]:
        """Yields values, then grid: `values, grid = b.table()`."""
    def __len__(self) -> int:
        """2 (values and grid)."""
    def __copy__(self) -> Table: ...
    def __deepcopy__(self, memo: Any, /) -> Table: ...

def open(
    source: _Source,
    *,
    interp: str = "auto",
    wavelengths: _Wavelengths = None,
    eager: bool = True,
) -> Brdf:
    """Opens SOURCE (a str, bytes or os.PathLike: a file name need not be UTF-8). interp:
    "auto" (nearest on tables of MERL cells and MERL files, linear otherwise), "nearest" or
    "linear" (a MERL file: its cells interpolated; an RGL file or a model: no effect)."""
def rgb_basis(nm: _ArrayLike) -> npt.NDArray[np.float64]:
    """The weights of R, G, B at wavelengths `nm` (nm; result shape: nm's + (3,)): RGB data
    (r, g, b) at a wavelength is r w[0] + g w[1] + b w[2], as `Brdf.eval_spectral` reads an RGB
    source. Weights >= 0 summing to 1; the spectrum they make projects (CIE 1931 2°, D65,
    linear sRGB) to the RGB it came from, so colour survives a spectral renderer. A value that
    is not a wavelength (a finite number > 0) is a ValueError."""
def check(source: _Source, *, wavelengths: _Wavelengths = None) -> dict[str, Any]:
    """The plausibility report of SOURCE as a dict with the keys of `brdftab check --json`."""
def info(source: _Source) -> dict[str, Any]:
    """What `brdftab info --json` reports of a table file (or, for DB#NAME, of one table): "file", "format", "bytes", "ratio_to_f32",
    "table_count" (the tables the file holds) and "tables", one dict per table with "name", "source", "parameterization", "symmetry",
    "channels", "units", "codec", "tool", "shape", "values", "chunks", "bytes", "ratio_to_f32",
    "sampling_bytes" (of one table — DB#NAME, a file of one table — only: sizing it builds
    the sampler), "quantity" (what the stored values are), "calibrated" and "axes" (per stored
    axis in shape order: "name", "mapping", "nodes" and every node's angle in "degrees"). Of a measured
    file (MERL .binary, RGL .bsdf): "file", "format" ("merl" or "rgl"), "bytes", "channels",
    "sha256", and MERL "material", "dims", "unmeasured", "cells" or RGL "description", "kind",
    "isotropic", "reduction", "phi_i", "theta_i", "resolution", "vndf_resolution", "fields"."""
def bake(
    source: _Source,
    output: _Path,
    *,
    preset: str | None = ...,
    grid: str | None = ...,
    param: str | None = ...,
    symmetry: str | None = ...,
    symmetry_tolerance: float | None = ...,
    force: bool = ...,
    codec: str | None = ...,
    codec_tolerance: float | None = ...,
    floor: float | None = ...,
    level: int | None = ...,
    exhaustive: bool = ...,
    name: str | None = ...,
    supersample: int | None = ...,
    wavelengths: _Wavelengths = ...,
    target_error: float | str | None = ...,
    calibrate: bool | None = ...,
    replace: bool = ...,
) -> dict[str, Any]:
    """Bakes SOURCE into OUTPUT (a .btdb file or DB#NAME); the keywords are the CLI's bake flags,
    snake_cased, validated by the library's request layer. `name` names a .btdb file's table;
    with DB#NAME it may only repeat NAME (another name is an error). Returns `brdftab info
    --json`. Ctrl-C stops it (KeyboardInterrupt; OUTPUT is left as it was)."""
def bake_cached(
    source: _Source,
    cache_dir: _Path | None = None,
    refresh: bool = False,
    **options: Any,
) -> dict[str, Any]:
    """The table of SOURCE baked with `options` (the keywords of `bake`), from the cache of
    baked tables (keyed by the source's content, the settings and the library's version) or
    baked into it now. A cached file whose structure does not read (emptied, truncated) is
    baked again; `refresh=True` bakes again whatever is there (for one whose chunk failed its
    checksum when read). Returns {"path": str, "hit": bool}: "path" is the str os.fsdecode gives
    of the file's name (a cache_dir need not be UTF-8). Ctrl-C stops the bake
    (KeyboardInterrupt; nothing is cached)."""
def convert(
    source: _Source,
    output: _Path,
    *,
    pairs: int | None = ...,
    interp: str | None = ...,
    resolution: int | None = ...,
    theta_i: int | None = ...,
    phi_i: int | None = ...,
    ndf_resolution: int | None = ...,
    **bake_options: Any,
) -> dict[str, Any]:
    """Converts SOURCE into OUTPUT, whose name says its kind: an RGL .bsdf (pbrt-v4 and
    Mitsuba 3 load it), a MERL .binary, DB#NAME, a .btdb file or a raw table. Takes the keywords
    of `bake` plus these; returns {"output", "format", "source", ...}. For a .bsdf, "error" is
    the file read back against SOURCE: "rel_rmse" and "max_rel" within 80°, then "whole"
    (hemisphere), "grazing" (a direction past 80°) and "albedo" (the worst directional albedo
    error: "worst", "theta_deg", "channel", ...), relative, or None with pairs=0. Ctrl-C stops
    it (KeyboardInterrupt; OUTPUT is left as it was)."""
def fit(
    source: _Source,
    model: str,
    *,
    params: str | Sequence[str] | None = ...,
    log: bool = ...,
    starts: int | None = ...,
    pairs: int | None = ...,
    max_theta_deg: float | None = ...,
    seed: int | None = ...,
    fresnel: str | None = ...,
    grey: bool = ...,
    wavelengths: _Wavelengths = ...,
    specular_fraction: float | None = ...,
    max_iterations: int | None = ...,
) -> dict[str, Any]:
    """Fits `model` (a name such as "ggx", a sum "lambert+ggx", or a JSON spec) to SOURCE; the
    keywords are the CLI's fit flags, snake_cased. Returns the dict of `brdftab fit --json`.
    Ctrl-C stops it (KeyboardInterrupt)."""

class Database:
    """A brdftab database: many named tables in one .btdb file. Pickles by its absolute path
    (a copy opens the same file from any working directory); equal to another Database whose
    path names the same file once made absolute and normalized (os.path.abspath: "./m.btdb"
    and "m.btdb"). len(db), name in db and for name in db are its tables' names (none for a
    file not created yet)."""

    path: str
    def __init__(self, path: _Path) -> None:
        """A handle on the database at `path` (a str, bytes or os.PathLike); `path` keeps it
        as the str os.fsdecode gives (a file name need not be UTF-8)."""
    def __repr__(self) -> str: ...
    def __reduce__(self) -> tuple[Any, tuple[Any, ...]]: ...
    def __eq__(self, other: object) -> bool: ...
    def __hash__(self) -> int: ...
    def names(self) -> list[str]:
        """The table names, in file order (the table of contents; `info` reads each table)."""
    def __contains__(self, name: object) -> bool: ...
    def __len__(self) -> int: ...
    def __iter__(self) -> Iterator[str]: ...
    def add(
        self, source: _Source, name: str, *, replace: bool = False, **options: Any
    ) -> dict[str, Any]:
        """Bakes SOURCE into table NAME (the database is created if absent); takes the keywords
        of `bake`. Returns what `brdftab info --json DB#NAME` reports."""
    def add_bytes(self, name: str, data: Buffer, *, replace: bool = False) -> None:
        """Adds the table in a single-table .btdb file's bytes as NAME (chunks copied as they
        are); an existing NAME is an error unless replace. bytes are read in place; another
        buffer (bytearray, memoryview, mmap, ...) is copied into bytes first (MemoryError if
        that does not fit)."""
    def remove(self, name: str) -> None:
        """Removes table NAME (atomic; GIL released while waiting for the lock, a wait Ctrl-C
        stops)."""
    def rename(self, old: str, new: str) -> None:
        """Renames table OLD to NEW (its place and stored bytes kept; atomic, GIL released
        while waiting for the lock, a wait Ctrl-C stops). Error when OLD or the database is absent or NEW is
        taken; ValueError for a name the rule refuses."""
    def open(self, name: str, **options: Any) -> Brdf:
        """Opens table NAME as a Brdf (the keywords of `open`)."""
    def source(self, name: str) -> str:
        """The SOURCE string of table NAME ("DB#NAME"), e.g. for worker processes."""
    def info(self) -> dict[str, Any]:
        """What `brdftab info --json DB` reports: the file and every table, read from their
        headers and indexes (no "sampling_bytes" for a database of several tables: that is
        `info(db.source(name))`'s, one table's)."""
