-- A certified sweep's twin relation, stored at submission: on a point's row, the position (in the same sweep) of its
-- refined twin (`solver::certify::refined`). A twin is found through it, not by its cache key, which changes with
-- the physics revision. NULL on the other rows, and on every row of sweeps submitted before this migration (those
-- find their twins by their parameters).
ALTER TABLE sweep_cases ADD COLUMN twin_position BIGINT;

-- The knot's states kept for viewers are snapshots ("frame" names the rods' material frames); the stored data is
-- unchanged.
ALTER TABLE results RENAME COLUMN frames TO snapshots;
