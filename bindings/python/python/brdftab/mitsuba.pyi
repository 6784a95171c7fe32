from typing import Any

def register() -> None:
    """Registers the Mitsuba 3 BSDF plugin `brdftab` for the current variant."""

def plugin_class() -> type: ...

LAYOUT_VERSION: int
MODEL_TARGET_ERROR: float

class JitTable:
    """A brdftab table evaluated in Dr.Jit operations: an implementation of the library's
    device layout (`Table.device_layout(interp)`), tested against the library's lookup."""

    def __init__(self, layout: dict[str, Any]) -> None: ...
    def coords(self, wi: Any, wo: Any) -> tuple[list[Any], Any]: ...
    def lookup(self, wi: Any, wo: Any, active: Any = True) -> list[Any]: ...
