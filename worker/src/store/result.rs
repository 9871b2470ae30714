//! A stored result's small part, typed as the store writes and reads it:
//! [`ResultSummary`] (the `results` row without the series and snapshots)
//! and its [`ResultDetails`] (the `summary` column's JSON object).
use serde::{Deserialize, Serialize};
use solver::measurements::Inversion;
use solver::protocol::{CaseReport, Event, Hysteresis, QuasiStatic, Scaling, Stats, Status};

/// The small part of a result.
#[derive(Clone, Debug, PartialEq)]
pub struct ResultSummary {
    /// The solver's status (never `cancelled`: a cancelled run is no result).
    pub outcome: Status,
    pub reason: String,
    pub inversion: Option<Inversion>,
    /// Determinants, statistics, events.
    pub summary: ResultDetails,
    pub wall_time: f64,
    pub worker: String,
    pub created_at: i64,
}

/// A result's determinants, statistics and events: the `summary` column, as
/// the API serves it. Fields a result stored before them lacks read as
/// empty.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct ResultDetails {
    /// Knot determinant of the start shape and at the end.
    pub determinant_initial: Option<u64>,
    pub determinant_final: Option<u64>,
    #[serde(default)]
    pub stats: Stats,
    #[serde(default)]
    pub events: Vec<Event>,
    pub hysteresis: Option<Hysteresis>,
    pub quasi_static: Option<QuasiStatic>,
    /// A bend's holding force (F bar) and whether its rods still hold each
    /// other at the end; none for a knot in one rod.
    #[serde(default)]
    pub holding_force_bar: Option<f64>,
    #[serde(default)]
    pub tied: Option<bool>,
    pub scaling: Option<Scaling>,
    /// A hitch's cylinder (centre, axis, radius, length; m), for viewers;
    /// none for a knot without one.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub cylinder: Option<solver::contact::Cylinder>,
}

impl From<&CaseReport> for ResultDetails {
    fn from(report: &CaseReport) -> Self {
        Self {
            determinant_initial: report.determinant_initial,
            determinant_final: report.determinant_final,
            stats: report.stats,
            events: report.events.clone(),
            hysteresis: report.hysteresis,
            quasi_static: report.quasi_static,
            holding_force_bar: report.holding_force_bar,
            tied: report.tied,
            scaling: report.scaling,
            cylinder: report.cylinder,
        }
    }
}
