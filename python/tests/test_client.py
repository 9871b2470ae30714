"""knotsweep.Client against a `knotsweep serve` started for the tests."""
import numpy as np
import pytest

import knotsweep
from conftest import QUICK, TOKEN, need


@pytest.fixture(scope="module")
def client(server):
    with knotsweep.Client(server, token=TOKEN) as c:
        yield c


def test_submit_wait_and_read_the_phase_diagram(client):
    pd = need("pandas")
    sweep = client.submit(base=QUICK, grid={"mu": [0.1, 0.2]}, name="python test")
    assert sweep.submitted["total"] == 2 and not sweep.submitted["replayed"]
    done = sweep.wait(progress=True, timeout=600)
    assert done["status"] == "done", done
    df = sweep.phase_diagram()
    assert isinstance(df, pd.DataFrame)
    assert list(df["mu"]) == [0.1, 0.2] and list(df["status"]) == ["completed", "completed"]
    assert {"case_id", "l_k_bar", "F_bar_before", "simplified_l_k_bar", "reason"} <= set(df.columns)
    assert df.attrs["varied"] == ["mu"] and df.attrs["complete"]
    cases = sweep.cases()
    assert [c["case_id"] for c in cases] == list(df["case_id"])
    series = sweep.series(cases[0]["case_id"])
    assert len(series) > 10 and "F_bar" in series.columns
    raw = client.series(cases[0]["case_id"], raw=True)
    assert np.array_equal(raw["l_k_bar"], series["l_k_bar"].to_numpy())
    snapshots = client.snapshots(cases[0]["case_id"])
    assert snapshots[0]["points"].shape == (QUICK["nodes"], 3)
    # The service computed what knotsweep.run computes here (its stored series
    # comes back through serde_json's float parser, within one ulp).
    mine = knotsweep.run(**QUICK, mu=0.1)
    assert np.allclose(mine.series["F_bar"], raw["F_bar"], rtol=1e-15, atol=0)


def test_a_certified_sweep_gives_each_point_its_uncertainty(client):
    need("pandas")
    sweep = client.submit(base=QUICK, grid={"mu": [0.3]}, certify=True)
    assert sweep.submitted["total"] == 2, "the point and its refined twin"
    assert sweep.wait(timeout=600)["status"] == "done"
    df = sweep.phase_diagram()
    assert df.attrs["certified"] and len(df) == 1
    assert df.attrs["converged_within"] == client.limits()["converged_within"] > 0
    assert {"refined_l_k_bar", "uncertainty", "relative_uncertainty", "converged"} <= set(df.columns)
    twin = [c for c in sweep.cases() if c["twin_of"] is not None]
    assert [c["twin_of"] for c in twin] == list(df["case_id"])


def test_api_errors_are_exceptions_with_the_apis_words(client, server):
    with pytest.raises(knotsweep.InvalidInput) as e:
        client.submit(base={"mu": -1.0})
    assert isinstance(e.value, ValueError) and e.value.status == 422
    assert e.value.fields == [{"field": "base.mu", "reason": "must be in [0, 2], got -1"}]
    # The binding refuses the same value in the same words.
    with pytest.raises(ValueError) as mine:
        knotsweep.validate(mu=-1.0)
    assert e.value.message == "base." + str(mine.value)
    with pytest.raises(knotsweep.InvalidInput, match="unknown preset"):
        client.submit(preset="fig99")
    with pytest.raises(knotsweep.NotFound):
        client.sweep(999_999).status()
    with pytest.raises(knotsweep.Unauthorized):
        knotsweep.Client(server, token="wrong").submit(preset="fig9")


def test_cancel(client):
    sweep = client.submit(base=dict(QUICK, min_l_k_bar=60.0), grid={"mu": [0.3, 0.4, 0.5]})
    sweep.cancel()
    done = sweep.wait(progress=False, timeout=300)
    assert done["status"] == "cancelled", done
    assert {"fig7", "fig9", "fig11"} <= {p["name"] for p in client.presets()} and any(s["id"] == sweep.id for s in client.sweeps())


def test_submit_carries_a_loading_program(client):
    program = [{"pull": {"to_l_k_bar": 132.0}}, {"release": {}}]
    sweep = client.submit(base=QUICK, loading=program, name="python loading")
    spec = sweep.status()["spec"]
    assert spec["base"]["loading"] == program
    assert spec["base"]["nodes"] == QUICK["nodes"]
    sweep.cancel()
