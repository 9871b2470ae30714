//! Axum extractors of the API's inputs, each refusing with the API's error
//! ([`ApiError`]): a numeric path id, a page of a list, and a submission (the
//! `Idempotency-Key` header and a sweep specification read strictly from the
//! body).
use crate::core::Core;
use crate::error::ApiError;
use crate::spec::{FieldError, Limits, SweepSpec};
use axum::body::Bytes;
use axum::extract::rejection::BytesRejection;
use axum::extract::{FromRef, FromRequest, FromRequestParts, Path, Query, Request};
use axum::http::request::Parts;
use axum::http::{HeaderMap, StatusCode};
use serde_json::Value;

/// A numeric path id; anything else is a 400 naming the field.
pub struct Id(pub i64);

impl<S: Send + Sync> FromRequestParts<S> for Id {
    type Rejection = ApiError;

    async fn from_request_parts(parts: &mut Parts, state: &S) -> Result<Self, Self::Rejection> {
        match Path::<i64>::from_request_parts(parts, state).await {
            Ok(Path(id)) => Ok(Id(id)),
            Err(e) => Err(ApiError::bad_request(
                "id",
                format!("must be an integer ({})", e.body_text()),
            )),
        }
    }
}

/// Largest `limit` of a paginated list.
pub const MAX_PAGE: usize = 1000;
/// Largest `offset` of a paginated list (the stores count in `i64`).
pub const MAX_OFFSET: usize = i64::MAX as usize;

/// One page of a list (`GET /api/sweeps`, `GET /api/sweeps/{id}/cases`).
#[derive(serde::Deserialize, utoipa::IntoParams)]
pub struct Page {
    /// Items per page, 1..=1000 (default 100).
    limit: Option<usize>,
    /// Items to skip, in the list's order (default 0, at most 2^63 - 1).
    offset: Option<usize>,
}

/// The page asked for: `limit` in 1..=[`MAX_PAGE`] (default 100), `offset`
/// in 0..=[`MAX_OFFSET`] (default 0); a malformed query or a number out of
/// range is a 400.
#[derive(Clone, Copy)]
pub struct Paging {
    pub limit: usize,
    pub offset: usize,
}

impl<S: Send + Sync> FromRequestParts<S> for Paging {
    type Rejection = ApiError;

    async fn from_request_parts(parts: &mut Parts, state: &S) -> Result<Self, Self::Rejection> {
        let Query(page) = Query::<Page>::from_request_parts(parts, state)
            .await
            .map_err(|e| ApiError::bad_request("query", e.body_text()))?;
        let limit = page.limit.unwrap_or(100);
        if !(1..=MAX_PAGE).contains(&limit) {
            return Err(ApiError::bad_request(
                "limit",
                format!("must be in 1..={MAX_PAGE}, got {limit}"),
            ));
        }
        let offset = page.offset.unwrap_or(0);
        if offset > MAX_OFFSET {
            return Err(ApiError::bad_request(
                "offset",
                format!("must be in 0..={MAX_OFFSET}, got {offset}"),
            ));
        }
        Ok(Self { limit, offset })
    }
}

/// A sweep submission: the `Idempotency-Key` header, if given, and the sweep
/// specification read strictly from the body. Faults are answered in this
/// order (after the media type, which [`crate::guard`] checks first: 415
/// unless `application/json`): the body's size and pace (413 beyond
/// [`Limits::max_body_bytes`], 408 when it does not arrive in time, 400 when
/// cut short), the header (400 when given twice or not visible ASCII; its
/// length and characters are the core's to check), then the JSON
/// ([`Core::parse_spec`]: 400 when malformed or naming a key twice, 422 for
/// unknown fields and wrong types). `raw` is the parsed body (for the
/// idempotency hash).
pub struct Submission {
    pub idempotency_key: Option<String>,
    pub spec: SweepSpec,
    pub raw: Value,
}

impl<S: Send + Sync> FromRequest<S> for Submission
where
    Limits: FromRef<S>,
{
    type Rejection = ApiError;

    async fn from_request(request: Request, state: &S) -> Result<Self, Self::Rejection> {
        let limit = Limits::from_ref(state).max_body_bytes;
        let idempotency_key = idempotency_key(request.headers());
        let body = Bytes::from_request(request, state)
            .await
            .map_err(|e| unreadable(e, limit))?;
        let idempotency_key = idempotency_key?;
        let (spec, raw) = Core::parse_spec(&body)?;
        Ok(Self {
            idempotency_key,
            spec,
            raw,
        })
    }
}

/// The `Idempotency-Key` header: at most once, visible ASCII.
fn idempotency_key(headers: &HeaderMap) -> Result<Option<String>, ApiError> {
    let mut given = headers.get_all("idempotency-key").iter();
    let (first, second) = (given.next(), given.next());
    if second.is_some() {
        return Err(ApiError::bad_request("Idempotency-Key", "given more than once"));
    }
    first
        .map(|v| v.to_str().map(str::to_string))
        .transpose()
        .map_err(|_| ApiError::bad_request("Idempotency-Key", "must be printable ASCII"))
}

/// A body that could not be read: too large (413), too slow (408) or cut
/// short (400).
fn unreadable(e: BytesRejection, limit: usize) -> ApiError {
    let (status, kind, reason) = if timed_out(&e) {
        (
            StatusCode::REQUEST_TIMEOUT,
            "request_timeout",
            "the body did not arrive in time".to_string(),
        )
    } else if e.status() == StatusCode::PAYLOAD_TOO_LARGE {
        (
            e.status(),
            "payload_too_large",
            format!("{} (limit {limit} bytes)", e.body_text()),
        )
    } else {
        (e.status(), "bad_request", e.body_text())
    };
    ApiError::new(
        status,
        kind,
        reason.clone(),
        vec![FieldError::new("body", reason)],
    )
}

/// The body's read timed out (`RequestBodyTimeoutLayer`).
fn timed_out(e: &BytesRejection) -> bool {
    let mut source: Option<&(dyn std::error::Error + 'static)> = Some(e);
    while let Some(error) = source {
        if error.is::<tower_http::timeout::TimeoutError>() {
            return true;
        }
        source = error.source();
    }
    false
}
