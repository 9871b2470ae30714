-- The claim reads the lowest queued id: a partial index holds exactly the queued rows in id order, so a claim does
-- not scan or sort the finished ones (and skips locked rows cheaply).
CREATE INDEX cases_queued ON cases (id) WHERE status = 'queued';
