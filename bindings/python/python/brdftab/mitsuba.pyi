from typing import Any

def register() -> None:
    """Registers the Mitsuba 3 BSDF plugin `brdftab` for the current variant."""

def plugin_class() -> type: ...

class JitTable:
    """A brdftab table evaluated in Dr.Jit operations (mirrors the Rust lookup)."""

    def __init__(self, values: Any, grid: dict[str, Any], interp: str = "linear") -> None: ...
    def coords(self, wi: Any, wo: Any) -> tuple[list[Any], Any]: ...
    def lookup(self, wi: Any, wo: Any, active: Any = True) -> list[Any]: ...

def kernel_values(values: Any) -> Any:
    """The values as the Rust kernel of adaptive tables reads them (float16 codes of values
    scaled by a power of two), as float32 of the same shape."""
