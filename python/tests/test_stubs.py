"""The committed type stubs are those the parameter table gives."""
import os
from pathlib import Path

from knotsweep import _stubs

STUBS = Path(__file__).resolve().parents[1] / "knotsweep" / "__init__.pyi"


def test_stubs_match_the_parameter_table():
    text = _stubs.render()
    if os.environ.get("UPDATE_STUBS"):
        STUBS.write_text(text)
    assert STUBS.read_text() == text, (
        "python/knotsweep/__init__.pyi is stale: UPDATE_STUBS=1 pytest python/tests/test_stubs.py rewrites it"
    )
    compile(text, str(STUBS), "exec")
    for name in ("n: int = 3,", "h: float = 1.6e-3,", "dt: float | None = None,",
                 'protocol: Literal["reference", "adaptive"] = "adaptive",'):
        assert name in text
