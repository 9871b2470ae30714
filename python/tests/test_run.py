"""knotsweep.run against `knotsweep run`, the parameter errors, the GIL and Ctrl-C."""
import json
import os
import signal
import subprocess
import threading
import time
from concurrent.futures import ThreadPoolExecutor

import numpy as np
import pytest

import knotsweep
from conftest import QUICK, need

# The same small case through the CLI and through Python: n = 2, about 2 s, with an
# inversion (at l_k bar 64.0).
CASE = dict(n=2)


def cli_flags(params):
    return [a for k, v in params.items() for a in (f"--{k.replace('_', '-')}", str(v))]


def test_same_inversion_and_series_as_the_cli(knotsweep_bin, tmp_path):
    out, csv = tmp_path / "cli.json", tmp_path / "cli.csv"
    done = subprocess.run([knotsweep_bin, "run", *cli_flags(CASE), "--out", str(out), "--csv", str(csv)],
                          capture_output=True, text=True, timeout=900)
    assert out.exists(), done.stdout + done.stderr
    cli = json.loads(out.read_text())
    r = knotsweep.run(**CASE)
    assert r.status == cli["status"] and r.reason == cli["reason"]
    assert r.params == cli["params"]
    assert cli["inversion"] is not None, "the case should invert"
    # The same binary result: every number equal, not close.
    assert dict(r.inversion) == cli["inversion"]
    assert list(r.series) == csv.read_text().splitlines()[0].split(",")
    table = np.genfromtxt(csv, delimiter=",", names=True, ndmin=1)
    for column, values in r.series.items():
        assert np.array_equal(values, table[column]), column
    assert r.stats.steps == cli["stats"]["steps"]
    assert [s["phase"] for s in r.report["phases"]] == [s["phase"] for s in cli["phases"]]
    assert r.events == cli["events"] and r.quasi_static == cli["quasi_static"]
    assert len(r.snapshots) == len(cli["snapshots"])
    for mine, theirs in zip(r.snapshots, cli["snapshots"]):
        assert mine.label == theirs["label"]
        assert np.array_equal(mine.points, np.array(theirs["points"]))
    assert r.determinant_initial == cli["determinant_initial"] == 5


def test_bad_parameter_raises_value_error_naming_the_field():
    with pytest.raises(ValueError, match=r"^mu: must be in \[0, 2\], got -1$") as e:
        knotsweep.run(n=3, mu=-1.0)
    assert isinstance(e.value, knotsweep.ParameterError)
    assert e.value.fields == [("mu", "must be in [0, 2], got -1")]
    with pytest.raises(ValueError, match=r"^nu: unknown parameter; known: adaptive_dt, .*youngs_modulus$"):
        knotsweep.run(nu=0.3)
    with pytest.raises(ValueError, match=r"^n: must be a whole number in 1\.\.=8, got \"three\"$"):
        knotsweep.run(n="three")
    with pytest.raises(ValueError, match=r"^h: must be in \[L/16000, L/50\)"):
        knotsweep.run(h=0.5)
    with pytest.raises(ValueError, match=r"^mu: must be a finite number, got NaN$"):
        knotsweep.validate(mu=float("nan"))
    # Every problem at once, as the API lists them.
    with pytest.raises(ValueError) as e:
        knotsweep.validate(mu=-1.0, poisson_ratio=0.7)
    assert [f for f, _ in e.value.fields] == ["mu", "poisson_ratio"]


def test_values_numpy_and_none():
    params = knotsweep.validate(mu=np.float64(0.2), n=np.int64(2), gravity=np.zeros(3), dt=None)
    assert params["mu"] == 0.2 and params["n"] == 2 and params["gravity"] == [0.0, 0.0, 0.0]
    assert params["dt"] is None
    assert set(params) == set(knotsweep.validate()) == {p.name for p in knotsweep.PARAMETERS}


def test_parameters_and_docstrings_come_from_the_table():
    h = next(p for p in knotsweep.PARAMETERS if p.name == "h")
    assert (h.unit, h.default, h.paper, h.annotation) == ("m", "1.6e-3", "1.6 mm", "float")
    doc = " ".join(knotsweep.run.__doc__.split())
    assert "h (m): Rod radius h" in doc and "Paper: 1.6 mm." in doc
    import inspect

    signature = inspect.signature(knotsweep.run)
    assert signature.parameters["mu"].default == 0.1
    assert signature.parameters["gravity"].default == (0.0, 0.0, 0.0)


def test_result_series_and_pandas():
    r = knotsweep.run(**QUICK)
    assert r.completed, r.reason
    assert r.series["l_k_bar"].dtype == np.float64 and r.series["contacts"].dtype == np.int64
    assert np.all(np.diff(r.series["l_k_bar"]) < 0)
    assert r.snapshots and r.snapshots[0].points.shape == (102, 3)
    assert r.stats.steps > 0 and r.stages
    pd = need("pandas")
    df = r.to_pandas()
    assert isinstance(df, pd.DataFrame) and len(df) == len(r.series["F_bar"])


def test_threads_run_cases_in_parallel_with_the_gil_released():
    counter = 0
    stop = threading.Event()

    def count():
        nonlocal counter
        while not stop.is_set():
            counter += 1

    ticker = threading.Thread(target=count)
    ticker.start()
    try:
        started = time.perf_counter()
        alone = knotsweep.run(**QUICK)
        single = time.perf_counter() - started
    finally:
        stop.set()
        ticker.join()
    # A Python thread kept running while the solver ran.
    assert counter > 10_000, counter
    with ThreadPoolExecutor(2) as pool:
        started = time.perf_counter()
        results = list(pool.map(lambda mu: knotsweep.run(**QUICK, mu=mu), [0.1, 0.1]))
        both = time.perf_counter() - started
    print(f"one case {single:.2f} s, two in two threads {both:.2f} s on {os.cpu_count()} cores")
    for r in results:
        assert np.array_equal(r.series["F_bar"], alone.series["F_bar"])


def test_progress_callback_and_cancel():
    seen = []

    def progress(p):
        seen.append(p)
        return len(seen) < 3

    r = knotsweep.run(**QUICK, progress=progress)
    assert r.status == "cancelled"
    assert len(seen) == 3 and isinstance(seen[0], knotsweep.Progress) and 0 <= seen[0].fraction <= 1


def test_ctrl_c_stops_a_run():
    params = dict(QUICK, min_l_k_bar=60.0, pull_speed=0.003)
    # Python's own Ctrl-C handler, even where the runner started it with
    # SIGINT ignored (a shell's background job).
    previous = signal.signal(signal.SIGINT, signal.default_int_handler)
    timer = threading.Timer(1.0, lambda: os.kill(os.getpid(), signal.SIGINT))
    started = time.perf_counter()
    timer.start()
    try:
        with pytest.raises(KeyboardInterrupt):
            knotsweep.run(**params)
    finally:
        timer.cancel()
        signal.signal(signal.SIGINT, previous)
    assert time.perf_counter() - started < 5.0


def test_parameters_come_in_groups():
    groups = [word for word, _, _ in knotsweep._params.grouped()]
    assert groups == ["knot", "rod", "friction", "loading", "solver"]
    loading = next(p for p in knotsweep.PARAMETERS if p.name == "loading")
    assert (loading.group, loading.kind, loading.default_value) == ("loading", "program", None)
    assert loading.annotation == "Sequence[Mapping[str, Mapping[str, Any]]] | None"
    doc = knotsweep.run.__doc__
    assert doc.index("Knot:") < doc.index("Rod and material:") < doc.index("Solver (advanced):")


def plain(program):
    """A program without its null fields (a release's target, when left out, comes back as null)."""
    return [{k: {f: v for f, v in body.items() if v is not None} for k, body in stage.items()} for stage in program]


def test_a_loading_program_as_a_list_of_dicts():
    program = [{"pull": {"to_l_k_bar": 150.0}}, {"hold": {"seconds": 0.5}}, {"release": {}}]
    assert plain(knotsweep.validate(loading=program)["loading"]) == program
    assert plain(knotsweep.validate(loading=tuple(program))["loading"]) == program
    with pytest.raises(ValueError, match=r"^loading: stage 2 \(hold\): seconds must be in") as e:
        knotsweep.validate(loading=[{"pull": {}}, {"hold": {"seconds": -1.0}}])
    assert e.value.fields[0][0] == "loading"
    with pytest.raises(ValueError, match=r"^loading: "):
        knotsweep.validate(loading=[{"twirl": {}}])
    with pytest.raises(ValueError, match=r"^loading: invalid key 1"):
        knotsweep.validate(loading=[{1: {}}])


def test_tighten_then_loosen_reports_each_stage():
    # QUICK (starting near l_k bar 138) pulled to 132, then loosened back to the start: about QUICK's run.
    r = knotsweep.run(**QUICK, loading=[{"pull": {"to_l_k_bar": 132.0}}, {"release": {}}])
    assert r.completed, r.reason
    assert plain(r.params["loading"]) == [{"pull": {"to_l_k_bar": 132.0}}, {"release": {}}]
    stage = r.series["stage"]
    assert set(np.unique(stage)) == {0, 1}
    lk = r.series["l_k_bar"]
    tight = lk[stage == 0]
    loose = lk[stage == 1]
    assert tight.min() == pytest.approx(132.0, abs=1.0)
    assert loose[-1] > tight.min() + 3, "the release loosens"
    assert {p.stage for p in r.phases} >= {0, 1}
    assert r.phases is r.stages
    assert isinstance(r.events, list) and all(isinstance(e, knotsweep.Event) for e in r.events)
    for e in r.events:
        assert e.direction == ("tighten" if e.stage == 0 else "loosen")
    assert r.hysteresis is None or r.hysteresis.width == pytest.approx(
        r.hysteresis.flip_back_l_k_bar - r.hysteresis.inversion_l_k_bar)
    assert r.quasi_static is None or isinstance(r.quasi_static.holds, bool)


def test_a_snapshot_splits_per_rod():
    """A bend's snapshot lists its rods one after the other; ``rods`` gives
    their node counts and ``per_rod`` splits any per-node array by them; one
    rod is ``[K]``."""
    from knotsweep._run import _snapshot

    shot = {"label": "relaxed", "l_k_bar": 150.0, "points": [[i, 0, 0] for i in range(5)],
            "curvature": [0.0, 1.0, 2.0, 3.0, 4.0], "contacts": []}
    bend = _snapshot({**shot, "rods": [2, 3]})
    assert bend.rods == [2, 3]
    first, second = bend.per_rod()
    assert first.shape == (2, 3) and second.shape == (3, 3) and second[0, 0] == 2.0
    assert bend.per_rod("curvature")[1].tolist() == [2.0, 3.0, 4.0]
    one = _snapshot(shot)
    assert one.rods == [5] and len(one.per_rod()) == 1


def test_a_bends_relaxed_snapshot_starts_a_case_again():
    """A tiny reef knot's relaxed snapshot, split per rod, is a start shape of
    two rods (standing ends pulled, tails free); one rod alone is refused,
    naming the key. Under the default smooth contact its strands' chords may
    lie closer than 2h by their sag: the check measures the smooth curves."""
    tiny = dict(knot="reef", length=0.4, nodes=121, relax_time=0.1, pull_speed=0.01, min_l_k_bar=100.0)
    r = knotsweep.run(**tiny)
    assert r.status == "completed", r.reason
    relaxed = next(s for s in r.snapshots if s.label == "relaxed")
    assert relaxed.rods == [121, 121]
    rods = [{"points": p, "start": "pulled", "finish": "free"} for p in relaxed.per_rod()]
    assert len(knotsweep.validate(**tiny, initial_shape={"rods": rods})["initial_shape"]["rods"]) == 2
    with pytest.raises(ValueError, match=r"initial_shape\.rods"):
        knotsweep.validate(**tiny, initial_shape={"rods": rods[:1]})
