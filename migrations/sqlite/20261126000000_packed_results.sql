-- Which snapshots a sweep's results keep: 'all', 'events' (those labelled by an event) or 'none'
-- (`knotsweep_worker::store::SnapshotChoice`). Sweeps stored before this migration kept all.
ALTER TABLE sweeps ADD COLUMN snapshots TEXT NOT NULL DEFAULT 'all' CHECK (snapshots IN ('all', 'events', 'none'));

-- Results keep their series and snapshots packed (`worker/src/store/codec`) in the BLOB columns; the JSON text
-- columns hold those of results stored before this migration and are NULL on packed rows. SQLite cannot drop a NOT
-- NULL constraint: the table is rebuilt, its rows copied as they are.
CREATE TABLE results_packed (
    case_id INTEGER PRIMARY KEY REFERENCES cases (id),
    outcome TEXT NOT NULL,
    reason TEXT NOT NULL,
    inversion TEXT,
    summary TEXT NOT NULL,
    series TEXT,
    snapshots TEXT,
    wall_time REAL NOT NULL,
    worker TEXT NOT NULL,
    fence INTEGER NOT NULL,
    created_at INTEGER NOT NULL,
    series_packed BLOB,
    snapshots_packed BLOB
);
INSERT INTO results_packed (case_id, outcome, reason, inversion, summary, series, snapshots, wall_time, worker, fence,
    created_at)
SELECT case_id, outcome, reason, inversion, summary, series, snapshots, wall_time, worker, fence, created_at
FROM results;
DROP TABLE results;
ALTER TABLE results_packed RENAME TO results;
