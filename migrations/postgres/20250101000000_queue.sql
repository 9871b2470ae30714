-- knotsweep's queue and results on PostgreSQL: the schema of migrations/sqlite in PostgreSQL's types
-- (BIGINT ids and times in Unix milliseconds, DOUBLE PRECISION, JSON as TEXT).

CREATE TABLE sweeps (
    id BIGSERIAL PRIMARY KEY,
    name TEXT,
    preset TEXT,
    spec TEXT NOT NULL,
    varied TEXT NOT NULL,
    state TEXT NOT NULL DEFAULT 'active' CHECK (state IN ('active', 'paused', 'cancelled')),
    idempotency_key TEXT UNIQUE,
    request_hash TEXT,
    created_at BIGINT NOT NULL,
    updated_at BIGINT NOT NULL
);

CREATE TABLE cases (
    id BIGSERIAL PRIMARY KEY,
    case_key TEXT NOT NULL UNIQUE,
    solver_version TEXT NOT NULL,
    params TEXT NOT NULL,
    status TEXT NOT NULL CHECK (status IN ('queued', 'running', 'done', 'failed', 'cancelled')),
    attempts BIGINT NOT NULL DEFAULT 0,
    max_attempts BIGINT NOT NULL,
    not_before BIGINT NOT NULL DEFAULT 0,
    lease_owner TEXT,
    lease_expires_at BIGINT,
    fence BIGINT NOT NULL DEFAULT 0,
    progress DOUBLE PRECISION NOT NULL DEFAULT 0,
    progress_detail TEXT,
    cancel_requested BIGINT NOT NULL DEFAULT 0,
    last_error TEXT,
    created_at BIGINT NOT NULL,
    started_at BIGINT,
    finished_at BIGINT
);
CREATE INDEX cases_claimable ON cases (status, not_before, id);
CREATE INDEX cases_leases ON cases (status, lease_expires_at);

CREATE TABLE sweep_cases (
    sweep_id BIGINT NOT NULL REFERENCES sweeps (id) ON DELETE CASCADE,
    case_id BIGINT NOT NULL REFERENCES cases (id),
    position BIGINT NOT NULL,
    cached BIGINT NOT NULL DEFAULT 0,
    PRIMARY KEY (sweep_id, case_id),
    UNIQUE (sweep_id, position)
);
CREATE INDEX sweep_cases_case ON sweep_cases (case_id);

CREATE TABLE results (
    case_id BIGINT PRIMARY KEY REFERENCES cases (id),
    outcome TEXT NOT NULL,
    reason TEXT NOT NULL,
    inversion TEXT,
    summary TEXT NOT NULL,
    series TEXT NOT NULL,
    frames TEXT NOT NULL,
    wall_time DOUBLE PRECISION NOT NULL,
    worker TEXT NOT NULL,
    fence BIGINT NOT NULL,
    created_at BIGINT NOT NULL
);

CREATE TABLE case_logs (
    id BIGSERIAL PRIMARY KEY,
    case_id BIGINT NOT NULL REFERENCES cases (id),
    at BIGINT NOT NULL,
    level TEXT NOT NULL,
    message TEXT NOT NULL
);
CREATE INDEX case_logs_case ON case_logs (case_id, id);
