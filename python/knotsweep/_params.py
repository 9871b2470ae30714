"""The case parameters as Python sees them, read from the solver's one table
(``solver::case::PARAMETERS``, through ``knotsweep._native.parameters()``):
their Python types, defaults and the docstring lines of ``run``."""
from __future__ import annotations

import json
from typing import Any, NamedTuple

from . import _native


class Parameter(NamedTuple):
    """One case parameter, as the solver's table documents it."""

    name: str
    group: str
    """The part of the case it belongs to: ``knot``, ``rod``, ``friction``,
    ``loading`` or ``solver`` (the web form's sections, the API's ``x-group``)."""
    group_title: str
    unit: str
    default: str
    """The default as JSON text (``null`` for none)."""
    range: str
    null: str | None
    paper: str
    doc: str
    description: str
    kind: str
    """``int``, ``float``, ``vector``, ``flag``, ``words``, ``points``, ``program`` or ``text``."""
    words: tuple[str, ...]

    @property
    def default_value(self) -> Any:
        """The default as a Python value (lists as tuples)."""
        value = json.loads(self.default)
        return tuple(value) if isinstance(value, list) else value

    @property
    def annotation(self) -> str:
        """The parameter's Python type, as the stubs write it."""
        base = {
            "int": "int",
            "float": "float",
            "vector": "Sequence[float]",
            "flag": "bool",
            "points": "ArrayLike | Mapping[str, Any]",
            "program": "Sequence[Mapping[str, Mapping[str, Any]]]",
            "text": "str",
        }.get(self.kind)
        if self.kind == "words":
            base = "Literal[" + ", ".join(json.dumps(w) for w in self.words) + "]"
        if self.null is not None:
            base += " | None"
        return base

    @property
    def default_text(self) -> str:
        """The default as Python source: numbers as the table writes them."""
        value = json.loads(self.default)
        if isinstance(value, (int, float)) and not isinstance(value, bool):
            return self.default
        if isinstance(value, str):
            return json.dumps(value)
        return repr(tuple(value) if isinstance(value, list) else value)

    @property
    def docline(self) -> str:
        """``name (unit): doc Range: ... Default: ... Paper: ...``."""
        unit = f" ({self.unit})" if self.unit else ""
        return f"{self.name}{unit}: {self.description}"


PARAMETERS: tuple[Parameter, ...] = tuple(
    Parameter(**{**p, "words": tuple(p["words"])}) for p in _native.parameters()
)
"""Every case parameter, in the table's order."""

NAMES: tuple[str, ...] = tuple(p.name for p in PARAMETERS)

GROUPS: tuple[tuple[str, str], ...] = tuple(dict.fromkeys((p.group, p.group_title) for p in PARAMETERS))
"""The groups (word, title) in the table's order of first appearance."""


def grouped() -> list[tuple[str, str, list[Parameter]]]:
    """The parameters by group in form order (knot, rod, friction, loading,
    solver): (word, title, parameters in the table's order)."""
    order = ("knot", "rod", "friction", "loading", "solver")
    groups = sorted(GROUPS, key=lambda g: order.index(g[0]) if g[0] in order else len(order))
    return [(word, title, [p for p in PARAMETERS if p.group == word]) for word, title in groups]
