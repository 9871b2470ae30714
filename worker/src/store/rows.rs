//! Decoding stored rows into records, once for every backend: the schema has
//! four column types (integer, real, text, bytes), read through [`Columns`].
use super::codec::{self, CodecError};
use super::*;
use solver::snapshot::Snapshot;
use sqlx::Row;
use sqlx::any::AnyRow;

/// Typed column access of a row (`StoreError`s, not sqlx errors).
pub(crate) trait Columns {
    fn text(&self, column: &str) -> StoreResult<String>;
    fn text_or_null(&self, column: &str) -> StoreResult<Option<String>>;
    fn int(&self, column: &str) -> StoreResult<i64>;
    fn int_or_null(&self, column: &str) -> StoreResult<Option<i64>>;
    fn real(&self, column: &str) -> StoreResult<f64>;
    fn bytes_or_null(&self, column: &str) -> StoreResult<Option<Vec<u8>>>;
}

impl Columns for AnyRow {
    fn text(&self, column: &str) -> StoreResult<String> {
        Ok(self.try_get(column)?)
    }
    fn text_or_null(&self, column: &str) -> StoreResult<Option<String>> {
        Ok(self.try_get(column)?)
    }
    fn int(&self, column: &str) -> StoreResult<i64> {
        Ok(self.try_get(column)?)
    }
    fn int_or_null(&self, column: &str) -> StoreResult<Option<i64>> {
        Ok(self.try_get(column)?)
    }
    fn real(&self, column: &str) -> StoreResult<f64> {
        Ok(self.try_get(column)?)
    }
    fn bytes_or_null(&self, column: &str) -> StoreResult<Option<Vec<u8>>> {
        Ok(self.try_get(column)?)
    }
}

/// Columns of a case with its result summary (`cases c LEFT JOIN results r`).
pub(crate) const CASE_COLUMNS: &str = "c.id, c.case_key, c.solver_version, c.params, c.status, c.attempts, \
    c.max_attempts, c.not_before, c.lease_owner, c.lease_expires_at, c.fence, c.progress, \
    c.progress_detail, c.cancel_requested, c.last_error, c.created_at, c.started_at, c.finished_at, \
    r.outcome, r.reason, r.inversion, r.summary, r.wall_time, r.worker, r.created_at AS result_created_at";

pub(crate) const SWEEP_COLUMNS: &str = "id, name, preset, spec, varied, state, created_at, updated_at";

/// Some active sweep wants case `c` (it may be claimed).
pub(crate) const CLAIMABLE: &str = "EXISTS (SELECT 1 FROM sweep_cases sc JOIN sweeps s ON s.id = sc.sweep_id \
    WHERE sc.case_id = c.id AND s.state = 'active')";

/// Some sweep that is not cancelled (active or paused) still wants case `c`.
pub(crate) const WANTED: &str = "EXISTS (SELECT 1 FROM sweep_cases w JOIN sweeps ws ON ws.id = w.sweep_id \
    WHERE w.case_id = c.id AND ws.state != 'cancelled')";

/// SQL condition: an active sweep (not paused, not cancelled) wants case `c`.
pub(crate) const ACTIVELY_WANTED: &str = "EXISTS (SELECT 1 FROM sweep_cases w JOIN sweeps ws ON ws.id = w.sweep_id \
    WHERE w.case_id = c.id AND ws.state = 'active')";

pub(crate) fn json<T: serde::de::DeserializeOwned>(text: &str, what: &str) -> StoreResult<T> {
    serde_json::from_str(text).map_err(|e| StoreError::Corrupt(format!("{what}: {e}")))
}

pub(crate) fn sweep_from_row(r: &AnyRow) -> StoreResult<SweepRecord> {
    Ok(SweepRecord {
        id: r.int("id")?,
        name: r.text_or_null("name")?,
        preset: r.text_or_null("preset")?,
        spec: json(&r.text("spec")?, "sweep spec")?,
        varied: json(&r.text("varied")?, "sweep varied")?,
        state: SweepState::parse(&r.text("state")?)?,
        created_at: r.int("created_at")?,
        updated_at: r.int("updated_at")?,
    })
}

/// The claim a claimed row (`id, case_key, params, fence, attempts`) gives `owner`.
pub(crate) fn claim_from_row(r: &AnyRow, owner: &str) -> StoreResult<Claim> {
    Ok(Claim {
        lease: Lease {
            case_id: r.int("id")?,
            owner: owner.to_string(),
            fence: r.int("fence")?,
        },
        key: r.text("case_key")?,
        params: json(&r.text("params")?, "case params")?,
        attempt: r.int("attempts")? as u32,
    })
}

pub(crate) fn case_from_row(r: &AnyRow) -> StoreResult<CaseRecord> {
    let result = match r.text_or_null("outcome")? {
        None => None,
        Some(outcome) => Some(ResultSummary {
            outcome,
            reason: r.text("reason")?,
            inversion: r
                .text_or_null("inversion")?
                .map(|t| json(&t, "inversion"))
                .transpose()?,
            summary: json(&r.text("summary")?, "result summary")?,
            wall_time: r.real("wall_time")?,
            worker: r.text("worker")?,
            created_at: r.int("result_created_at")?,
        }),
    };
    Ok(CaseRecord {
        id: r.int("id")?,
        // A retired attempt's row stores `key#id` (`Store::create_sweep`).
        key: {
            let key = r.text("case_key")?;
            key.split_once('#').map_or(key.as_str(), |(k, _)| k).to_string()
        },
        solver_version: r.text("solver_version")?,
        params: json(&r.text("params")?, "case params")?,
        state: CaseState::parse(&r.text("status")?)?,
        attempts: r.int("attempts")? as u32,
        max_attempts: r.int("max_attempts")? as u32,
        not_before: r.int("not_before")?,
        lease_owner: r.text_or_null("lease_owner")?,
        lease_expires_at: r.int_or_null("lease_expires_at")?,
        fence: r.int("fence")?,
        progress: r.real("progress")?,
        progress_detail: r
            .text_or_null("progress_detail")?
            .map(|t| json(&t, "progress"))
            .transpose()?,
        // 2 is a paused sweep's request to hand the case back, not a cancellation.
        cancel_requested: r.int("cancel_requested")? == 1,
        last_error: r.text_or_null("last_error")?,
        created_at: r.int("created_at")?,
        started_at: r.int_or_null("started_at")?,
        finished_at: r.int_or_null("finished_at")?,
        result,
    })
}

/// What a completed report stores: outcome word, summary and inversion (JSON
/// text), the packed series, and the log line. The snapshots are packed by
/// [`packed_snapshots`] once the sweeps' choice is known.
pub(crate) struct StoredResult {
    pub outcome: String,
    pub summary: String,
    pub series: Vec<u8>,
    pub inversion: Option<String>,
    pub message: String,
}

impl StoredResult {
    /// `Conflict` for a cancelled run, which is not a result.
    pub(crate) fn new(report: &CaseReport, worker: &str) -> StoreResult<Self> {
        use solver::protocol::Status;
        if report.status == Status::Cancelled {
            return Err(StoreError::Conflict(
                "a cancelled run is not a result".to_string(),
            ));
        }
        let outcome = report.status.to_string();
        let summary = serde_json::json!({
            "determinant_initial": report.determinant_initial,
            "determinant_final": report.determinant_final,
            "stats": report.stats,
            "events": report.events,
            "hysteresis": report.hysteresis,
            "quasi_static": report.quasi_static,
            "holding_force_bar": report.holding_force_bar,
            "tied": report.tied,
            "scaling": report.scaling,
        });
        let wall = report.stats.wall_time;
        let message = match (&report.inversion, report.reason.is_empty()) {
            (Some(inv), _) => format!(
                "result {outcome} by {worker} in {wall:.2} s: inversion at l_k bar {:.2}",
                inv.l_k_bar
            ),
            (None, true) => format!("result {outcome} by {worker} in {wall:.2} s: no inversion"),
            (None, false) => format!("result {outcome} by {worker} in {wall:.2} s: {}", report.reason),
        };
        Ok(Self {
            outcome,
            summary: summary.to_string(),
            series: codec::pack_series(&report.series),
            inversion: report
                .inversion
                .map(|i| serde_json::to_string(&i).expect("inversion serialises")),
            message,
        })
    }
}

/// The snapshots `choice` keeps, packed.
pub(crate) fn packed_snapshots(snapshots: &[Snapshot], choice: SnapshotChoice) -> Vec<u8> {
    let kept: Vec<Snapshot> = (snapshots.iter())
        .filter(|s| choice.keeps(&s.label))
        .cloned()
        .collect();
    codec::pack_snapshots(&kept)
}

/// A series or snapshots column pair as the API serves it: the packed bytes
/// decoded and written as JSON, or the JSON text of a row stored before the
/// packed columns, as stored.
pub(crate) fn served_json(row: &AnyRow, what: Packed) -> StoreResult<String> {
    let (text, packed) = what.columns();
    let corrupt = |e: CodecError| StoreError::Corrupt(format!("{text}: {e}"));
    match (row.bytes_or_null(packed)?, row.text_or_null(text)?) {
        (Some(bytes), _) => Ok(match what {
            Packed::Series => serde_json::to_string(&codec::unpack_series(&bytes).map_err(corrupt)?),
            Packed::Snapshots => serde_json::to_string(&codec::unpack_snapshots(&bytes).map_err(corrupt)?),
        }
        .expect("decoded values serialise")),
        (None, Some(json)) => Ok(json),
        (None, None) => Err(StoreError::Corrupt(format!("a result without its {text}"))),
    }
}

/// The packed columns of a result.
#[derive(Clone, Copy, Debug)]
pub(crate) enum Packed {
    Series,
    Snapshots,
}

impl Packed {
    /// The JSON text column (rows stored before packing) and the packed one.
    pub(crate) fn columns(self) -> (&'static str, &'static str) {
        match self {
            Self::Series => ("series", "series_packed"),
            Self::Snapshots => ("snapshots", "snapshots_packed"),
        }
    }
}
