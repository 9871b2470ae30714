//! Errors of the core and their HTTP form: `{"error": kind, "message": text,
//! "fields": [{"field", "reason"}]}` with 400 (malformed), 401 (token), 404,
//! 409 (conflict), 413 (body too large), 422 (invalid values), 429 (too many
//! event streams) or 503 (store). A store's or the server's own failure is
//! logged with its detail and answered without it.
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
    #[error("{field}: {reason}")]
    BadRequest { field: String, reason: String },
    #[error("{0} not found")]
    NotFound(String),
    #[error("{0}")]
    Conflict(String),
    /// Over a per-client or per-sweep cap (429).
    #[error("{0}")]
    TooMany(String),
    #[error("storage: {0}")]
    Store(StoreError),
    /// A figure or an archive could not be made (500).
    #[error("figure: {0}")]
    Figure(String),
    /// A computation of the server's own failed (500; the detail is logged).
    #[error("internal: {0}")]
    Internal(String),
}

impl CoreError {
    /// Malformed input (400) at `field`.
    pub fn bad_request(field: impl Into<String>, reason: impl Into<String>) -> Self {
        Self::BadRequest {
            field: field.into(),
            reason: reason.into(),
        }
    }
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
    /// `invalid_input`, `bad_request`, `unauthorized`, `forbidden`,
    /// `not_found`, `method_not_allowed`, `conflict`, `request_timeout`,
    /// `payload_too_large`, `unsupported_media_type`, `too_many_requests`,
    /// `internal`, `unavailable`.
    pub error: String,
    pub message: String,
    /// The offending fields (may be empty).
    #[schema(schema_with = crate::openapi::field_errors)]
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
            CoreError::BadRequest { field, reason } => Self::bad_request(&field, reason),
            CoreError::NotFound(what) => Self::new(
                StatusCode::NOT_FOUND,
                "not_found",
                format!("{what} not found"),
                vec![],
            ),
            CoreError::Conflict(m) => Self::new(StatusCode::CONFLICT, "conflict", m, vec![]),
            CoreError::TooMany(m) => Self::new(StatusCode::TOO_MANY_REQUESTS, "too_many_requests", m, vec![]),
            CoreError::Figure(m) => {
                tracing::error!(error = %m, "figure failed");
                Self::new(
                    StatusCode::INTERNAL_SERVER_ERROR,
                    "internal",
                    format!("figure: {m}"),
                    vec![],
                )
            }
            CoreError::Internal(m) => {
                tracing::error!(error = %m, "internal error");
                Self::new(
                    StatusCode::INTERNAL_SERVER_ERROR,
                    "internal",
                    "the server failed to answer this request; its log has the detail",
                    vec![],
                )
            }
            CoreError::Store(e) => {
                tracing::error!(error = %e, "store error");
                Self::new(
                    StatusCode::SERVICE_UNAVAILABLE,
                    "unavailable",
                    "the database is unavailable; try again later (the server's log has the detail)",
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
