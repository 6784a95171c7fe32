from typing import Any

import brdftab

def register() -> None:
    """Registers the Mitsuba 3 BSDF plugin `brdftab` for the current variant."""

def plugin_class() -> type:
    """The plugin's class for the current variant (a subclass of that variant's `mi.BSDF`)."""

def brdftab_kind(source: str) -> str:
    """The kind of SOURCE as the library classifies it: "spec", "merl", "rgl" or "table" (a
    ``DB.btdb#NAME`` is a table whatever its name ends with)."""

JIT_TABLE_PROPERTIES: tuple[str, ...]
"""Properties of the JIT variants' table (preset, grid, cache, cache_dir, sampling_res); the scalar
variants accept them and ignore them (they evaluate the source itself), checking cache and
sampling_res as the JIT variants do."""
SAMPLING_RES_RANGE: tuple[int, int]
"""The range of the ``sampling_res`` property (half-vector nodes per axis), checked in every
variant."""
LAYOUT_VERSION: int
"""The device-layout version JitTable implements (Rust `brdftab::table::device::VERSION`)."""
MODEL_TARGET_ERROR: float
"""The error target of the JIT variants' tables of isotropic models (`bake`'s target_error)."""

class JitTable:
    """A brdftab table evaluated in Dr.Jit operations: an implementation of the library's
    device layout (`Table.device_layout(interp)`), tested against the library's lookup."""

    params: Any
    """The layout's values (float32 Dr.Jit array, the table's stored layout): the plugin's
    differentiable scene parameter `values`."""
    n_values: int
    """Number of values in `params`."""
    edited: bool
    """Whether `params` were edited (lookups then read them instead of packed codes)."""

    def __init__(self, layout: dict[str, Any]) -> None: ...
    def coords(self, wi: Any, wo: Any) -> tuple[list[Any], Any]:
        """Canonical [x0, x1, x2, x3] (float64) of a grid layout, and the validity mask; raises
        `brdftab.Error` on a kernel layout (its lookup works in its own warped variables)."""
    def lookup(self, wi: Any, wo: Any, active: Any = True) -> list[Any]:
        """f_r per channel: a list of c float32 arrays (0 where invalid)."""
    def edit(self) -> None:
        """Lookups read `params` from now on (after an in-place change, as
        `mi.SceneParameters.update` makes); raises brdftab.Error if their number changed."""

class _Common:
    """What both plugin flavours share: the properties, the flags, the description."""

    source: str
    """The SOURCE the plugin opened (a file found through Mitsuba's file resolver)."""
    interp: str
    """The `interp` property ("auto", "linear" or "nearest")."""
    spectral: bool
    """Whether the variant is spectral."""
    brdf: brdftab.Brdf
    """The source opened by the library."""
    delta: bool
    """Whether the source has a delta lobe (its draws are delta samples)."""
    def to_string(self) -> str:
        """`BrdftabBSDF[source=..., <the source's description>]`."""

class ScalarBrdftabBSDF(_Common):
    """The plugin's methods in a scalar variant (copied into `plugin_class()`, a subclass of
    the variant's `mi.BSDF`): every query calls the library (the native source)."""

    def __init__(self, props: Any) -> None: ...
    def eval(self, ctx: Any, si: Any, wo: Any, active: Any = True) -> Any:
        """f_r · cos θ(wo) (Mitsuba's `eval`; 0 below either horizon and for a delta source).
        In importance transport the adjoint, f_r(wo, si.wi) · cos θ(wo); 0 for a context whose
        type mask or component leaves out the plugin's one component."""
    def pdf(self, ctx: Any, si: Any, wo: Any, active: Any = True) -> Any:
        """The density of `sample` drawing wo given `si.wi` (0 for a delta source)."""
    def eval_pdf(self, ctx: Any, si: Any, wo: Any, active: Any = True) -> tuple[Any, Any]:
        """`(eval(...), pdf(...))`."""
    def sample(
        self, ctx: Any, si: Any, sample1: Any, sample2: Any, active: Any = True
    ) -> tuple[Any, Any]:
        """(a `BSDFSample3f`, its weight f_r cos θ(wo) / pdf) drawn by the library's sampler;
        a delta lobe's draw is a `DeltaReflection` sample."""
    def traverse(self, callback: Any) -> None:
        """Nothing to expose: a scalar variant evaluates the source, which has no values."""
    def parameters_changed(self, keys: list[str]) -> None:
        """Nothing to update (see `traverse`)."""

class JitBrdftabBSDF(_Common):
    """The plugin's methods in a JIT variant (copied into `plugin_class()`, a subclass of the
    variant's `mi.BSDF`; what `mi.load_dict({"type": "brdftab", ...})` returns): a table
    evaluated in Dr.Jit, the library's importance sampler."""

    table: JitTable
    """The table the plugin evaluates."""
    cache: bool
    """The `cache` property: baked tables are kept in the cache of baked tables."""
    cache_dir: str | None
    """The `cache_dir` property."""
    def __init__(self, props: Any) -> None: ...
    def eval(self, ctx: Any, si: Any, wo: Any, active: Any = True) -> Any:
        """f_r · cos θ(wo) from the table (0 below either horizon).
        In importance transport the adjoint, f_r(wo, si.wi) · cos θ(wo); 0 for a context whose
        type mask or component leaves out the plugin's one component."""
    def pdf(self, ctx: Any, si: Any, wo: Any, active: Any = True) -> Any:
        """The density of `sample` drawing wo given `si.wi`."""
    def eval_pdf(self, ctx: Any, si: Any, wo: Any, active: Any = True) -> tuple[Any, Any]:
        """`(eval(...), pdf(...))` in one table lookup."""
    def sample(
        self, ctx: Any, si: Any, sample1: Any, sample2: Any, active: Any = True
    ) -> tuple[Any, Any]:
        """(a `BSDFSample3f`, its weight f_r cos θ(wo) / pdf) drawn by the library's sampler."""
    def traverse(self, callback: Any) -> None:
        """Exposes `values` (differentiable): the table's values before its albedo calibration;
        eval, eval_pdf and sample's weight are linear in them."""
    def parameters_changed(self, keys: list[str]) -> None:
        """After `values` changed: lookups read them; the sampling distributions stay those of
        the loaded table (unbiased) until `resample`."""
    def resample(self) -> None:
        """Rebuilds the sampling distributions from the current `values` (between renders)."""
    def export_table(self) -> brdftab.Table:
        """The table with its current values, a `brdftab.Table` on the same grid (albedo
        calibration included); save it with `Table.save`."""
