//! The interactive tuning page behind `beltune serve`.
//!
//! - `GET /`, `/app.js`, `/style.css`: the page, embedded in the binary (no CDN, no
//!   network); the plots are drawn client-side from the API's data with uPlot
//!   (`/uPlot.iife.min.js`, `/uPlot.min.css`, vendored, see
//!   [`beltune::report::web`]) and beltune's plots on it (`/beltune-plot.js`,
//!   `/beltune-plot.css`): zoom, read-out on hover, log frequency axes.
//! - `GET /api/info`: model summary, knob defaults and ranges.
//! - `POST /api/design`: knobs -> gains, margins, Bode data, simulated move ([`api`]).
//! - `POST /api/save`: writes a new folder `tuned-<UTC time>` in the save folder
//!   with a consistent set (`controller.toml`, `commissioning.json`, `report.html`,
//!   data files), never overwriting an earlier result.
//!
//! POST bodies must be `application/json` (a cross-site form cannot post them
//! without a CORS preflight, which this server never grants) and at most
//! [`api::MAX_BODY_BYTES`]. Every error answer is JSON `{ "error": "..." }`
//! (405, 408, 413, 414, 431 and 503 included).
//!
//! Against slow or abusive clients ([`serve`], [`conn`]): the request head
//! must arrive within [`HEADER_READ_TIMEOUT`] and the body within
//! [`BODY_READ_TIMEOUT`]; a connection carries one request, and a client that
//! does not read its answer is cut off after [`conn::WRITE_TIMEOUT`]; at most
//! [`MAX_CONNECTIONS`] connections are served at once (more get 503); a
//! connection lives at most [`CONNECTION_LIFETIME`]; a request target longer
//! than [`MAX_URI_BYTES`] is 414, a head larger than [`MAX_HEADER_BYTES`] or
//! with more than [`conn::MAX_HEADERS`] headers is 431, a garbage request line
//! or an ambiguous body length is 400. With `loopback_only`, a request needs
//! exactly one `Host` header naming a loopback host (`localhost`,
//! `127.x.y.z`, `[::1]`) with an optional numeric port.
//!
//! Against other web sites in the same browser: no page may frame this one
//! (`frame-ancestors 'none'`, `X-Frame-Options: DENY`), and a POST that a
//! browser marks as coming from another site (`Sec-Fetch-Site` other than
//! `same-origin`/`none`, or an `Origin` that is not this server's) is 403.
//! [`router`] is separate from the listener so that tests run the server
//! in-process on port 0.

pub mod api;
pub mod conn;
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
use std::time::Duration;
use tuner::{TuneError, Tuner};

/// Time a client has to send a request head (also the idle time between
/// requests on a kept-alive connection).
pub const HEADER_READ_TIMEOUT: Duration = Duration::from_secs(10);
/// Time a client has to send a request body.
pub const BODY_READ_TIMEOUT: Duration = Duration::from_secs(10);
/// Longest life of one connection.
pub const CONNECTION_LIFETIME: Duration = Duration::from_secs(300);
/// Connections served at once; more are answered 503 and closed.
pub const MAX_CONNECTIONS: usize = 64;
/// Longest request target (path and query), bytes.
pub const MAX_URI_BYTES: usize = 2048;
/// Largest request head (header names and values), bytes.
pub const MAX_HEADER_BYTES: usize = 8 * 1024;
/// hyper's own limit, beyond ours: only a head larger than this gets hyper's
/// bare 431 without a JSON body.
const HYPER_MAX_HEADER_BYTES: usize = 64 * 1024;

const INDEX_HTML: &str = include_str!("assets/index.html");
const APP_JS: &str = include_str!("assets/app.js");
const STYLE_CSS: &str = include_str!("assets/style.css");
use beltune::report::web::{PLOT_CSS, PLOT_JS, UPLOT_CSS, UPLOT_JS};

/// The page may load only its own script and style sheet.
const CSP: &str = "default-src 'none'; script-src 'self'; style-src 'self'; \
                   connect-src 'self'; img-src 'self' data:; base-uri 'none'; form-action 'none'; \
                   frame-ancestors 'none'";

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
        .route("/uPlot.iife.min.js", get(|| asset(JS, UPLOT_JS)))
        .route("/uPlot.min.css", get(|| asset(CSS, UPLOT_CSS)))
        .route("/beltune-plot.js", get(|| asset(JS, PLOT_JS)))
        .route("/beltune-plot.css", get(|| asset(CSS, PLOT_CSS)))
        .route("/api/info", get(info))
        .route("/api/design", post(design))
        .route("/api/save", post(save))
        .fallback(not_found)
        .method_not_allowed_fallback(method_not_allowed)
        .layer(DefaultBodyLimit::max(api::MAX_BODY_BYTES))
        .layer(middleware::from_fn_with_state(state.clone(), guard))
        .with_state(state)
}

/// `true` for exactly `localhost`, an IPv4 loopback address or `[::1]`
/// (any IPv6 loopback in brackets), each with an optional numeric port
/// `:1..=65535`; nothing before or after (`[::1]evil.com`,
/// `localhost:evil.com` and `localhost.` are refused).
pub fn is_loopback_host(host: &str) -> bool {
    let (loopback, port) = match host.strip_prefix('[') {
        Some(rest) => {
            let Some((inside, after)) = rest.split_once(']') else {
                return false;
            };
            let port = match after {
                "" => None,
                p => match p.strip_prefix(':') {
                    Some(p) => Some(p),
                    None => return false,
                },
            };
            let ip = inside.parse::<std::net::Ipv6Addr>();
            (ip.is_ok_and(|ip| ip.is_loopback()), port)
        }
        None => {
            let (name, port) = match host.split_once(':') {
                Some((h, p)) => (h, Some(p)),
                None => (host, None),
            };
            let ok = name.eq_ignore_ascii_case("localhost")
                || name
                    .parse::<std::net::Ipv4Addr>()
                    .is_ok_and(|ip| ip.is_loopback());
            (ok, port)
        }
    };
    let port_ok = port.is_none_or(|p| {
        !p.is_empty()
            && p.len() <= 5
            && p.bytes().all(|b| b.is_ascii_digit())
            && p.parse::<u32>().is_ok_and(|n| (1..=65535).contains(&n))
    });
    loopback && port_ok
}

/// Limits and checks before any route runs, and JSON for every error answer
/// (see the module documentation).
async fn guard(State(state): State<AppState>, req: Request, next: Next) -> Response {
    if let Some(e) = check_request_head(&state, &req) {
        return error_response(e);
    }
    // Read the body here, within the time limit; the routes get it from memory.
    let (parts, body) = req.into_parts();
    let bytes = match tokio::time::timeout(
        BODY_READ_TIMEOUT,
        axum::body::to_bytes(body, api::MAX_BODY_BYTES + 1),
    )
    .await
    {
        Ok(Ok(b)) => b,
        Ok(Err(_)) => {
            return error_response(ApiError {
                status: 413,
                message: format!(
                    "request body too large (limit {} bytes) or unreadable",
                    api::MAX_BODY_BYTES
                ),
            })
        }
        Err(_) => {
            return error_response(ApiError {
                status: 408,
                message: format!(
                    "request body not received within {} s",
                    BODY_READ_TIMEOUT.as_secs()
                ),
            })
        }
    };
    let response = next
        .run(Request::from_parts(parts, axum::body::Body::from(bytes)))
        .await;
    let mut response = json_errors(response);
    response.headers_mut().insert(
        header::X_FRAME_OPTIONS,
        header::HeaderValue::from_static("DENY"),
    );
    response
}

/// The request-head checks of [`guard`]: target length, head size, `Host`.
fn check_request_head(state: &AppState, req: &Request) -> Option<ApiError> {
    let target = req.uri().path_and_query().map_or(0, |p| p.as_str().len());
    if target > MAX_URI_BYTES {
        return Some(ApiError {
            status: 414,
            message: format!("request target of {target} bytes is longer than {MAX_URI_BYTES}"),
        });
    }
    let head: usize = req
        .headers()
        .iter()
        .map(|(n, v)| n.as_str().len() + v.len() + 4)
        .sum();
    if head > MAX_HEADER_BYTES {
        return Some(ApiError {
            status: 431,
            message: format!("request headers of {head} bytes exceed {MAX_HEADER_BYTES}"),
        });
    }
    if state.loopback_only {
        let hosts: Vec<_> = req.headers().get_all(header::HOST).iter().collect();
        if hosts.len() != 1 {
            return Some(ApiError {
                status: 400,
                message: format!(
                    "a request needs exactly one Host header, got {}",
                    hosts.len()
                ),
            });
        }
        let host = hosts[0].to_str().unwrap_or("");
        if !is_loopback_host(host) {
            return Some(ApiError {
                status: 403,
                message: format!(
                    "Host `{}` is not a loopback name; open the page as http://127.0.0.1:PORT/",
                    host.escape_debug()
                ),
            });
        }
    }
    if req.method() == axum::http::Method::POST {
        return cross_site(req.headers());
    }
    None
}

/// A POST a browser sent on behalf of another site: `Sec-Fetch-Site` other
/// than `same-origin` or `none` (typed by the user), or an `Origin` that is
/// not `http://` + this request's `Host`. Clients that are not browsers send
/// neither header and pass.
fn cross_site(headers: &HeaderMap) -> Option<ApiError> {
    let text = |name: &str| {
        headers
            .get(name)
            .map(|v| v.to_str().unwrap_or("(not text)").to_string())
    };
    if let Some(site) = text("sec-fetch-site") {
        if site != "same-origin" && site != "none" {
            return Some(ApiError {
                status: 403,
                message: format!(
                    "a request from another site (Sec-Fetch-Site: {}) may not change anything",
                    site.escape_debug()
                ),
            });
        }
    }
    if let Some(origin) = text("origin") {
        let own = text("host").map(|h| format!("http://{h}"));
        if own.as_deref() != Some(origin.as_str()) {
            return Some(ApiError {
                status: 403,
                message: format!(
                    "a request from origin `{}` may not change anything; use the page this \
                     server serves",
                    origin.escape_debug()
                ),
            });
        }
    }
    None
}

/// An error answer whose body is not JSON (axum's own 405, a rejection) gets
/// the `{ "error": "..." }` body with the status' reason.
fn json_errors(response: Response) -> Response {
    let status = response.status();
    let is_json = response
        .headers()
        .get(header::CONTENT_TYPE)
        .and_then(|v| v.to_str().ok())
        .is_some_and(|v| v.starts_with("application/json"));
    if !(status.is_client_error() || status.is_server_error()) || is_json {
        return response;
    }
    let (mut parts, _) = response.into_parts();
    let message = status
        .canonical_reason()
        .unwrap_or("error")
        .to_ascii_lowercase();
    let body = serde_json::to_vec(&ErrorBody { error: message }).unwrap_or_default();
    parts.headers.insert(
        header::CONTENT_TYPE,
        header::HeaderValue::from_static("application/json"),
    );
    parts.headers.remove(header::CONTENT_LENGTH);
    Response::from_parts(parts, axum::body::Body::from(body))
}

async fn method_not_allowed() -> Response {
    error_response(ApiError {
        status: 405,
        message: "method not allowed for this path".into(),
    })
}

/// Serve `router(state)` on an already bound listener until the process
/// ends, with the limits of the module documentation.
pub async fn serve(listener: tokio::net::TcpListener, state: AppState) -> std::io::Result<()> {
    use hyper_util::rt::{TokioIo, TokioTimer};
    let app = router(state);
    let permits = Arc::new(tokio::sync::Semaphore::new(MAX_CONNECTIONS));
    loop {
        let stream = match listener.accept().await {
            Ok((stream, _)) => stream,
            // Out of file descriptors and the like: wait, then accept again.
            Err(_) => {
                tokio::time::sleep(Duration::from_millis(50)).await;
                continue;
            }
        };
        let Ok(permit) = permits.clone().try_acquire_owned() else {
            tokio::spawn(conn::answer_and_close(
                stream,
                503,
                format!("server busy: more than {MAX_CONNECTIONS} connections; retry"),
            ));
            continue;
        };
        let service = hyper_util::service::TowerToHyperService::new(app.clone());
        tokio::spawn(async move {
            let _permit = permit;
            let mut stream = stream;
            let head = match conn::read_head(&mut stream).await {
                Ok(head) => head,
                Err(refused) => {
                    return conn::answer_and_close(stream, refused.status, refused.message).await
                }
            };
            let mut builder = hyper::server::conn::http1::Builder::new();
            builder
                .timer(TokioTimer::new())
                .keep_alive(false)
                .header_read_timeout(HEADER_READ_TIMEOUT)
                .max_header_size(HYPER_MAX_HEADER_BYTES);
            let io = TokioIo::new(conn::Replay::new(head, stream));
            let conn = builder.serve_connection(io, service);
            // Dropping the connection closes it.
            let _ = tokio::time::timeout(CONNECTION_LIFETIME, conn).await;
        });
    }
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

const JS: &str = "text/javascript; charset=utf-8";
const CSS: &str = "text/css; charset=utf-8";

/// A static asset of the page (the plotting library and beltune's plots on it).
async fn asset(content_type: &'static str, body: &'static str) -> Response {
    (
        [
            (header::CONTENT_TYPE, content_type),
            (header::CACHE_CONTROL, "no-store"),
        ],
        body,
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
        commissioned_verdict: model.commissioned_verdict,
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
