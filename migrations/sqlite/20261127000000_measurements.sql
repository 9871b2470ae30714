-- Measured inversions a researcher put beside a sweep (`PUT /api/sweeps/{id}/measurements`): the points as JSON
-- (`[{"params": {...}, "l_k_bar": ..., "error": ...}]`), drawn on the sweep's phase diagram and curves; an upload
-- replaces the one before.
CREATE TABLE measurements (
    sweep_id INTEGER PRIMARY KEY REFERENCES sweeps (id),
    points TEXT NOT NULL,
    created_at INTEGER NOT NULL
);
