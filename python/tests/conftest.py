"""Shared fixtures: the `knotsweep` binary the Python results are compared
with and the server the client talks to. `KNOTSWEEP_BIN` names the binary
(.ci/run sets it); without it the usual cargo target directories are
searched. A test whose prerequisite (the binary, pandas) is missing is
skipped, or fails when the environment variable CI is set (`missing`)."""
import importlib
import os
import re
import shutil
import subprocess
import time
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]

# A case of a few seconds: one pass on a short rod, pulled fast at a constant speed (the solver's doc-test case,
# under the reference protocol, so that its length scales with the pull).
QUICK = dict(n=1, length=0.3, nodes=102, relax_time=0.1, pull_speed=0.01, min_l_k_bar=130.0, protocol="reference")


def missing(why):
    """A prerequisite of the calling test is missing: it fails when CI is set
    (CI sets it, and .ci/run installs every prerequisite), else it is skipped."""
    if os.environ.get("CI"):
        pytest.fail(f"{why} (CI is set: a missing prerequisite fails the test)")
    pytest.skip(why)


def need(module):
    """The module, imported, or `missing`."""
    try:
        return importlib.import_module(module)
    except ImportError as e:
        missing(f"no {module} module ({e})")


def _binary():
    given = os.environ.get("KNOTSWEEP_BIN")
    if given:
        if not os.access(given, os.X_OK):
            pytest.fail(f"KNOTSWEEP_BIN={given} is not an executable")
        return given
    targets = [os.environ.get("CARGO_TARGET_DIR"), ROOT / "target"]
    for target in filter(None, targets):
        for profile in ("release", "debug"):
            path = Path(target) / profile / "knotsweep"
            if path.is_file():
                return str(path)
    return shutil.which("knotsweep")


@pytest.fixture(scope="session")
def knotsweep_bin():
    path = _binary()
    if not path:
        missing("no knotsweep binary: set KNOTSWEEP_BIN or `cargo build --release`")
    return path


TOKEN = "python-test-token"


@pytest.fixture(scope="session")
def server(knotsweep_bin, tmp_path_factory):
    """A `knotsweep serve` on a free loopback port with a scratch SQLite
    database and two workers, requiring TOKEN; yields its URL."""
    db = tmp_path_factory.mktemp("serve") / "ks.sqlite"
    env = {**os.environ, "KNOTSWEEP_TOKEN": TOKEN, "RUST_LOG": "warn"}
    env.pop("DATABASE_URL", None)
    proc = subprocess.Popen(
        [knotsweep_bin, "serve", "--addr", "127.0.0.1:0", "--database-url", f"sqlite://{db}", "--workers", "2"],
        stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True, env=env,
    )
    url, seen, deadline = None, [], time.monotonic() + 60
    while url is None and time.monotonic() < deadline:
        line = proc.stdout.readline()
        if not line:
            break
        seen.append(line)
        m = re.search(r"serving on (http://\S+)", line)
        if m:
            url = m.group(1)
    if url is None:
        proc.kill()
        pytest.fail("knotsweep serve did not start:\n" + "".join(seen))
    # Keep draining its output so that it never blocks on a full pipe.
    import threading

    threading.Thread(target=lambda: [None for _ in proc.stdout], daemon=True).start()
    yield url
    proc.terminate()
    try:
        proc.wait(timeout=30)
    except subprocess.TimeoutExpired:
        proc.kill()
