-- knotsweep's queue and results. Portable SQL (SQLite now, PostgreSQL later):
-- integer ids, times as integer milliseconds since the Unix epoch, JSON as TEXT.

-- A sweep: a submitted base case + grid (or preset), expanded into cases.
CREATE TABLE sweeps (
    id INTEGER PRIMARY KEY AUTOINCREMENT,
    name TEXT,
    preset TEXT,
    -- The submitted specification (JSON), as accepted.
    spec TEXT NOT NULL,
    -- Names of the grid axes, in grid order (JSON array of strings).
    varied TEXT NOT NULL,
    -- 'active': its cases are handed out; 'paused': not handed out (running
    -- ones finish); 'cancelled': terminal.
    state TEXT NOT NULL DEFAULT 'active' CHECK (state IN ('active', 'paused', 'cancelled')),
    -- Idempotency-Key header of the submission and a hash of its body.
    idempotency_key TEXT UNIQUE,
    request_hash TEXT,
    created_at INTEGER NOT NULL,
    updated_at INTEGER NOT NULL
);

-- A case is a queue entry: the cases table IS the queue. One row per distinct
-- (canonical parameters, solver version); sweeps share rows (dedup and cache).
CREATE TABLE cases (
    id INTEGER PRIMARY KEY AUTOINCREMENT,
    -- blake3 of the canonical parameters and the solver version.
    case_key TEXT NOT NULL UNIQUE,
    solver_version TEXT NOT NULL,
    -- Canonical CaseParams JSON.
    params TEXT NOT NULL,
    -- queued -> running -> done | failed | cancelled; running -> queued on
    -- lease expiry, release or a retryable error (with backoff).
    status TEXT NOT NULL CHECK (status IN ('queued', 'running', 'done', 'failed', 'cancelled')),
    attempts INTEGER NOT NULL DEFAULT 0,
    max_attempts INTEGER NOT NULL,
    -- Not handed out before this time (retry backoff).
    not_before INTEGER NOT NULL DEFAULT 0,
    -- The lease: holder, expiry and fencing counter (incremented at every claim).
    lease_owner TEXT,
    lease_expires_at INTEGER,
    fence INTEGER NOT NULL DEFAULT 0,
    -- Progress stored by heartbeats: fraction 0..1 and the solver's Progress (JSON).
    progress REAL NOT NULL DEFAULT 0,
    progress_detail TEXT,
    -- Set when every sweep that wants the case is cancelled; read by heartbeats.
    cancel_requested INTEGER NOT NULL DEFAULT 0,
    -- Why the case failed or was last retried.
    last_error TEXT,
    created_at INTEGER NOT NULL,
    started_at INTEGER,
    finished_at INTEGER
);
CREATE INDEX cases_claimable ON cases (status, not_before, id);
CREATE INDEX cases_leases ON cases (status, lease_expires_at);

-- Which cases a sweep asked for, in grid order.
CREATE TABLE sweep_cases (
    sweep_id INTEGER NOT NULL REFERENCES sweeps (id) ON DELETE CASCADE,
    case_id INTEGER NOT NULL REFERENCES cases (id),
    position INTEGER NOT NULL,
    -- The case already had a result when the sweep was submitted (cache hit).
    cached INTEGER NOT NULL DEFAULT 0,
    PRIMARY KEY (sweep_id, case_id),
    UNIQUE (sweep_id, position)
);
CREATE INDEX sweep_cases_case ON sweep_cases (case_id);

-- The solver's result of a case (any final solver status except cancelled):
-- written once, by the lease holder, in the transaction that marks the case done.
CREATE TABLE results (
    case_id INTEGER PRIMARY KEY REFERENCES cases (id),
    -- The solver's status: completed, invalid, diverged, penetrated, topology_changed.
    outcome TEXT NOT NULL,
    reason TEXT NOT NULL,
    -- The inversion point (JSON) or NULL.
    inversion TEXT,
    -- Determinants, stats (JSON), the series and the frames (JSON arrays).
    summary TEXT NOT NULL,
    series TEXT NOT NULL,
    frames TEXT NOT NULL,
    wall_time REAL NOT NULL,
    worker TEXT NOT NULL,
    fence INTEGER NOT NULL,
    created_at INTEGER NOT NULL
);

-- Per-case log lines (claims, retries, results, cancellations).
CREATE TABLE case_logs (
    id INTEGER PRIMARY KEY AUTOINCREMENT,
    case_id INTEGER NOT NULL REFERENCES cases (id),
    at INTEGER NOT NULL,
    level TEXT NOT NULL,
    message TEXT NOT NULL
);
CREATE INDEX case_logs_case ON case_logs (case_id, id);
