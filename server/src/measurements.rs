//! Measured inversions beside a sweep (`PUT /api/sweeps/{id}/measurements`):
//! a researcher's own points, stored with the sweep and drawn on its phase
//! diagram and curves.
use crate::core::Core;
use crate::error::CoreError;
use crate::fit::{MeasuredPoint, check_measured, measured_csv};
use crate::spec::FieldError;
use serde::{Deserialize, Serialize};
use utoipa::ToSchema;

/// Measured points to put beside a sweep: as a list, or as CSV (a header
/// naming the sweep's first varied parameter, `l_k_bar` and `error`; SI units).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, ToSchema)]
#[serde(deny_unknown_fields)]
#[schema(example = json!({"csv": "h,l_k_bar,error\n0.0016,121.5,1.0\n0.0024,95.0,1.5\n"}))]
pub struct MeasurementsBody {
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub points: Option<Vec<MeasuredPoint>>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub csv: Option<String>,
}

impl Core {
    /// Checks and stores measured points beside sweep `id` (replacing any
    /// before): each needs a positive l̄_k and error and, when the sweep
    /// varies a parameter, that parameter's value (its x on the phase diagram).
    pub async fn set_measurements(
        &self,
        id: i64,
        body: MeasurementsBody,
    ) -> Result<Vec<MeasuredPoint>, CoreError> {
        let detail = self.sweep(id).await?;
        let points = match (body.points, body.csv) {
            (Some(points), None) => points,
            (None, Some(csv)) => {
                measured_csv(&csv).map_err(|e| CoreError::Invalid(vec![FieldError::new("csv", e)]))?
            }
            _ => {
                return Err(CoreError::Invalid(vec![FieldError::new(
                    "body",
                    "give either points or csv",
                )]));
            }
        };
        let mut errors = check_measured(&points, "points");
        if points.is_empty() {
            errors.push(FieldError::new("points", "needs at least one measured point"));
        }
        if let Some(axis) = detail.varied.first() {
            for (k, p) in points.iter().enumerate() {
                if !p.params.get(axis).is_some_and(|v| v.is_number() || v.is_string()) {
                    errors.push(FieldError::new(
                        format!("points[{k}].params.{axis}"),
                        format!("needs the sweep's varied parameter {axis} (its x on the phase diagram)"),
                    ));
                }
            }
        }
        if !errors.is_empty() {
            return Err(CoreError::Invalid(errors));
        }
        let json = serde_json::to_string(&points).expect("points serialise");
        self.store().set_measurements(id, &json).await?;
        Ok(points)
    }

    /// The measured points beside sweep `id` (none when nothing was put);
    /// 404 for an unknown sweep.
    pub async fn measurements(&self, id: i64) -> Result<Vec<MeasuredPoint>, CoreError> {
        self.sweep(id).await?;
        match self.store().measurements(id).await? {
            Some(json) => serde_json::from_str(&json)
                .map_err(|e| CoreError::Store(knotsweep_worker::StoreError::Corrupt(e.to_string()))),
            None => Ok(Vec::new()),
        }
    }
}
