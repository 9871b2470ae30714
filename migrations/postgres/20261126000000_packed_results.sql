-- Which snapshots a sweep's results keep: 'all', 'events' (those labelled by an event) or 'none'
-- (`knotsweep_worker::store::SnapshotChoice`). Sweeps stored before this migration kept all.
ALTER TABLE sweeps ADD COLUMN snapshots TEXT NOT NULL DEFAULT 'all' CHECK (snapshots IN ('all', 'events', 'none'));

-- Results keep their series and snapshots packed (`worker/src/store/codec`) in the BYTEA columns; the JSON text
-- columns hold those of results stored before this migration and are NULL on packed rows.
ALTER TABLE results
    ALTER COLUMN series DROP NOT NULL,
    ALTER COLUMN snapshots DROP NOT NULL,
    ADD COLUMN series_packed BYTEA,
    ADD COLUMN snapshots_packed BYTEA;
