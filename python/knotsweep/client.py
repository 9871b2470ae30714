"""``knotsweep.Client``: the sweep service's REST API (docs/API.md) from
Python, over httpx. The API's errors are raised as exceptions carrying its
message and fields."""
from __future__ import annotations

import io
import json
import os
import sys
import time
import uuid
from typing import Any, Iterator

import httpx
import numpy as np


class ApiError(Exception):
    """An error answer of the API: ``status`` (HTTP), ``error`` (its kind,
    e.g. ``invalid_input``), ``message`` and ``fields`` ([{field, reason}])."""

    def __init__(self, status: int, error: str, message: str, fields: list[dict] | None = None):
        super().__init__(message)
        self.status = status
        self.error = error
        self.message = message
        self.fields = fields or []

    def __str__(self) -> str:
        return f"{self.message} ({self.status} {self.error})"


class InvalidInput(ApiError, ValueError):
    """422: unknown fields, wrong types, out-of-range values, too many cases."""


class NotFound(ApiError, LookupError):
    """404: unknown sweep, case or route; a case's series before its result."""


class Unauthorized(ApiError, PermissionError):
    """401: the server wants ``Authorization: Bearer <token>``."""


class Conflict(ApiError):
    """409: an idempotency key reused with another body; resuming a cancelled sweep."""


_ERRORS = {401: Unauthorized, 404: NotFound, 409: Conflict, 422: InvalidInput}


def _raise_for(response: httpx.Response) -> None:
    if response.is_success:
        return
    try:
        body = response.json()
        error, message, fields = body["error"], body["message"], body.get("fields", [])
    except (ValueError, KeyError, TypeError):
        error, message, fields = "http", response.text.strip() or response.reason_phrase, []
    raise _ERRORS.get(response.status_code, ApiError)(response.status_code, error, message, fields)


def _require_pandas(what: str):
    try:
        import pandas as pd
    except ImportError as e:
        raise ImportError(f"{what} needs pandas: pip install pandas (or raw=True)") from e
    return pd


class Client:
    """A client of a running ``knotsweep serve`` at ``url``.

    ``token``: the server's ``KNOTSWEEP_TOKEN`` (sent as ``Authorization:
    Bearer``); by default the environment's ``KNOTSWEEP_TOKEN``, if set.
    ``timeout``: seconds for each request (the event stream waits longer)."""

    def __init__(self, url: str = "http://127.0.0.1:8080", token: str | None = None, timeout: float = 30.0):
        self.url = url.rstrip("/")
        token = token if token is not None else os.environ.get("KNOTSWEEP_TOKEN") or None
        headers = {"Authorization": f"Bearer {token}"} if token else {}
        self.http = httpx.Client(base_url=self.url, headers=headers, timeout=timeout)

    def close(self) -> None:
        self.http.close()

    def __enter__(self) -> Client:
        return self

    def __exit__(self, *exc) -> None:
        self.close()

    def __repr__(self) -> str:
        return f"<knotsweep.Client {self.url}>"

    # -- plumbing --------------------------------------------------------
    def _get(self, path: str, **params: Any) -> httpx.Response:
        response = self.http.get(path, params=params or None)
        _raise_for(response)
        return response

    def _post(self, path: str, body: Any = None, headers: dict | None = None) -> httpx.Response:
        # The server takes every POST as JSON only (415 otherwise), a bodiless one too.
        response = self.http.post(path, content=json.dumps({} if body is None else body), headers={
            "Content-Type": "application/json", **(headers or {})})
        _raise_for(response)
        return response

    def _pages(self, path: str) -> list[dict]:
        items: list[dict] = []
        page = self.limits()["max_page"]
        while True:
            response = self._get(path, limit=page, offset=len(items))
            batch = response.json()
            items.extend(batch)
            total = int(response.headers.get("X-Total-Count", len(items)))
            if not batch or len(items) >= total:
                return items

    # -- the API ---------------------------------------------------------
    def submit(
        self,
        preset: str | None = None,
        *,
        base: dict | None = None,
        grid: dict[str, list] | None = None,
        name: str | None = None,
        idempotency_key: str | None = None,
        certify: bool = False,
        loading: list[dict] | None = None,
    ) -> Sweep:
        """Submits a sweep: a ``preset`` (``fig7``, ``fig9``, ``fig11``; ``base``
        overrides its base) or a ``base`` case and a ``grid`` (parameter name
        -> list of values; the cartesian product). ``certify=True`` also runs
        each case's refined twin (time step halved) so that every point of the
        phase diagram gets its numerical uncertainty (about 3x the cost). A
        retry with the same ``idempotency_key`` returns the first sweep.
        ``loading`` is the base's loading program, a list of one-key stages
        (``[{"pull": {}}, {"release": {}}]``; docs/API.md, "Loading
        programs"), the same as ``base={"loading": [...]}``. Raises
        InvalidInput (a ValueError) with the API's message and fields."""
        if loading is not None:
            base = {**(base or {}), "loading": [dict(stage) for stage in loading]}
        spec: dict[str, Any] = {}
        for key, value in (("name", name), ("preset", preset), ("base", base), ("grid", grid)):
            if value is not None:
                spec[key] = value
        if certify:
            spec["certify"] = True
        headers = {"Idempotency-Key": idempotency_key} if idempotency_key else None
        answer = self._post("/api/sweeps", spec, headers).json()
        return Sweep(self, answer["id"], answer)

    def sweep(self, sweep_id: int) -> Sweep:
        """The handle of an existing sweep."""
        return Sweep(self, sweep_id)

    def sweeps(self) -> list[dict]:
        """Every sweep's summary, oldest first."""
        return self._pages("/api/sweeps")

    def presets(self) -> list[dict]:
        """The presets with their base, grid and case count."""
        return self._get("/api/presets").json()

    def case(self, case_id: int) -> dict:
        """A case: parameters, status, result (with stats and stages), series, logs."""
        return self._get(f"/api/cases/{case_id}").json()

    def series(self, case_id: int, raw: bool = False):
        """A finished case's series (the columns of ``knotsweep run --csv``) as
        a pandas DataFrame, or with ``raw=True`` a dict of numpy arrays."""
        text = self._get(f"/api/cases/{case_id}/series.csv").text
        if raw:
            table = np.genfromtxt(io.StringIO(text), delimiter=",", names=True, ndmin=1)
            return {name: np.asarray(table[name]) for name in table.dtype.names or ()}
        return _require_pandas("series").read_csv(io.StringIO(text))

    def snapshots(self, case_id: int) -> list[dict]:
        """A finished case's snapshots (the knot's states kept for viewers), each
        ``points`` a (K, 3) numpy array (a bend's rods one after the other) and
        ``rods`` its rods' node counts (``[K]`` for one rod)."""
        snapshots = self._get(f"/api/cases/{case_id}/snapshots").json()
        for s in snapshots:
            s["points"] = np.asarray(s["points"], dtype=float).reshape(-1, 3)
            s["rods"] = [int(n) for n in s.get("rods") or [len(s["points"])]]
        return snapshots

    def fit(
        self,
        points: list[dict],
        *,
        parameter: str = "mu",
        range: tuple[float, float] = (0.05, 0.8),
        base: dict | None = None,
        certify: bool = False,
        tolerance: float | None = None,
        name: str | None = None,
        wait: bool = True,
        timeout: float | None = None,
        poll: float = 2.0,
    ) -> dict:
        """Fits ``parameter`` (mu by default) within ``range`` to measured
        inversions: ``points`` a list of ``{"params": {"n": 3, "h": 3.4e-3},
        "l_k_bar": 129.3, "error": 1.0}`` (``POST /api/fits``). The search
        runs over queued cases on the server's workers; with ``wait`` (the
        default) this returns the finished fit, whose ``status`` is ``done``
        (``value``, ``interval`` [low, high], ``chi_squared``) or ``failed``
        (``reason``); else the fit as accepted (follow it with
        ``Client.fit_status``). ``certify=True`` certifies every case so that
        its numerical uncertainty widens the interval. Raises InvalidInput
        with the API's fields, TimeoutError after ``timeout`` seconds."""
        spec: dict[str, Any] = {"parameter": parameter, "range": [float(range[0]), float(range[1])],
                                "points": [dict(p) for p in points]}
        for key, value in (("base", base), ("tolerance", tolerance), ("name", name)):
            if value is not None:
                spec[key] = value
        if certify:
            spec["certify"] = True
        fit = self._post("/api/fits", spec).json()
        deadline = None if timeout is None else time.monotonic() + timeout
        while wait and fit["status"] == "running":
            if deadline is not None and time.monotonic() > deadline:
                raise TimeoutError(f"fit {fit['id']} not done after {timeout} s")
            time.sleep(poll)
            fit = self.fit_status(fit["id"])
        return fit

    def fit_status(self, fit_id: int) -> dict:
        """A fit (``GET /api/fits/{id}``): status, evaluations, value and interval when done."""
        return self._get(f"/api/fits/{fit_id}").json()

    def limits(self) -> dict:
        """The service's limits and certification threshold (``/api/limits``):
        ``max_cases``, ``max_body_bytes``, ``max_name_chars``,
        ``max_idempotency_key_chars``, ``max_page``, ``converged_within``."""
        return self._get("/api/limits").json()

    def health(self) -> dict:
        """``/healthz``: database, workers, stalled workers (no exception when degraded)."""
        return self.http.get("/healthz").json()


class Sweep:
    """A submitted sweep (``Client.submit`` or ``Client.sweep``)."""

    def __init__(self, client: Client, sweep_id: int, submitted: dict | None = None):
        self.client = client
        self.id = int(sweep_id)
        self.submitted = submitted
        """The submission's answer (``replayed``, ``cached``, the sweep), if this handle made it."""

    def __repr__(self) -> str:
        return f"<knotsweep.Sweep {self.id} at {self.client.url}>"

    def status(self) -> dict:
        """The sweep: status (queued, running, paused, done, cancelled),
        ``counts`` per case status, ``progress`` (0..1), ``eta_seconds``, ``varied``, ``spec``."""
        return self.client._get(f"/api/sweeps/{self.id}").json()

    def cancel(self) -> dict:
        """Cancels the queued cases; running ones stop at their next heartbeat."""
        return self.client._post(f"/api/sweeps/{self.id}/cancel").json()

    def pause(self) -> dict:
        return self.client._post(f"/api/sweeps/{self.id}/pause").json()

    def resume(self) -> dict:
        return self.client._post(f"/api/sweeps/{self.id}/resume").json()

    def cases(self) -> list[dict]:
        """Every case in grid order: ``case_id``, ``params`` (the varied ones),
        status, progress, inversion, reason, wall time."""
        return self.client._pages(f"/api/sweeps/{self.id}/cases")

    def events(self) -> Iterator[tuple[str, dict]]:
        """The server-sent events, as (name, data): ``progress`` on every
        change, then ``done``; ends with the stream."""
        timeout = httpx.Timeout(self.client.http.timeout.connect, read=60.0)
        with self.client.http.stream("GET", f"/api/sweeps/{self.id}/events", timeout=timeout) as response:
            if not response.is_success:
                response.read()
                _raise_for(response)
            name, data = "message", []
            for line in response.iter_lines():
                if line == "":
                    if data:
                        yield name, json.loads("\n".join(data))
                    name, data = "message", []
                elif line.startswith(":"):
                    continue
                else:
                    key, _, value = line.partition(":")
                    value = value[1:] if value.startswith(" ") else value
                    if key == "event":
                        name = value
                    elif key == "data":
                        data.append(value)

    def wait(self, progress: bool = True, timeout: float | None = None, poll: float = 2.0) -> dict:
        """Waits until the sweep is done (or cancelled) and returns its status.
        Follows the event stream (polling if it breaks); ``progress`` shows a
        progress bar (tqdm if installed, else a line on stderr). Raises
        TimeoutError after ``timeout`` seconds."""
        deadline = None if timeout is None else time.monotonic() + timeout
        bar = _Bar(self.id) if progress else None
        try:
            while True:
                try:
                    for name, event in self.events():
                        if bar:
                            bar.update(event)
                        if name == "done" or event.get("status") in ("done", "cancelled"):
                            return self.status()
                        if deadline is not None and time.monotonic() > deadline:
                            raise TimeoutError(f"sweep {self.id} not done after {timeout} s")
                except (httpx.TransportError, httpx.StreamError):
                    pass
                detail = self.status()
                if bar:
                    bar.update(detail)
                if detail["status"] in ("done", "cancelled"):
                    return detail
                if deadline is not None and time.monotonic() > deadline:
                    raise TimeoutError(f"sweep {self.id} not done after {timeout} s")
                time.sleep(poll)
        finally:
            if bar:
                bar.close()

    def phase_diagram(self, raw: bool = False):
        """The phase diagram as a pandas DataFrame, one row per case in grid
        order: ``case_id``, the varied parameters, ``status``, the inversion's
        fields (``l_k_bar``, ``l_k_arc_bar``, ``l_c_over_L``, ``F_bar_before``, ...; NaN without
        one), ``simplified_l_k_bar`` (the simplified model's snap),
        ``reason`` and, for a certified sweep, ``refined_l_k_bar``,
        ``uncertainty`` (|refined - default| in l_k bar),
        ``relative_uncertainty`` and ``converged`` (relative at most the
        service's threshold, ``df.attrs["converged_within"]``);
        ``df.attrs`` holds the sweep's ``varied``, ``base``, ``preset``,
        ``complete``, ``certified``, ``solver_version``,
        ``physics_revision`` and ``converged_within``. ``raw=True``: the
        API's JSON as a dict."""
        diagram = self.client._get(f"/api/sweeps/{self.id}/phase-diagram").json()
        if raw:
            return diagram
        pd = _require_pandas("phase_diagram")
        fields = ["l_k_bar", "l_k_arc_bar", "l_c_over_L", "F_bar_before", "F_bar_after", "H_bar_before",
                  "H_bar_after", "kinetic_energy_ratio"]
        certified_columns = [("refined_l_k_bar", "refined_l_k_bar"), ("uncertainty", "absolute"),
                             ("relative_uncertainty", "relative"), ("converged", "converged")]
        rows = []
        for point in diagram["points"]:
            inversion = point.get("inversion") or {}
            row = {"case_id": point["case_id"]}
            row.update({axis: point["params"].get(axis) for axis in diagram["varied"]})
            row["status"] = point["status"]
            row.update({f: inversion.get(f, np.nan) for f in fields})
            simplified = point.get("simplified_l_k_bar")
            row["simplified_l_k_bar"] = np.nan if simplified is None else simplified
            row["reason"] = point.get("reason")
            uncertainty = point.get("uncertainty") or {}
            for column, key in certified_columns:
                value = uncertainty.get(key)
                row[column] = np.nan if value is None else value
            rows.append(row)
        certified = bool(diagram.get("certified"))
        columns = ["case_id", *diagram["varied"], "status", *fields, "simplified_l_k_bar", "reason"]
        if certified:
            columns += [column for column, _ in certified_columns]
        df = pd.DataFrame(rows, columns=columns)
        df.attrs.update({k: diagram.get(k) for k in (
            "sweep_id", "name", "preset", "status", "complete", "certified", "varied", "base",
            "solver_version", "physics_revision")})
        df.attrs["converged_within"] = self.client.limits()["converged_within"]
        return df

    def series(self, case_id: int, raw: bool = False):
        """A case's series (``Client.series``)."""
        return self.client.series(case_id, raw=raw)


class _Bar:
    """The progress of ``Sweep.wait``: tqdm if installed, else a line on stderr."""

    def __init__(self, sweep_id: int):
        self.sweep_id = sweep_id
        self.tqdm = None
        try:
            from tqdm.auto import tqdm

            self.tqdm = tqdm(total=1.0, desc=f"sweep {sweep_id}",
                             bar_format="{desc}: {percentage:3.0f}%|{bar}| {elapsed} {postfix}")
        except ImportError:
            pass

    def update(self, event: dict) -> None:
        counts = event.get("counts") or {}
        text = " ".join(f"{k} {v}" for k, v in sorted(counts.items()) if v)
        eta = event.get("eta_seconds")
        if eta is not None:
            text += f" eta {eta:.0f}s"
        if self.tqdm is not None:
            self.tqdm.n = round(float(event.get("progress", 0.0)), 4)
            self.tqdm.set_postfix_str(text, refresh=False)
            self.tqdm.refresh()
        else:
            print(f"\rsweep {self.sweep_id}: {100 * event.get('progress', 0.0):5.1f}% {text}   ",
                  end="", file=sys.stderr, flush=True)

    def close(self) -> None:
        if self.tqdm is not None:
            self.tqdm.close()
        else:
            print(file=sys.stderr)


def new_idempotency_key() -> str:
    """A fresh key for ``submit(idempotency_key=...)`` (keep it to retry safely)."""
    return uuid.uuid4().hex
