//! The `impl Store` of a backend, written once: each trait method calls the
//! backend's function of the same concern (`sweeps`, `claims`, `results`).

/// `impl Store for $backend`: every method delegates to the function of the
/// same job in the backend's `sweeps`, `claims` or `results` module, over
/// `&self.pool` (and `&self.retry` where an attempt can be retried). `$own`
/// holds the backend's own methods (`close`; `wait_for_work` where the
/// backend has notifications).
macro_rules! store_impl {
    ($backend:ty, { $($own:tt)* }) => {
        #[async_trait]
        impl Store for $backend {
            async fn create_sweep(&self, sweep: NewSweep) -> StoreResult<CreateOutcome> {
                sweeps::create(&self.pool, &self.retry, sweep).await
            }

            async fn list_sweeps(&self, limit: i64, offset: i64) -> StoreResult<Vec<SweepRecord>> {
                sweeps::list(&self.pool, limit, offset).await
            }

            async fn count_sweeps(&self) -> StoreResult<i64> {
                sweeps::count(&self.pool).await
            }

            async fn get_sweep(&self, id: i64) -> StoreResult<Option<SweepRecord>> {
                sweeps::get(&self.pool, id).await
            }

            async fn sweep_status_counts(&self, ids: RangeInclusive<i64>) -> StoreResult<Vec<(i64, String, i64)>> {
                sweeps::status_counts(&self.pool, ids).await
            }

            async fn sweep_cases(&self, id: i64) -> StoreResult<Vec<SweepCase>> {
                sweeps::cases(&self.pool, id).await
            }

            async fn control_sweep(&self, id: i64, action: SweepAction) -> StoreResult<SweepRecord> {
                sweeps::control(&self.pool, id, action).await
            }

            async fn get_case(&self, id: i64) -> StoreResult<Option<CaseRecord>> {
                results::get_case(&self.pool, id).await
            }

            async fn case_sweeps(&self, id: i64) -> StoreResult<Vec<i64>> {
                results::case_sweeps(&self.pool, id).await
            }

            async fn case_series_json(&self, id: i64) -> StoreResult<Option<String>> {
                results::series_json(&self.pool, id).await
            }

            async fn case_frames_json(&self, id: i64) -> StoreResult<Option<String>> {
                results::frames_json(&self.pool, id).await
            }

            async fn case_logs(&self, id: i64) -> StoreResult<Vec<LogLine>> {
                results::logs(&self.pool, id).await
            }

            async fn append_log(&self, case_id: i64, level: &str, message: &str) -> StoreResult<()> {
                log(&self.pool, case_id, level, message).await
            }

            async fn requeue_expired(&self) -> StoreResult<usize> {
                claims::requeue_expired(&self.pool, &self.retry).await
            }

            async fn claim(&self, owner: &str, lease: Duration) -> StoreResult<Option<Claim>> {
                claims::claim(&self.pool, owner, lease).await
            }

            async fn heartbeat(
                &self,
                lease: &Lease,
                progress: Option<&Progress>,
                extend: Duration,
            ) -> StoreResult<Heartbeat> {
                claims::heartbeat(&self.pool, lease, progress, extend).await
            }

            async fn complete(&self, lease: &Lease, report: &CaseReport) -> StoreResult<bool> {
                results::complete(&self.pool, lease, report).await
            }

            async fn fail_attempt(&self, lease: &Lease, reason: &str) -> StoreResult<FailOutcome> {
                claims::fail_attempt(&self.pool, &self.retry, lease, reason).await
            }

            async fn release(&self, lease: &Lease) -> StoreResult<bool> {
                claims::release(&self.pool, lease).await
            }

            async fn finish_cancelled(&self, lease: &Lease) -> StoreResult<bool> {
                claims::finish_cancelled(&self.pool, lease).await
            }

            async fn status_counts(&self) -> StoreResult<StatusCounts> {
                results::status_counts(&self.pool).await
            }

            async fn queue_depth(&self) -> StoreResult<i64> {
                claims::queue_depth(&self.pool).await
            }

            $($own)*
        }
    };
}
