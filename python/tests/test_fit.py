"""Client.fit against a `knotsweep serve` started for the tests: a point the
tool made itself at a known mu comes back inside the fit's interval, a fit
followed without waiting, and bad fits refused in the API's words."""
import pytest

import knotsweep
from conftest import QUICK, TOKEN

# The paper's rod (n = 3, h = 1.6 mm): its inversion grows smoothly with mu (l_k bar 139.30 at mu = 0.2, 142.59 at
# 0.3: `knotsweep run --mu 0.2`); the short rods of the other tests invert too erratically with mu to fit.
PAPER = {}
TRUTH = 0.3


@pytest.fixture(scope="module")
def client(server):
    with knotsweep.Client(server, token=TOKEN) as c:
        yield c


def made_at(client, mu):
    """The inversion l_k bar the service computes for the paper's rod at mu."""
    sweep = client.submit(base=dict(PAPER, mu=mu), name=f"made at mu = {mu}")
    assert sweep.wait(progress=False, timeout=600)["status"] == "done"
    point = sweep.phase_diagram(raw=True)["points"][0]
    assert point["inversion"] is not None, point
    return point["inversion"]["l_k_bar"]


def test_fit_recovers_the_mu_that_made_a_point(client):
    l_k_bar = made_at(client, TRUTH)
    fit = client.fit([{"params": {}, "l_k_bar": l_k_bar, "error": 1.0}], range=(0.25, 0.35), base=PAPER,
                     tolerance=0.005, name="python fit", timeout=1200, poll=0.5)
    assert fit["status"] == "done", fit
    low, high = fit["interval"]
    assert low <= TRUTH <= high and low <= fit["value"] <= high, fit
    # Its evaluations ran as sweeps of the queue, and the fit is stored: listed and read back the same.
    assert fit["sweeps"] and all(client.sweep(s).status()["status"] == "done" for s in fit["sweeps"])
    assert client.fit_status(fit["id"]) == fit
    # The simulated l_k bar at each end of the range brackets the measurement.
    ends = sorted(fit["evaluations"][:2], key=lambda e: e["value"])
    simulated = [e["points"][0]["l_k_bar"] for e in ends]
    assert [e["value"] for e in ends] == [0.25, 0.35]
    assert min(simulated) <= l_k_bar <= max(simulated), simulated


def test_fit_without_waiting_is_followed_by_its_id(client):
    fit = client.fit([{"params": {}, "l_k_bar": 120.0, "error": 1.0}], range=(0.1, 0.3), base=QUICK, wait=False)
    assert fit["status"] == "running" and fit["value"] is None
    assert client.fit_status(fit["id"])["id"] == fit["id"]


def test_bad_fits_raise_with_the_fields(client):
    with pytest.raises(knotsweep.InvalidInput) as e:
        client.fit([], range=(0.4, 0.05))
    assert [f["field"] for f in e.value.fields] == ["range", "points"]
    with pytest.raises(knotsweep.InvalidInput) as e:
        client.fit([{"params": {"mu": 0.2}, "l_k_bar": 120.0, "error": -1.0}])
    assert {f["field"] for f in e.value.fields} == {"points[0].params.mu", "points[0].error"}
    with pytest.raises(knotsweep.NotFound):
        client.fit_status(999_999)
