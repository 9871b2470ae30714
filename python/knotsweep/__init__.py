"""knotsweep: snap buckling of overhand knots in elastic rods.

``knotsweep.run(n=3, h=1.6e-3, mu=0.1, ...)`` runs one case in this process
with the solver of ``knotsweep run`` (GIL released; parameters of the one
table, docs/API.md); ``knotsweep.Client(url)`` submits sweeps to a running
``knotsweep serve`` and reads their phase diagrams.
"""
from ._native import PHYSICS_REVISION, ParameterError, __version__
from ._params import PARAMETERS, Parameter
from ._run import (
    Event,
    Hysteresis,
    Inversion,
    Progress,
    QuasiStatic,
    Record,
    Result,
    Snapshot,
    Stage,
    Stats,
    run,
    validate,
)
from .client import ApiError, Client, Conflict, InvalidInput, NotFound, Sweep, Unauthorized

__all__ = [
    "PARAMETERS",
    "PHYSICS_REVISION",
    "ApiError",
    "Client",
    "Conflict",
    "Event",
    "Hysteresis",
    "InvalidInput",
    "Inversion",
    "NotFound",
    "Parameter",
    "ParameterError",
    "Progress",
    "QuasiStatic",
    "Record",
    "Result",
    "Snapshot",
    "Stage",
    "Stats",
    "Sweep",
    "Unauthorized",
    "__version__",
    "run",
    "validate",
]
