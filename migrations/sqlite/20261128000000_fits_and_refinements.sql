-- Fits (`POST /api/fits`) and maps' refinements (`POST /api/sweeps/{id}/refine`): searches over queued cases, each
-- stored whole as its JSON view (specification, status, evaluations, result) at every step, so that they outlive the
-- process that ran them; one still 'running' when its server stops is taken up again when one starts (its cases are
-- cached, so the search replays without computing them again).
CREATE TABLE fits (
    id INTEGER PRIMARY KEY AUTOINCREMENT,
    status TEXT NOT NULL,
    view TEXT NOT NULL,
    created_at INTEGER NOT NULL,
    updated_at INTEGER NOT NULL
);

-- At most one refinement per sweep: a new one replaces the one before.
CREATE TABLE refinements (
    sweep_id INTEGER PRIMARY KEY REFERENCES sweeps (id),
    status TEXT NOT NULL,
    view TEXT NOT NULL,
    created_at INTEGER NOT NULL,
    updated_at INTEGER NOT NULL
);
