from typing import Any

def register() -> None:
    """Registers the Mitsuba 3 BSDF plugin `brdftab` for the current variant."""

def plugin_class() -> type:
    """The plugin's class for the current variant (a subclass of that variant's `mi.BSDF`)."""

def brdftab_kind(source: str) -> str:
    """The kind of SOURCE by its name, as the plugin needs it: "spec", "merl", "rgl" or "table"."""

LAYOUT_VERSION: int
"""The device-layout version JitTable implements (Rust `brdftab::table::device::VERSION`)."""
RGB_WAVELENGTHS: tuple[float, float, float]
"""Where B, G and R of an RGB table sit on the wavelength axis (nm) in a spectral variant."""
MODEL_TARGET_ERROR: float
"""The error target of the JIT variants' tables of isotropic models (`bake`'s target_error)."""

class JitTable:
    """A brdftab table evaluated in Dr.Jit operations: an implementation of the library's
    device layout (`Table.device_layout(interp)`), tested against the library's lookup."""

    def __init__(self, layout: dict[str, Any]) -> None: ...
    def coords(self, wi: Any, wo: Any) -> tuple[list[Any], Any]:
        """Canonical [x0, x1, x2, x3] (float64) of the grid layout, and the validity mask."""
    def lookup(self, wi: Any, wo: Any, active: Any = True) -> list[Any]:
        """f_r per channel: a list of c float32 arrays (0 where invalid)."""
