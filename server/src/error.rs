//! Errors of the core and their HTTP form: `{"error": kind, "message": text,
//! "fields": [{"field", "reason"}]}` with 400 (malformed), 401 (token), 404,
//! 409 (conflict), 413 (body too large), 422 (invalid values) or 503 (store).
use crate::spec::FieldError;
use axum::http::StatusCode;
use axum::response::{IntoResponse, Response};
use knotsweep_worker::StoreError;
use serde::{Deserialize, Serialize};
use utoipa::ToSchema;

/// An error of the core.
#[derive(Debug, thiserror::Error)]
pub enum CoreError {
    /// Well-formed input with invalid values (422).
    #[error("invalid input")]
    Invalid(Vec<FieldError>),
    /// Malformed input (400).
    #[error("{1}")]
    BadRequest(String, String),
    #[error("{0} not found")]
    NotFound(String),
    #[error("{0}")]
    Conflict(String),
    #[error("storage: {0}")]
    Store(StoreError),
    /// A figure or an archive could not be made (500).
    #[error("figure: {0}")]
    Figure(String),
}

impl From<StoreError> for CoreError {
    fn from(e: StoreError) -> Self {
        match e {
            StoreError::Conflict(m) => Self::Conflict(m),
            StoreError::NotFound => Self::NotFound("resource".to_string()),
            other => Self::Store(other),
        }
    }
}

/// The JSON body of every error response.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, ToSchema)]
pub struct ErrorBody {
    /// `invalid_input`, `bad_request`, `unauthorized`, `not_found`,
    /// `conflict`, `payload_too_large`, `unavailable`.
    pub error: String,
    pub message: String,
    /// The offending fields (may be empty).
    pub fields: Vec<FieldError>,
}

/// An HTTP error.
#[derive(Debug)]
pub struct ApiError {
    pub status: StatusCode,
    pub body: ErrorBody,
}

impl ApiError {
    pub fn new(status: StatusCode, error: &str, message: impl Into<String>, fields: Vec<FieldError>) -> Self {
        Self {
            status,
            body: ErrorBody {
                error: error.to_string(),
                message: message.into(),
                fields,
            },
        }
    }

    pub fn bad_request(field: &str, reason: impl Into<String>) -> Self {
        let reason = reason.into();
        Self::new(
            StatusCode::BAD_REQUEST,
            "bad_request",
            reason.clone(),
            vec![FieldError::new(field, reason)],
        )
    }

    pub fn unauthorized() -> Self {
        Self::new(
            StatusCode::UNAUTHORIZED,
            "unauthorized",
            "this request needs the header Authorization: Bearer <KNOTSWEEP_TOKEN>",
            vec![FieldError::new("Authorization", "missing or wrong bearer token")],
        )
    }
}

impl From<CoreError> for ApiError {
    fn from(e: CoreError) -> Self {
        match e {
            CoreError::Invalid(fields) => {
                let message = fields
                    .iter()
                    .map(|f| format!("{}: {}", f.field, f.reason))
                    .collect::<Vec<_>>()
                    .join("; ");
                Self::new(StatusCode::UNPROCESSABLE_ENTITY, "invalid_input", message, fields)
            }
            CoreError::BadRequest(field, reason) => Self::bad_request(&field, reason),
            CoreError::NotFound(what) => Self::new(
                StatusCode::NOT_FOUND,
                "not_found",
                format!("{what} not found"),
                vec![],
            ),
            CoreError::Conflict(m) => Self::new(StatusCode::CONFLICT, "conflict", m, vec![]),
            CoreError::Figure(m) => {
                tracing::error!(error = %m, "figure failed");
                Self::new(
                    StatusCode::INTERNAL_SERVER_ERROR,
                    "internal",
                    format!("figure: {m}"),
                    vec![],
                )
            }
            CoreError::Store(e) => {
                tracing::error!(error = %e, "store error");
                Self::new(
                    StatusCode::SERVICE_UNAVAILABLE,
                    "unavailable",
                    format!("storage error: {e}"),
                    vec![],
                )
            }
        }
    }
}

impl IntoResponse for ApiError {
    fn into_response(self) -> Response {
        let mut response = (self.status, axum::Json(self.body)).into_response();
        if self.status == StatusCode::UNAUTHORIZED {
            response.headers_mut().insert(
                axum::http::header::WWW_AUTHENTICATE,
                axum::http::HeaderValue::from_static("Bearer"),
            );
        }
        response
    }
}
