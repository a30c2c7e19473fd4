//! The interactive tuning page behind `beltune serve` (issue 7).
//!
//! - `GET /`, `/app.js`, `/style.css`: the page, embedded in the binary (no CDN, no
//!   network); the plots are drawn client-side as inline SVG from the API's data.
//! - `GET /api/info`: model summary, knob defaults and ranges.
//! - `POST /api/design`: knobs -> gains, margins, Bode data, simulated move ([`api`]).
//! - `POST /api/save`: writes a new folder `tuned-<UTC time>` in the save folder
//!   with a consistent set (`controller.toml`, `commissioning.json`, `report.html`,
//!   data files), never overwriting an earlier result.
//!
//! POST bodies must be `application/json` (a cross-site form cannot post them
//! without a CORS preflight, which this server never grants) and at most
//! [`api::MAX_BODY_BYTES`]. Every error answer is JSON `{ "error": "..." }`.
//! [`router`] is separate from the listener so that tests run the server
//! in-process on port 0.

pub mod api;
pub mod library;
pub mod tuner;

use api::{ApiError, DesignRequest, ErrorBody, InfoResponse, SaveResponse};
use axum::body::Bytes;
use axum::extract::rejection::BytesRejection;
use axum::extract::{DefaultBodyLimit, Request, State};
use axum::http::{header, HeaderMap, StatusCode};
use axum::middleware::{self, Next};
use axum::response::{IntoResponse, Response};
use axum::routing::{get, post};
use axum::{Json, Router};
use std::path::PathBuf;
use std::sync::Arc;
use tuner::{TuneError, Tuner};

const INDEX_HTML: &str = include_str!("assets/index.html");
const APP_JS: &str = include_str!("assets/app.js");
const STYLE_CSS: &str = include_str!("assets/style.css");

/// The page may load only its own script and style sheet.
const CSP: &str = "default-src 'none'; script-src 'self'; style-src 'self'; \
                   connect-src 'self'; img-src 'self' data:; base-uri 'none'; form-action 'none'";

/// File name written by `POST /api/save`.
pub const CONTROLLER_FILE: &str = "controller.toml";

/// Shared state of the server.
#[derive(Clone)]
pub struct AppState {
    /// Design + simulation backend.
    pub tuner: Arc<dyn Tuner>,
    /// Folder `controller.toml` is saved into.
    pub save_dir: PathBuf,
    /// Answer only requests whose `Host` is a loopback name (`localhost`,
    /// `127.0.0.1`, `[::1]`, any port): a web page from elsewhere that re-binds
    /// its own domain name to 127.0.0.1 (DNS rebinding) cannot use the API.
    pub loopback_only: bool,
}

/// The page and the API, ready for `axum::serve`.
pub fn router(state: AppState) -> Router {
    Router::new()
        .route("/", get(index))
        .route("/app.js", get(app_js))
        .route("/style.css", get(style_css))
        .route("/api/info", get(info))
        .route("/api/design", post(design))
        .route("/api/save", post(save))
        .fallback(not_found)
        .layer(DefaultBodyLimit::max(api::MAX_BODY_BYTES))
        .layer(middleware::from_fn_with_state(state.clone(), check_host))
        .with_state(state)
}

/// `true` for `localhost`, a loopback IP literal, with or without a port.
pub fn is_loopback_host(host: &str) -> bool {
    let name = match host.strip_prefix('[') {
        Some(rest) => rest.split(']').next().unwrap_or(""),
        None => host.rsplit_once(':').map_or(host, |(h, _)| h),
    };
    name.eq_ignore_ascii_case("localhost")
        || name
            .parse::<std::net::IpAddr>()
            .is_ok_and(|ip| ip.is_loopback())
}

async fn check_host(State(state): State<AppState>, req: Request, next: Next) -> Response {
    if state.loopback_only {
        if let Some(host) = req.headers().get(header::HOST) {
            let host = host.to_str().unwrap_or("");
            if !is_loopback_host(host) {
                return error_response(ApiError {
                    status: 403,
                    message: format!(
                        "Host `{host}` is not a loopback name; open the page as http://127.0.0.1:PORT/"
                    ),
                });
            }
        }
    }
    next.run(req).await
}

/// Serve `router(state)` on an already bound listener until the process ends.
pub async fn serve(listener: tokio::net::TcpListener, state: AppState) -> std::io::Result<()> {
    axum::serve(listener, router(state)).await
}

fn error_response(e: ApiError) -> Response {
    let status = StatusCode::from_u16(e.status).unwrap_or(StatusCode::INTERNAL_SERVER_ERROR);
    (status, Json(ErrorBody { error: e.message })).into_response()
}

fn tune_error(e: TuneError) -> ApiError {
    match e {
        TuneError::Infeasible(reason) => ApiError {
            status: 422,
            message: reason,
        },
        TuneError::Internal(reason) => ApiError {
            status: 500,
            message: format!("internal error: {reason}"),
        },
    }
}

async fn index() -> Response {
    (
        [
            (header::CONTENT_TYPE, "text/html; charset=utf-8"),
            (header::CONTENT_SECURITY_POLICY, CSP),
            (header::CACHE_CONTROL, "no-store"),
        ],
        INDEX_HTML,
    )
        .into_response()
}

async fn app_js() -> Response {
    (
        [
            (header::CONTENT_TYPE, "text/javascript; charset=utf-8"),
            (header::CACHE_CONTROL, "no-store"),
        ],
        APP_JS,
    )
        .into_response()
}

async fn style_css() -> Response {
    (
        [
            (header::CONTENT_TYPE, "text/css; charset=utf-8"),
            (header::CACHE_CONTROL, "no-store"),
        ],
        STYLE_CSS,
    )
        .into_response()
}

async fn not_found() -> Response {
    error_response(ApiError {
        status: 404,
        message: "not found".into(),
    })
}

async fn info(State(state): State<AppState>) -> Json<InfoResponse> {
    let model = state.tuner.model();
    Json(InfoResponse {
        model_source: model.source,
        f_r_hz: model.f_r_hz,
        f_z_hz: model.f_z_hz,
        nominal_payload_kg: model.nominal_payload_kg,
        defaults: state.tuner.defaults(),
        default_attenuation_db: state.tuner.default_attenuation(),
        ranges: api::RANGES.to_vec(),
        save_dir: state.save_dir.display().to_string(),
        measured_frf: model.measured_frf,
        commissioned: model.commissioned,
    })
}

/// Content type check, body limit and JSON parsing shared by the POST routes.
fn read_knobs(
    headers: &HeaderMap,
    body: Result<Bytes, BytesRejection>,
) -> Result<api::Knobs, ApiError> {
    let content_type = headers
        .get(header::CONTENT_TYPE)
        .and_then(|v| v.to_str().ok())
        .unwrap_or("");
    let mime = content_type.split(';').next().unwrap_or("").trim();
    if !mime.eq_ignore_ascii_case("application/json") {
        return Err(ApiError {
            status: 415,
            message: format!("Content-Type must be application/json, got `{content_type}`"),
        });
    }
    let body = body.map_err(|rejection| {
        let status = rejection.status().as_u16();
        let message = if status == 413 {
            format!(
                "request body too large (limit {} bytes)",
                api::MAX_BODY_BYTES
            )
        } else {
            format!("cannot read request body: {}", rejection.body_text())
        };
        ApiError { status, message }
    })?;
    DesignRequest::parse(&body)?.validate()
}

/// Run a blocking tuner call off the async runtime.
async fn blocking<T: Send + 'static>(
    f: impl FnOnce() -> Result<T, TuneError> + Send + 'static,
) -> Result<T, ApiError> {
    match tokio::task::spawn_blocking(f).await {
        Ok(r) => r.map_err(tune_error),
        Err(e) => Err(ApiError {
            status: 500,
            message: format!("internal error: design task failed: {e}"),
        }),
    }
}

async fn design(
    State(state): State<AppState>,
    headers: HeaderMap,
    body: Result<Bytes, BytesRejection>,
) -> Response {
    let knobs = match read_knobs(&headers, body) {
        Ok(k) => k,
        Err(e) => return error_response(e),
    };
    let tuner = state.tuner.clone();
    match blocking(move || tuner.tune(&knobs)).await {
        Ok(r) => Json(r).into_response(),
        Err(e) => error_response(e),
    }
}

async fn save(
    State(state): State<AppState>,
    headers: HeaderMap,
    body: Result<Bytes, BytesRejection>,
) -> Response {
    let knobs = match read_knobs(&headers, body) {
        Ok(k) => k,
        Err(e) => return error_response(e),
    };
    let tuner = state.tuner.clone();
    let set = match blocking(move || tuner.save_set(&knobs)).await {
        Ok(t) => t,
        Err(e) => return error_response(e),
    };
    // Never overwrite: a new folder per save, written whole or not at all.
    let dir = std::path::absolute(&state.save_dir).unwrap_or_else(|_| state.save_dir.clone());
    let written = tokio::task::spawn_blocking(move || library::write_saved_set(&dir, &set)).await;
    match written {
        Ok(Ok(saved)) => Json(SaveResponse {
            path: saved.dir.join(CONTROLLER_FILE).display().to_string(),
            bytes: saved.controller_bytes,
            dir: saved.dir.display().to_string(),
            files: saved.files,
        })
        .into_response(),
        Ok(Err(e)) => error_response(ApiError {
            status: 500,
            message: format!("cannot save: {e}"),
        }),
        Err(e) => error_response(ApiError {
            status: 500,
            message: format!("internal error: save task failed: {e}"),
        }),
    }
}
