//! HTTP adapters over [`Core`]: extract, call, serialise. Routes:
//!
//! | route | what |
//! | --- | --- |
//! | `GET /` | the web page (`web/`): sweeps, the submission form, curves and phase diagrams, cases, fits |
//! | `GET /healthz` | health (503 when degraded) |
//! | `GET /metrics` | Prometheus text |
//! | `GET /api/openapi.json`, `GET /api/docs` | OpenAPI document, Swagger UI (embedded, offline) |
//! | `GET /api/presets` | the presets with their full definitions |
//! | `GET /api/limits` | the limits below and the certification threshold |
//! | `GET /api/materials` | the named materials (E, rho, nu and their source) |
//! | `POST /api/sweeps` | submit (`Idempotency-Key` header honoured) |
//! | `GET /api/sweeps`, `GET /api/sweeps/{id}` | list, detail (counts, progress, ETA) |
//! | `POST /api/sweeps/{id}/pause`, `/resume`, `/cancel` | control |
//! | `GET /api/sweeps/{id}/events` | server-sent progress events |
//! | `GET /api/sweeps/{id}/phase-diagram` | inversion points of the sweep's cases |
//! | `GET /api/sweeps/{id}/phase-diagram.csv` | the same, one row per point (`report::tables`) |
//! | `GET`, `PUT /api/sweeps/{id}/measurements` | measured inversions beside the sweep (`crate::measurements`) |
//! | `POST /api/sweeps/{id}/refine`, `GET /api/sweeps/{id}/refinement` | bisect the grid lines where the outcome changes (`crate::refine`) |
//! | `POST /api/fits`, `GET /api/fits`, `GET /api/fits/{id}` | fit a parameter to measured inversions (`crate::fit`) |
//! | `GET /api/cases/{id}`, `/series.csv`, `/snapshots` | a case, its series as CSV, its snapshots |
//! | `GET /api/cases/{id}/snapshots.zip` | its snapshots for ParaView (`.pvd` over `.vtp` files, docs/PARAVIEW.md) |
//!
//! Limits: request bodies of at most [`Limits::max_body_bytes`] (413 beyond),
//! at most [`Limits::max_cases`] cases per sweep (422 beyond). With a token
//! configured (`KNOTSWEEP_TOKEN`), every request other than GET/HEAD/OPTIONS
//! needs `Authorization: Bearer <token>` (401 otherwise). Every POST, token
//! or not, passes the cross-site guards of [`crate::guard`] (415, 403), and
//! every answer carries its security headers.
use crate::core::Core;
use crate::error::{ApiError, ErrorBody};
use crate::events::Feeds;
use crate::extract::{Id, MAX_PAGE, Page, Paging, Submission};
use crate::fit::{Evaluation, FitSpec, FitStatus, FitView, MeasuredPoint, Simulated};
use crate::guard::{self, AllowedHosts};
use crate::measurements::MeasurementsBody;
use crate::refine::{Bracket, End, Outcome, RefineSpec, RefineStatus, RefinedPoint, RefinementView};
use crate::spec::{Limits, Preset, SweepSpec};
use crate::views::*;
use axum::extract::{ConnectInfo, DefaultBodyLimit, FromRef, Path, Query, Request, State};
use axum::http::{HeaderValue, Method, StatusCode, header};
use axum::middleware::Next;
use axum::response::sse::{Event, KeepAlive, Sse};
use axum::response::{Html, IntoResponse, Response};
use axum::routing::{get, post};
use axum::{Extension, Json, Router};
use futures_util::{Stream, StreamExt};
use knotsweep_worker::store::SweepAction;
use report::charts::Quantity;
use std::convert::Infallible;
use std::net::{IpAddr, Ipv4Addr, SocketAddr};
use std::time::Duration;
use utoipa::openapi::security::{HttpAuthScheme, HttpBuilder, SecurityRequirement, SecurityScheme};
use utoipa::openapi::{OpenApi as OpenApiDoc, RefOr};
use utoipa::{Modify, OpenApi};
use utoipa_swagger_ui::SwaggerUi;

/// Shared state of the handlers.
#[derive(Clone)]
pub struct App {
    pub core: Core,
    /// Bearer token required for mutating requests.
    pub token: Option<String>,
    /// Host names a `POST` may name ([`crate::guard`]).
    pub allowed_hosts: AllowedHosts,
    /// The sweeps' event feeds.
    pub feeds: Feeds,
    /// Time allowed for a request's body (408 beyond).
    pub body_read_timeout: Duration,
}

impl FromRef<App> for Limits {
    fn from_ref(app: &App) -> Self {
        *app.core.limits()
    }
}

impl FromRef<App> for AllowedHosts {
    fn from_ref(app: &App) -> Self {
        app.allowed_hosts.clone()
    }
}

/// The router with every route, the auth layer and the body limit.
pub fn router(app: App) -> Router {
    let limits: Limits = *app.core.limits();
    let api = Router::new()
        .route("/", get(index))
        .route("/assets/app.js", get(app_js))
        .route("/assets/app.css", get(app_css))
        .route("/healthz", get(healthz))
        .route("/metrics", get(metrics))
        .route("/api/presets", get(list_presets))
        .route("/api/limits", get(get_limits))
        .route("/api/materials", get(list_materials))
        .route("/api/sweeps", post(submit_sweep).get(list_sweeps))
        .route("/api/sweeps/{id}", get(get_sweep))
        .route("/api/sweeps/{id}/cases", get(sweep_cases))
        .route("/api/sweeps/{id}/pause", post(pause_sweep))
        .route("/api/sweeps/{id}/resume", post(resume_sweep))
        .route("/api/sweeps/{id}/cancel", post(cancel_sweep))
        .route("/api/sweeps/{id}/events", get(sweep_events))
        .route("/api/sweeps/{id}/phase-diagram", get(phase_diagram))
        .route("/api/sweeps/{id}/phase-diagram.csv", get(phase_diagram_csv))
        .route(
            "/api/sweeps/{id}/measurements",
            get(get_measurements).put(put_measurements),
        )
        .route("/api/sweeps/{id}/refine", post(refine_sweep))
        .route("/api/sweeps/{id}/refinement", get(get_refinement))
        .route("/api/fits", post(submit_fit).get(list_fits))
        .route("/api/fits/{id}", get(get_fit))
        .route("/api/cases/{id}", get(get_case))
        .route("/api/cases/{id}/series.csv", get(case_series_csv))
        .route("/api/cases/{id}/snapshots", get(case_snapshots))
        .route("/api/cases/{id}/snapshots.zip", get(case_snapshots_zip))
        .route("/api/cases/{id}/figures/{figure}", get(case_figure))
        .route("/api/sweeps/{id}/figures/{figure}", get(sweep_figure))
        .merge(SwaggerUi::new("/api/docs").url("/api/openapi.json", openapi(app.token.is_some())))
        .fallback(not_found)
        .layer(axum::middleware::from_fn(json_errors))
        .layer(DefaultBodyLimit::max(limits.max_body_bytes))
        .layer(tower_http::timeout::RequestBodyTimeoutLayer::new(
            app.body_read_timeout,
        ))
        .layer(axum::middleware::from_fn_with_state(app.clone(), auth))
        .layer(axum::middleware::from_fn_with_state(
            app.clone(),
            guard::cross_site,
        ))
        .layer(axum::middleware::from_fn(guard::security_headers))
        .layer(tower_http::trace::TraceLayer::new_for_http());
    api.with_state(app)
}

/// The OpenAPI document; with `token`, its `POST` routes require the bearer
/// token (without, they require nothing).
pub fn openapi(token: bool) -> OpenApiDoc {
    let mut doc = ApiDoc::openapi();
    let required = token.then(|| vec![SecurityRequirement::new("bearer", Vec::<String>::new())]);
    for item in doc.paths.paths.values_mut() {
        if let Some(post) = &mut item.post {
            post.security = required.clone();
        }
    }
    doc
}

#[derive(OpenApi)]
#[openapi(
    info(
        title = "knotsweep",
        description = "Sweeps of overhand-knot tightening simulations (\"Snap buckling of overhand knots\"): \
            submit a base case and a grid (or a preset reproducing the paper's Figs 7, 9, 11), follow the \
            progress and download the phase diagram (inversion point per case). \n\n\
            Limits: request bodies and cases per sweep as `GET /api/limits` serves them (413, 422), parameter \
            ranges as documented on CaseParams (422 with the field and reason). With KNOTSWEEP_TOKEN set on the \
            server, POST requests need `Authorization: Bearer <token>` (401)."
    ),
    paths(
        submit_sweep, list_sweeps, get_sweep, sweep_cases, sweep_figure, case_figure, pause_sweep, resume_sweep, cancel_sweep, sweep_events,
        phase_diagram, phase_diagram_csv, get_measurements, put_measurements, refine_sweep, get_refinement, submit_fit, list_fits, get_fit, get_case, case_series_csv, case_snapshots, case_snapshots_zip, list_presets, get_limits, list_materials, healthz, metrics
    ),
    components(schemas(
        SweepSpec, ErrorBody, Preset, SweepStatus, SweepSummary, SweepDetail, SweepCaseView,
        SubmitResponse, PhaseDiagram, PhasePoint, UncertaintyView, InversionPoint, CaseProgress, CaseDetail, ResultView,
        LogLineView, Health, SweepEvent, RunningCase, ServiceLimits, MaterialView,
        MeasurementsBody, FitSpec, MeasuredPoint, FitView, FitStatus, Evaluation, Simulated,
        RefineSpec, RefinementView, RefineStatus, Outcome, End, Bracket, RefinedPoint
    )),
    modifiers(&Extras),
    tags(
        (name = "sweeps", description = "Submit and follow sweeps"),
        (name = "cases", description = "Cases and their results"),
        (name = "fits", description = "Fit a parameter to measured inversions"),
        (name = "service", description = "Health, metrics, presets")
    )
)]
struct ApiDoc;

struct Extras;

impl Modify for Extras {
    fn modify(&self, openapi: &mut OpenApiDoc) {
        let components = openapi.components.get_or_insert_with(Default::default);
        let mut params = crate::openapi::case_params_schema();
        if let utoipa::openapi::schema::Schema::Object(object) = &mut params {
            object
                .extensions
                .get_or_insert_with(Default::default)
                .merge(form_layout());
        }
        components
            .schemas
            .insert("CaseParams".to_string(), RefOr::T(params));
        components.schemas.insert(
            "FieldError".to_string(),
            RefOr::T(crate::openapi::field_error_schema()),
        );
        components.schemas.insert(
            "SnapshotLabel".to_string(),
            RefOr::T(crate::openapi::snapshot_label_schema()),
        );
        components.add_security_scheme(
            "bearer",
            SecurityScheme::Http(HttpBuilder::new().scheme(HttpAuthScheme::Bearer).build()),
        );
    }
}

/// The form's layout of the parameter table for the CaseParams schema (whose
/// properties a JSON object lists alphabetically): `x-order`, the parameters
/// in the table's order, and `x-groups`, each group's name and title in form
/// order (`solver::case::Group`).
fn form_layout() -> utoipa::openapi::extensions::Extensions {
    use solver::case::{Group, PARAMETERS};
    let order: Vec<&str> = PARAMETERS.iter().map(|p| p.name).collect();
    let groups: Vec<serde_json::Value> = Group::ALL
        .iter()
        .map(|g| serde_json::json!({"name": g, "title": g.title()}))
        .collect();
    utoipa::openapi::extensions::Extensions::from_iter([
        ("x-order", serde_json::json!(order)),
        ("x-groups", serde_json::json!(groups)),
    ])
}

fn constant_time_eq(a: &[u8], b: &[u8]) -> bool {
    a.len() == b.len() && a.iter().zip(b).fold(0u8, |acc, (x, y)| acc | (x ^ y)) == 0
}

async fn auth(State(app): State<App>, request: Request, next: Next) -> Response {
    if let Some(token) = &app.token
        && !matches!(*request.method(), Method::GET | Method::HEAD | Method::OPTIONS)
    {
        let given = request
            .headers()
            .get(header::AUTHORIZATION)
            // A value that is not visible ASCII holds no valid token: 401 as without one.
            .and_then(|v| v.to_str().ok())
            .and_then(bearer_token);
        if !given.is_some_and(|t| constant_time_eq(t.as_bytes(), token.as_bytes())) {
            return ApiError::unauthorized().into_response();
        }
    }
    next.run(request).await
}

/// The token of an `Authorization: Bearer <token>` value; the scheme is
/// case-insensitive (RFC 9110, 11.1).
fn bearer_token(value: &str) -> Option<&str> {
    let (scheme, token) = value.trim().split_once(' ')?;
    scheme.eq_ignore_ascii_case("bearer").then(|| token.trim())
}

/// Gives the router's bodiless 405 answers the JSON error body (keeping
/// their `Allow` header), and any 404 under `/api/` that is not JSON (Swagger
/// UI's) the API's.
async fn json_errors(request: Request, next: Next) -> Response {
    let method = request.method().clone();
    let api = request.uri().path().starts_with("/api/");
    let response = next.run(request).await;
    let json = response
        .headers()
        .get(header::CONTENT_TYPE)
        .is_some_and(|t| t.as_bytes().starts_with(b"application/json"));
    if api && response.status() == StatusCode::NOT_FOUND && !json {
        return not_found().await.into_response();
    }
    if response.status() != StatusCode::METHOD_NOT_ALLOWED {
        return response;
    }
    let allow = response.headers().get(header::ALLOW).cloned();
    let message = match allow.as_ref().and_then(|a| a.to_str().ok()) {
        Some(a) => format!("{method} is not allowed here; allowed: {a}"),
        None => format!("{method} is not allowed here"),
    };
    let mut json = ApiError::new(
        StatusCode::METHOD_NOT_ALLOWED,
        "method_not_allowed",
        message,
        vec![],
    )
    .into_response();
    if let Some(a) = allow {
        json.headers_mut().insert(header::ALLOW, a);
    }
    json
}

async fn not_found() -> ApiError {
    ApiError::new(StatusCode::NOT_FOUND, "not_found", "no such route", vec![])
}

async fn index() -> Html<&'static str> {
    Html(include_str!("../../web/index.html"))
}

/// The page's bundle (web/dist, built from web/src by `npm run build` and
/// committed, so the binary needs no Node at build or run time).
async fn app_js() -> impl IntoResponse {
    asset(
        "text/javascript; charset=utf-8",
        include_bytes!("../../web/dist/app.js"),
    )
}

async fn app_css() -> impl IntoResponse {
    asset(
        "text/css; charset=utf-8",
        include_bytes!("../../web/dist/app.css"),
    )
}

fn asset(content_type: &'static str, bytes: &'static [u8]) -> impl IntoResponse {
    (
        [
            (header::CONTENT_TYPE, content_type),
            (header::CACHE_CONTROL, "no-cache"),
        ],
        bytes,
    )
}

/// Health: database reachable and no embedded worker stalled.
#[utoipa::path(get, path = "/healthz", tag = "service",
    responses((status = 200, body = Health), (status = 503, description = "Degraded", body = Health)))]
async fn healthz(State(app): State<App>) -> (StatusCode, Json<Health>) {
    let health = app.core.health().await;
    let status = if health.status == "ok" {
        StatusCode::OK
    } else {
        StatusCode::SERVICE_UNAVAILABLE
    };
    (status, Json(health))
}

/// Prometheus metrics: `knotsweep_cases{status}`, `knotsweep_queue_depth`,
/// `knotsweep_sweeps{status}`, `knotsweep_claims_total`,
/// `knotsweep_completions_total{outcome}`, `knotsweep_case_duration_seconds`
/// (histogram), retries, failures, lost leases, queue overhead.
#[utoipa::path(get, path = "/metrics", tag = "service",
    responses((status = 200, description = "Prometheus text exposition", content_type = "text/plain")))]
async fn metrics(State(app): State<App>) -> Result<Response, ApiError> {
    let text = app.core.metrics().await?;
    Ok((
        [(header::CONTENT_TYPE, "text/plain; version=0.0.4; charset=utf-8")],
        text,
    )
        .into_response())
}

/// The presets (paper Figs 7, 9, 11, the hysteresis, twist and materials programs) with their full definitions.
#[utoipa::path(get, path = "/api/presets", tag = "service", responses((status = 200, body = Vec<Preset>)))]
async fn list_presets() -> Json<Vec<Preset>> {
    Json(crate::spec::presets())
}

/// The service's limits (cases per sweep, body size, name and key lengths,
/// page size) and the certification threshold.
#[utoipa::path(get, path = "/api/limits", tag = "service", responses((status = 200, body = ServiceLimits)))]
async fn get_limits(State(app): State<App>) -> Json<ServiceLimits> {
    Json(ServiceLimits::new(app.core.limits(), MAX_PAGE))
}

/// A named material: its elastic constants under the case parameters' names,
/// so that a client sets them as they are (`solver::case::NamedMaterial`).
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize, utoipa::ToSchema)]
pub struct MaterialView {
    /// `rubber` (the paper's), `silicone`, `nylon`, `nitinol`, `steel`.
    pub name: String,
    /// Young's modulus E (Pa).
    pub youngs_modulus: f64,
    /// Density rho (kg/m^3).
    pub density: f64,
    /// Poisson's ratio nu.
    pub poisson_ratio: f64,
    /// What the rod is and where its constants come from.
    pub source: String,
}

impl From<&solver::case::NamedMaterial> for MaterialView {
    fn from(m: &solver::case::NamedMaterial) -> Self {
        Self {
            name: m.name.to_string(),
            youngs_modulus: m.youngs_modulus,
            density: m.density,
            poisson_ratio: m.poisson_ratio,
            source: m.source.to_string(),
        }
    }
}

/// The named materials (`solver::case::MATERIALS`): E, rho and nu under the
/// case parameters' names (`youngs_modulus`, `density`, `poisson_ratio`) with
/// their source, for a form's material picker.
#[utoipa::path(get, path = "/api/materials", tag = "service", responses((status = 200, body = Vec<MaterialView>)))]
async fn list_materials() -> Json<Vec<MaterialView>> {
    Json(solver::case::MATERIALS.iter().map(MaterialView::from).collect())
}

/// Submit a sweep: a base case plus a grid, or a preset.
///
/// Every case parameter is optional (paper defaults); `grid` lists values for
/// any parameters (cartesian product, at most `max_cases` of `GET /api/limits`). A case
/// already computed (same parameters and solver version) is reused at once
/// (`cached: true`). With an `Idempotency-Key` seen before and the same body,
/// the first sweep is returned (200, `replayed: true`); with a different body,
/// 409.
#[utoipa::path(post, path = "/api/sweeps", tag = "sweeps",
    request_body(content = SweepSpec, description = "At most `max_body_bytes` of `GET /api/limits`"),
    params(("Idempotency-Key" = Option<String>, Header, description = "Makes retried submissions return the first sweep (printable ASCII, at most `max_idempotency_key_chars` of `GET /api/limits`)")),
    responses(
        (status = 201, description = "Accepted", body = SubmitResponse),
        (status = 200, description = "Idempotent replay of an earlier submission", body = SubmitResponse),
        (status = 400, description = "Malformed JSON or header", body = ErrorBody),
        (status = 401, description = "Token required", body = ErrorBody),
        (status = 403, description = "A foreign Host or Origin (docs/API.md, \"Cross-site requests\")", body = ErrorBody),
        (status = 408, description = "The body did not arrive in time", body = ErrorBody),
        (status = 409, description = "Idempotency-Key reused with another body", body = ErrorBody),
        (status = 413, description = "Body too large", body = ErrorBody),
        (status = 415, description = "Not application/json", body = ErrorBody),
        (status = 422, description = "Invalid values: the fields and reasons", body = ErrorBody)
    ))]
async fn submit_sweep(State(app): State<App>, submission: Submission) -> Result<Response, ApiError> {
    let Submission {
        idempotency_key,
        spec,
        raw,
    } = submission;
    let response = app.core.submit(spec, &raw, idempotency_key.as_deref()).await?;
    let status = if response.replayed {
        StatusCode::OK
    } else {
        StatusCode::CREATED
    };
    let location =
        HeaderValue::from_str(&format!("/api/sweeps/{}", response.sweep.summary.id)).expect("ascii");
    Ok((status, [(header::LOCATION, location)], Json(response)).into_response())
}

/// Sweeps with their counts per status, oldest first, a page at a time:
/// `X-Total-Count` gives the number of sweeps and `Link` the next page.
#[utoipa::path(get, path = "/api/sweeps", tag = "sweeps", params(Page),
    responses((status = 200, body = Vec<SweepSummary>), (status = 400, body = ErrorBody)))]
async fn list_sweeps(State(app): State<App>, page: Paging) -> Result<Response, ApiError> {
    let (sweeps, total) = app.core.list_sweeps(page.limit, page.offset).await?;
    Ok(page_response(sweeps, total, page, "/api/sweeps"))
}

/// One page of `all` as JSON, with `X-Total-Count` and a `Link: rel="next"`.
fn paginate<T: serde::Serialize>(all: Vec<T>, page: Paging, path: &str) -> Response {
    let total = all.len();
    let items: Vec<T> = all.into_iter().skip(page.offset).take(page.limit).collect();
    page_response(items, total, page, path)
}

/// `items`, the page at `offset` of a list of `total`, as JSON with
/// `X-Total-Count` and a `Link: rel="next"` when more follow.
fn page_response<T: serde::Serialize>(
    items: Vec<T>,
    total: usize,
    Paging { limit, offset }: Paging,
    path: &str,
) -> Response {
    let mut response = Json(items).into_response();
    let headers = response.headers_mut();
    headers.insert("x-total-count", HeaderValue::from(total));
    if offset.saturating_add(limit) < total {
        let next = format!("<{path}?limit={limit}&offset={}>; rel=\"next\"", offset + limit);
        headers.insert(header::LINK, HeaderValue::from_str(&next).expect("ascii"));
    }
    response
}

/// A sweep's cases in grid order: parameters, status, progress, inversion (paginated).
#[utoipa::path(get, path = "/api/sweeps/{id}/cases", tag = "sweeps",
    params(("id" = i64, Path), Page),
    responses((status = 200, body = [SweepCaseView], headers(("x-total-count" = usize, description = "Cases in the sweep"),
        ("link" = String, description = "The next page, when there is one"))),
        (status = 400, body = ErrorBody), (status = 404, body = ErrorBody)))]
async fn sweep_cases(State(app): State<App>, Id(id): Id, page: Paging) -> Result<Response, ApiError> {
    let detail = app.core.sweep(id).await?;
    Ok(paginate(detail.cases, page, &format!("/api/sweeps/{id}/cases")))
}

/// A sweep: counts per status, progress, ETA (its cases: `/api/sweeps/{id}/cases`).
#[utoipa::path(get, path = "/api/sweeps/{id}", tag = "sweeps", params(("id" = i64, Path)),
    responses((status = 200, body = SweepDetail), (status = 400, body = ErrorBody), (status = 404, body = ErrorBody)))]
async fn get_sweep(State(app): State<App>, Id(id): Id) -> Result<Json<SweepDetail>, ApiError> {
    Ok(Json(app.core.sweep(id).await?))
}

/// Pause: queued cases are not handed out; running ones stop at their next
/// heartbeat and go back to the queue (computed again on resume) unless an
/// active sweep also wants them.
#[utoipa::path(post, path = "/api/sweeps/{id}/pause", tag = "sweeps", params(("id" = i64, Path)),
    responses((status = 200, body = SweepDetail), (status = 401, body = ErrorBody), (status = 403, body = ErrorBody),
        (status = 404, body = ErrorBody), (status = 415, body = ErrorBody),
        (status = 409, description = "The sweep is cancelled", body = ErrorBody)))]
async fn pause_sweep(State(app): State<App>, Id(id): Id) -> Result<Json<SweepDetail>, ApiError> {
    Ok(Json(app.core.control(id, SweepAction::Pause).await?))
}

/// Resume a paused sweep.
#[utoipa::path(post, path = "/api/sweeps/{id}/resume", tag = "sweeps", params(("id" = i64, Path)),
    responses((status = 200, body = SweepDetail), (status = 401, body = ErrorBody), (status = 403, body = ErrorBody),
        (status = 404, body = ErrorBody), (status = 415, body = ErrorBody),
        (status = 409, description = "The sweep is cancelled", body = ErrorBody)))]
async fn resume_sweep(State(app): State<App>, Id(id): Id) -> Result<Json<SweepDetail>, ApiError> {
    Ok(Json(app.core.control(id, SweepAction::Resume).await?))
}

/// Cancel: queued cases are cancelled, running ones stop at their next
/// heartbeat (cases another live sweep also wants go on); a finished sweep is
/// left as it is.
#[utoipa::path(post, path = "/api/sweeps/{id}/cancel", tag = "sweeps", params(("id" = i64, Path)),
    responses((status = 200, body = SweepDetail), (status = 401, body = ErrorBody), (status = 403, body = ErrorBody),
        (status = 404, body = ErrorBody), (status = 415, body = ErrorBody)))]
async fn cancel_sweep(State(app): State<App>, Id(id): Id) -> Result<Json<SweepDetail>, ApiError> {
    Ok(Json(app.core.control(id, SweepAction::Cancel).await?))
}

/// Server-sent events: `progress` (a [`SweepEvent`]) now and whenever the
/// sweep changes, then one `done` event when it is finished or cancelled,
/// after which the stream ends; open streams are capped per sweep and per
/// client address ([`crate::events`]).
#[utoipa::path(get, path = "/api/sweeps/{id}/events", tag = "sweeps", params(("id" = i64, Path)),
    responses((status = 200, description = "text/event-stream of `progress` and `done` events whose data is a SweepEvent",
        content_type = "text/event-stream", body = SweepEvent), (status = 404, body = ErrorBody),
        (status = 429, description = "Too many streams open for this sweep or from this address", body = ErrorBody)))]
async fn sweep_events(
    State(app): State<App>,
    Id(id): Id,
    peer: Option<Extension<ConnectInfo<SocketAddr>>>,
) -> Result<Sse<impl Stream<Item = Result<Event, Infallible>>>, ApiError> {
    // In-process callers (tests) have no peer: one bucket for all of them.
    let client = peer.map_or(IpAddr::V4(Ipv4Addr::UNSPECIFIED), |Extension(ConnectInfo(a))| {
        a.ip()
    });
    let updates = app.feeds.subscribe(id, client).await?;
    let stream = updates.map(|update| {
        let data = serde_json::to_string(update.event()).expect("event serialises");
        Ok(Event::default().event(update.name()).data(data))
    });
    Ok(Sse::new(stream).keep_alive(KeepAlive::new().interval(crate::events::HEARTBEAT)))
}

/// The phase diagram: for each case its varied parameters, status and
/// inversion point (l_k bar, l_c/L) or null with the reason. Paper Figs 7, 9
/// and 11 plot `points[].inversion.l_k_bar` against the varied parameter.
#[utoipa::path(get, path = "/api/sweeps/{id}/phase-diagram", tag = "sweeps", params(("id" = i64, Path)),
    responses((status = 200, body = PhaseDiagram), (status = 404, body = ErrorBody)))]
async fn phase_diagram(State(app): State<App>, Id(id): Id) -> Result<Json<PhaseDiagram>, ApiError> {
    Ok(Json(app.core.phase_diagram(id).await?))
}

/// The phase diagram as CSV, one row per point: the varied parameters (the
/// paper's symbols with SI units), status, the inversion (l̄_k, its certified
/// uncertainty δl̄_k, l_c/L, F̄ and H̄ around it), the simplified model's l̄_k,
/// the flip back, every event and the reason a point has none.
#[utoipa::path(get, path = "/api/sweeps/{id}/phase-diagram.csv", tag = "sweeps", params(("id" = i64, Path)),
    responses((status = 200, description = "CSV, one row per point", content_type = "text/csv"),
        (status = 404, body = ErrorBody)))]
async fn phase_diagram_csv(State(app): State<App>, Id(id): Id) -> Result<Response, ApiError> {
    let pd = app.core.phase_diagram(id).await?;
    let csv = report::tables::phase_diagram_csv(&serde_json::to_value(pd).expect("views serialise"));
    Ok(attachment(
        "text/csv; charset=utf-8",
        &format!("sweep-{id}-phase-diagram.csv"),
        csv,
    ))
}

/// Put measured inversions beside a sweep (replacing any before): a list of
/// points, or CSV with a header naming the sweep's first varied parameter,
/// `l_k_bar` and `error` (SI units). They are drawn on the sweep's phase
/// diagram (with their error bars) and curves.
#[utoipa::path(put, path = "/api/sweeps/{id}/measurements", tag = "sweeps", params(("id" = i64, Path)),
    request_body(content = MeasurementsBody),
    responses((status = 200, body = Vec<MeasuredPoint>), (status = 400, body = ErrorBody), (status = 401, body = ErrorBody),
        (status = 404, body = ErrorBody), (status = 422, body = ErrorBody)),
    security((), ("bearer" = [])))]
async fn put_measurements(
    State(app): State<App>,
    Id(id): Id,
    body: axum::body::Bytes,
) -> Result<Json<Vec<crate::fit::MeasuredPoint>>, ApiError> {
    let body: MeasurementsBody = Core::parse_json(&body)?;
    Ok(Json(app.core.set_measurements(id, body).await?))
}

/// The measured inversions beside a sweep (an empty list when none were put).
#[utoipa::path(get, path = "/api/sweeps/{id}/measurements", tag = "sweeps", params(("id" = i64, Path)),
    responses((status = 200, body = Vec<MeasuredPoint>), (status = 404, body = ErrorBody)))]
async fn get_measurements(State(app): State<App>, Id(id): Id) -> Result<Json<Vec<MeasuredPoint>>, ApiError> {
    Ok(Json(app.core.measurements(id).await?))
}

/// Refine a sweep's map: along each axis given a tolerance, every grid line
/// where the outcome changes (an inversion or none, a clean snap or not) is
/// bisected over queued cases (one sweep each) until the two cases
/// bracketing the change are within the tolerance. Starts once the sweep is
/// done; follow it at `GET /api/sweeps/{id}/refinement`. A new refinement
/// replaces the one before (409 while that one runs).
#[utoipa::path(post, path = "/api/sweeps/{id}/refine", tag = "sweeps", params(("id" = i64, Path)),
    request_body(content = RefineSpec),
    responses(
        (status = 202, description = "Accepted: the bisection runs", body = RefinementView),
        (status = 400, description = "Malformed JSON", body = ErrorBody),
        (status = 401, description = "Token required", body = ErrorBody),
        (status = 404, body = ErrorBody),
        (status = 409, description = "A refinement of the sweep is running", body = ErrorBody),
        (status = 422, description = "Invalid values: the fields and reasons", body = ErrorBody)
    ),
    security((), ("bearer" = [])))]
async fn refine_sweep(
    State(app): State<App>,
    Id(id): Id,
    body: axum::body::Bytes,
) -> Result<Response, ApiError> {
    let spec: RefineSpec = Core::parse_json(&body)?;
    let view = app.core.submit_refinement(id, spec).await?;
    let location = HeaderValue::from_str(&format!("/api/sweeps/{id}/refinement")).expect("ascii");
    Ok((StatusCode::ACCEPTED, [(header::LOCATION, location)], Json(view)).into_response())
}

/// A sweep's refinement: its status, the cases it added and every bracket
/// of a change of outcome (404 when the sweep has none).
#[utoipa::path(get, path = "/api/sweeps/{id}/refinement", tag = "sweeps", params(("id" = i64, Path)),
    responses((status = 200, body = RefinementView), (status = 404, body = ErrorBody)))]
async fn get_refinement(State(app): State<App>, Id(id): Id) -> Result<Json<RefinementView>, ApiError> {
    Ok(Json(app.core.refinement(id).await?))
}

/// Fit a parameter (mu by default) to measured inversions: the search runs
/// over queued cases (one sweep per point and evaluation); follow it at
/// `GET /api/fits/{id}` until its `status` is `done` (with `value` and
/// `interval`) or `failed` (with `reason`). Fits are stored: one running when
/// its server stops starts again when one starts (its cases are cached).
#[utoipa::path(post, path = "/api/fits", tag = "fits",
    request_body(content = FitSpec),
    responses(
        (status = 202, description = "Accepted: the search runs", body = FitView),
        (status = 400, description = "Malformed JSON", body = ErrorBody),
        (status = 401, description = "Token required", body = ErrorBody),
        (status = 422, description = "Invalid values: the fields and reasons", body = ErrorBody)
    ),
    security((), ("bearer" = [])))]
async fn submit_fit(State(app): State<App>, body: axum::body::Bytes) -> Result<Response, ApiError> {
    let spec: FitSpec = Core::parse_json(&body)?;
    let fit = app.core.submit_fit(spec).await?;
    let location = HeaderValue::from_str(&format!("/api/fits/{}", fit.id)).expect("ascii");
    Ok((StatusCode::ACCEPTED, [(header::LOCATION, location)], Json(fit)).into_response())
}

/// Every fit, oldest first.
#[utoipa::path(get, path = "/api/fits", tag = "fits", responses((status = 200, body = Vec<FitView>)))]
async fn list_fits(State(app): State<App>) -> Result<Json<Vec<FitView>>, ApiError> {
    Ok(Json(app.core.list_fits().await?))
}

/// A fit: its status, evaluations and, when done, `value` and `interval`.
#[utoipa::path(get, path = "/api/fits/{id}", tag = "fits", params(("id" = i64, Path)),
    responses((status = 200, body = FitView), (status = 404, body = ErrorBody)))]
async fn get_fit(State(app): State<App>, Id(id): Id) -> Result<Json<FitView>, ApiError> {
    Ok(Json(app.core.fit(id).await?))
}

/// A case: parameters, status, result, series, log lines.
#[utoipa::path(get, path = "/api/cases/{id}", tag = "cases", params(("id" = i64, Path)),
    responses((status = 200, body = CaseDetail), (status = 404, body = ErrorBody)))]
async fn get_case(State(app): State<App>, Id(id): Id) -> Result<Json<CaseDetail>, ApiError> {
    Ok(Json(app.core.case(id).await?))
}

/// The series of a case's result as CSV (404 before the result).
#[utoipa::path(get, path = "/api/cases/{id}/series.csv", tag = "cases", params(("id" = i64, Path)),
    responses((status = 200, description = "CSV, one row per sample", content_type = "text/csv"),
        (status = 404, body = ErrorBody)))]
async fn case_series_csv(State(app): State<App>, Id(id): Id) -> Result<Response, ApiError> {
    let csv = app.core.series_csv(id).await?;
    Ok(attachment(
        "text/csv; charset=utf-8",
        &format!("case-{id}-series.csv"),
        csv,
    ))
}

/// A download: `body` as `content_type`, saved as `filename`.
fn attachment(content_type: &'static str, filename: &str, body: impl IntoResponse) -> Response {
    let disposition = format!("attachment; filename=\"{filename}\"");
    (
        [
            (header::CONTENT_TYPE, content_type.to_string()),
            (header::CONTENT_DISPOSITION, disposition),
        ],
        body,
    )
        .into_response()
}

/// A figure's format: the SVG charts are drawn as, or that SVG as PDF.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Format {
    Svg,
    Pdf,
}

/// A figure's name `STEM.svg` or `STEM.pdf` as its stem and format.
fn figure_name(figure: &str) -> Option<(&str, Format)> {
    (figure.strip_suffix(".svg").map(|s| (s, Format::Svg)))
        .or_else(|| figure.strip_suffix(".pdf").map(|s| (s, Format::Pdf)))
}

/// `{id}` and a figure name `F_bar.svg`, `H_bar.pdf`, ... from the path.
fn figure_path(id: &str, figure: &str) -> Result<(i64, Quantity, Format), ApiError> {
    let id = id
        .parse()
        .map_err(|_| ApiError::bad_request("id", format!("must be an integer, got {id:?}")))?;
    let (quantity, format) = figure_name(figure)
        .and_then(|(stem, format)| Some((Quantity::parse(stem)?, format)))
        .ok_or_else(|| {
            ApiError::new(
                StatusCode::NOT_FOUND,
                "not_found",
                "figures: F_bar.svg, H_bar.svg (or .pdf)",
                vec![],
            )
        })?;
    Ok((id, quantity, format))
}

/// A chart's SVG as the answer in `format` (PDF: `report::pdf`).
fn figure(text: String, format: Format) -> Result<Response, ApiError> {
    Ok(match format {
        Format::Svg => ([(header::CONTENT_TYPE, "image/svg+xml")], text).into_response(),
        Format::Pdf => {
            let pdf =
                report::pdf::svg_to_pdf(&text).map_err(|e| crate::error::CoreError::Figure(e.to_string()))?;
            ([(header::CONTENT_TYPE, "application/pdf")], pdf).into_response()
        }
    })
}

/// F bar or H bar against l_k bar of a case as SVG or PDF (the figure of `knotsweep run --plot`).
#[utoipa::path(get, path = "/api/cases/{id}/figures/{figure}", tag = "cases",
    params(("id" = i64, Path), ("figure" = String, Path, description = "F_bar.svg or H_bar.svg, or .pdf")),
    responses((status = 200, description = "SVG or PDF", content_type = "image/svg+xml"), (status = 404, body = ErrorBody)))]
async fn case_figure(
    State(app): State<App>,
    Path((id, name)): Path<(String, String)>,
) -> Result<Response, ApiError> {
    let (id, quantity, format) = figure_path(&id, &name)?;
    figure(app.core.case_figure(id, quantity).await?, format)
}

/// The query of a sweep's figure: `with`, the sweeps whose points the phase
/// diagram overlays (`?with=3,4`).
#[derive(Debug, serde::Deserialize)]
struct FigureQuery {
    with: Option<String>,
}

/// F bar or H bar against l_k bar of every finished case of a sweep, overlaid,
/// or the phase diagram with the simplified model's line (and the points of
/// the sweeps `?with=3,4` overlaid), as SVG.
#[utoipa::path(get, path = "/api/sweeps/{id}/figures/{figure}", tag = "sweeps",
    params(("id" = i64, Path), ("figure" = String, Path, description = "F_bar.svg, H_bar.svg, phase.svg or map.svg (two axes), or .pdf"),
        ("with" = Option<String>, Query, description = "phase.svg: sweeps whose points are overlaid, ids separated by commas")),
    responses((status = 200, description = "SVG or PDF", content_type = "image/svg+xml"), (status = 404, body = ErrorBody)))]
async fn sweep_figure(
    State(app): State<App>,
    Path((id, name)): Path<(String, String)>,
    Query(query): Query<FigureQuery>,
) -> Result<Response, ApiError> {
    if let Some(("phase", format)) = figure_name(&name) {
        let id = id
            .parse()
            .map_err(|_| ApiError::bad_request("id", format!("must be an integer, got {id:?}")))?;
        let with = (query.with.as_deref().unwrap_or_default().split(','))
            .filter(|w| !w.trim().is_empty())
            .map(|w| w.trim().parse::<i64>())
            .collect::<Result<Vec<_>, _>>()
            .map_err(|_| ApiError::bad_request("with", "must be sweep ids separated by commas"))?;
        return figure(app.core.phase_figure(id, &with).await?, format);
    }
    if let Some(("map", format)) = figure_name(&name) {
        let id = id
            .parse()
            .map_err(|_| ApiError::bad_request("id", format!("must be an integer, got {id:?}")))?;
        return figure(app.core.map_figure(id).await?, format);
    }
    let (id, quantity, format) = figure_path(&id, &name)?;
    figure(app.core.sweep_figure(id, quantity).await?, format)
}

/// The snapshots of a case: its knot's states kept for viewers
/// (`[{label, l_k_bar, time, points: [[x, y, z], ...], ...}]`; the labels'
/// words are the `SnapshotLabel` schema's).
#[utoipa::path(get, path = "/api/cases/{id}/snapshots", tag = "cases", params(("id" = i64, Path)),
    responses((status = 200, description = "JSON array of snapshots", content_type = "application/json"),
        (status = 404, body = ErrorBody)))]
async fn case_snapshots(State(app): State<App>, Id(id): Id) -> Result<Response, ApiError> {
    let json = app.core.snapshots(id).await?;
    Ok(([(header::CONTENT_TYPE, "application/json")], json).into_response())
}

/// The snapshots for ParaView: a zip of `case-{id}.pvd` and, per snapshot in time order, the centre line and the contacts
/// as VTK XML PolyData (`case-{id}/centreline_NNN.vtp`, `case-{id}/contacts_NNN.vtp`; docs/PARAVIEW.md).
#[utoipa::path(get, path = "/api/cases/{id}/snapshots.zip", tag = "cases", params(("id" = i64, Path)),
    responses((status = 200, description = "zip of a .pvd and its .vtp files", content_type = "application/zip"),
        (status = 404, body = ErrorBody)))]
async fn case_snapshots_zip(State(app): State<App>, Id(id): Id) -> Result<Response, ApiError> {
    let zip = app.core.snapshots_zip(id).await?;
    Ok(attachment(
        "application/zip",
        &format!("case-{id}-snapshots.zip"),
        zip,
    ))
}
