"""``knotsweep.run``: one tightening case in this process, the solver of
``knotsweep run`` (the same Rust code, compiled with the same profile), with
the GIL released while it runs."""
from __future__ import annotations

import inspect
import json
import textwrap
from typing import Any, Callable, NamedTuple

import numpy as np

from . import _native
from ._params import grouped


class Record(dict):
    """A JSON object of a report: a dict whose keys are also attributes
    (``r.inversion.l_k_bar`` and ``r.inversion["l_k_bar"]``)."""

    def __getattr__(self, name: str) -> Any:
        try:
            return self[name]
        except KeyError:
            raise AttributeError(name) from None

    def __dir__(self):
        return list(super().__dir__()) + list(self.keys())


class Inversion(Record):
    """The inversion point (eq. 11's quantities; docs/API.md, "Phase diagram"):
    ``l_k_bar``, ``l_k_arc_bar`` (the knot's own length, (arc length - l_c) / h),
    ``l_c_over_L``, ``F_bar_before``, ``F_bar_after``, ``H_bar_before``,
    ``H_bar_after``, ``kinetic_energy_ratio``, ``sample``."""


class Stats(Record):
    """Counts and timings of a run: ``steps``, ``newton_iterations``,
    ``contact_sweeps``, ``relax_steps``, ``restarts`` (returns of the adaptive
    pull to a checkpoint), ``rejected_steps``, ``smallest_dt``
    (s), ``wall_time``, ``detection_time``, ``contact_time``, ``dynamics_time`` (s)."""


class Stage(Record):
    """A stretch of the run in one step phase (``settle``, ``reference``,
    ``approach``, ``snap``, ``after``, ``fallback``, ``hold``, ``rotate``):
    ``phase``, ``stage`` (the loading program's stage index, None for the
    relaxation), ``from_l_k_bar``, ``to_l_k_bar``, ``steps``,
    ``newton_iterations``, ``contact_sweeps``, ``outcome`` (how the adaptive
    schedule ended it: ``restarted``, ``confirmed``, ``refuted``, ``too_late``;
    None: it ran its course)."""


class Event(Record):
    """A snap of the loop in one stage of the loading program: ``stage``
    (index), ``direction`` (``tighten``, ``loosen``), ``kind`` (``inversion``,
    ``flip_back``), ``clean``, ``restarts`` (the stage's restarts until it was
    found), and the inversion's quantities (``l_k_bar``, ``l_k_arc_bar``,
    ``F_bar_before``, ``F_bar_after``, ``H_bar_before``, ``H_bar_after``, ...)."""


class Hysteresis(Record):
    """The loop snapped at ``inversion_l_k_bar`` while tightened and flipped
    back at ``flip_back_l_k_bar`` while loosened; ``width`` is their difference."""


class QuasiStatic(Record):
    """Whether the loading was quasi-static: ``kinetic_ratio`` (median kinetic
    over elastic energy before each event), ``limit``, ``holds``."""


class Snapshot(Record):
    """A state of the knot kept for viewers: ``label``, ``l_k_bar``, ``points`` (a (K, 3)
    numpy array, m; a bend's rods one after the other), ``rods`` (each rod's node
    count: ``[K]`` for one rod), the other per-node quantities the solver records
    (numpy arrays) and ``contacts`` (loaded contacts: ``a``, ``b``, ``force``, ...)."""

    def per_rod(self, key: str = "points") -> list[np.ndarray]:
        """A per-node array (``points``, ``curvature``, ``twist_rate``,
        ``velocity``) split into one array per rod."""
        return np.split(self[key], np.cumsum(self.rods)[:-1])


class Progress(NamedTuple):
    """What a running case reports after every sample."""

    fraction: float
    l_k_bar: float
    H_bar: float
    steps: int


class Result:
    """The report of one case, as ``knotsweep run --out`` writes it.

    ``status`` (``completed``, ``diverged``, ``penetrated``,
    ``topology_changed``, ``cancelled``) and ``reason``; ``params`` (every
    parameter, defaults filled in); ``inversion`` (None when there is none);
    ``series`` (numpy arrays by the columns of ``knotsweep run --csv``:
    ``l_k_bar``, ``F_bar``, ``H_bar``, ...); ``snapshots``; ``stats``;
    ``phases`` (the run's step phases, each with its loading stage; ``stages``
    is the same list under its former name); ``events`` (every inversion and
    flip back of every stage of the loading program), ``hysteresis`` (None
    unless a loosening stage saw the loop flip back) and ``quasi_static``
    (None where no sample was taken at ``pull_speed``); ``scaling`` (time
    step, mass scale, time unit, pull rates); ``writhe`` and ``start_twist``
    (turns); the knot's Alexander polynomials ``alexander_initial`` and
    ``alexander_final`` (integer coefficients, lowest power first) and
    determinants ``determinant_initial`` and ``determinant_final``;
    ``report``, the whole report as a dict (without the series)."""

    def __init__(self, report: dict, series: dict[str, np.ndarray]):
        self.report = report
        self.status: str = report["status"]
        self.reason: str = report["reason"]
        self.params: dict = report["params"]
        inversion = report.get("inversion")
        self.inversion: Inversion | None = Inversion(inversion) if inversion is not None else None
        self.series: dict[str, np.ndarray] = series
        self.snapshots: list[Snapshot] = [_snapshot(s) for s in report.get("snapshots", [])]
        self.stats = Stats(report.get("stats", {}))
        self.phases: list[Stage] = [Stage(s) for s in report.get("phases", report.get("stages", []))]
        self.stages: list[Stage] = self.phases
        self.events: list[Event] = [Event(e) for e in report.get("events", [])]
        hysteresis = report.get("hysteresis")
        self.hysteresis: Hysteresis | None = Hysteresis(hysteresis) if hysteresis is not None else None
        quasi = report.get("quasi_static")
        self.quasi_static: QuasiStatic | None = QuasiStatic(quasi) if quasi is not None else None
        scaling = report.get("scaling")
        self.scaling: Record | None = Record(scaling) if scaling is not None else None
        self.writhe: float = report.get("writhe", 0.0)
        self.start_twist: float = report.get("start_twist", 0.0)
        self.alexander_initial: list[int] | None = report.get("alexander_initial")
        self.alexander_final: list[int] | None = report.get("alexander_final")
        self.determinant_initial: int | None = report.get("determinant_initial")
        self.determinant_final: int | None = report.get("determinant_final")

    @property
    def completed(self) -> bool:
        """Whether the case ran to its stop condition."""
        return self.status == "completed"

    def to_pandas(self):
        """The series as a pandas DataFrame (the columns of ``knotsweep run --csv``)."""
        try:
            import pandas as pd
        except ImportError as e:  # pragma: no cover - depends on the environment
            raise ImportError("Result.to_pandas needs pandas: pip install pandas") from e
        return pd.DataFrame(self.series)

    def to_dict(self) -> dict:
        """The report as ``knotsweep run --out`` writes it, series included (lists)."""
        series = [
            dict(zip(self.series, row)) for row in zip(*(a.tolist() for a in self.series.values()))
        ]
        return {**self.report, "series": series}

    def __repr__(self) -> str:
        p = self.params
        inv = f"{self.inversion.l_k_bar:.2f}" if self.inversion else None
        return (
            f"<knotsweep.Result n={p['n']} h={p['h']} mu={p['mu']}: {self.status}, "
            f"inversion l_k_bar {inv}, {len(self.series.get('l_k_bar', []))} samples>"
        )


def _snapshot(snapshot: dict) -> Snapshot:
    """A report's (or the service's) snapshot with its per-node lists (points,
    and whatever else the solver records per node) as numpy arrays and
    ``rods`` its rods' node counts (``[K]`` for one rod)."""
    out = Snapshot(snapshot)
    for key, value in snapshot.items():
        if key not in ("contacts", "rods") and isinstance(value, list):
            out[key] = np.asarray(value, dtype=float)
    out["points"] = np.asarray(snapshot["points"], dtype=float).reshape(-1, 3)
    out["rods"] = [int(n) for n in snapshot.get("rods") or [len(out["points"])]]
    return out


def _progress_callback(progress: bool | Callable[[Progress], Any] | None):
    """The native observer for ``run``'s ``progress``, and what to close after."""
    if not progress:
        return None, None
    if callable(progress):
        return (lambda *a: progress(Progress(*a))), None
    try:
        from tqdm.auto import tqdm
    except ImportError:
        return None, None
    bar = tqdm(total=1000, bar_format="{l_bar}{bar}| {elapsed}<{remaining} {postfix}")

    def update(fraction, l_k_bar, H_bar, steps):
        bar.n = int(fraction * 1000)
        bar.set_postfix_str(f"l_k bar {l_k_bar:.1f}  H bar {H_bar:.2f}", refresh=False)
        bar.refresh()

    return update, bar


def run(*, progress: bool | Callable[[Progress], Any] | None = None, **params: Any) -> Result:
    bar = None
    try:
        callback, bar = _progress_callback(progress)
        report, series = _native.run(params, callback)
    finally:
        if bar is not None:
            bar.close()
    return Result(json.loads(report), series)


def validate(**params: Any) -> dict:
    """Checks case parameters (the keywords of ``run``) as the API checks a
    sweep's base, building the knot, and returns every parameter's value;
    raises ParameterError (a ValueError) naming each bad field."""
    return json.loads(_native.validate(params))


def _run_doc() -> str:
    lines = "\n\n".join(
        f"  {title}:\n"
        + "\n".join(
            textwrap.fill(p.docline, width=100, initial_indent="    ", subsequent_indent="        ")
            for p in params
        )
        for _, title, params in grouped()
    )
    return (
        "Runs one overhand-knot tightening case and returns its Result.\n\n"
        "The keywords are the case parameters of the solver's one table (docs/API.md); any left\n"
        "out takes the paper's default. An unknown name, a value of the wrong type or out of its\n"
        "range raises ParameterError (a ValueError) naming the field, in the API's words.\n"
        "The GIL is released while the solver runs, so threads run cases in parallel;\n"
        "Ctrl-C stops the case and raises KeyboardInterrupt.\n\n"
        "progress: True shows a progress bar (tqdm, if installed); a callable is called with a\n"
        "    Progress(fraction, l_k_bar, H_bar, steps) after every sample, and returning False\n"
        "    stops the case (status 'cancelled').\n\n"
        "loading: a list of stages (dicts), e.g. [{'pull': {}}, {'release': {}}] (docs/API.md,\n"
        "    Loading programs).\n\n"
        "Case parameters (SI units), by group:\n" + lines + "\n"
    )


run.__doc__ = _run_doc()
run.__signature__ = inspect.Signature(  # type: ignore[attr-defined]
    [inspect.Parameter("progress", inspect.Parameter.KEYWORD_ONLY, default=None)]
    + [
        inspect.Parameter(p.name, inspect.Parameter.KEYWORD_ONLY, default=p.default_value)
        for _, _, params in grouped()
        for p in params
    ]
)
