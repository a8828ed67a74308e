//! The HTTP service: a thin shell that parses requests, schedules the engine on a
//! bounded worker pool and serialises its results.
//!
//! Routes: `POST /segment`, `GET /healthz`, `GET /readyz`, `GET /metrics`,
//! `GET /openapi.json`, `GET /docs`.

pub mod config;
pub mod error;
mod health;
pub mod metrics;
pub mod pool;
pub mod request_id;
mod segment;

use std::ops::Deref;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};

use axum::Router;
use axum::extract::{DefaultBodyLimit, MatchedPath, Request};
use axum::http::Method;
use axum::middleware::{self, Next};
use axum::response::Response;
use tokio::net::TcpListener;
use utoipa::OpenApi;
use utoipa_axum::router::OpenApiRouter;
use utoipa_axum::routes;
use utoipa_swagger_ui::SwaggerUi;

pub use config::{LogFormat, Presets, ServeArgs};
pub use error::ApiError;
use pool::WorkerPool;

use crate::detect::{EndpointDetector, OnnxDetector};

/// Shared state of the service: configuration, presets, the pool and the life-cycle
/// flags. Cheap to clone.
#[derive(Clone)]
pub struct AppState(Arc<Inner>);

/// What [`AppState`] holds.
pub struct Inner {
    /// Settings.
    pub config: ServeArgs,
    /// Named parameter sets.
    pub presets: Presets,
    /// Where CPU work runs.
    pub pool: WorkerPool,
    /// Finds ends when a request gives none.
    pub detector: Arc<dyn EndpointDetector>,
    /// True once warmed up.
    pub ready: AtomicBool,
    /// True once shutdown has begun.
    pub draining: AtomicBool,
}

impl Deref for AppState {
    type Target = Inner;
    fn deref(&self) -> &Inner {
        &self.0
    }
}

impl AppState {
    /// State for `config`: presets loaded, pool started, not yet ready.
    pub fn new(
        config: ServeArgs,
        presets: Presets,
        detector: Arc<dyn EndpointDetector>,
    ) -> std::io::Result<Self> {
        let pool = WorkerPool::new(config.worker_count(), config.queue)?;
        Ok(Self(Arc::new(Inner {
            config,
            presets,
            pool,
            detector,
            ready: AtomicBool::new(false),
            draining: AtomicBool::new(false),
        })))
    }
}

#[derive(OpenApi)]
#[openapi(
    info(
        title = "Ariadne",
        description = "Cable segmentation and B-spline centrelines from a photo, by walks on superpixel graphs."
    ),
    tags(
        (name = "segmentation", description = "Finding cables"),
        (name = "operations", description = "Health, readiness and metrics"),
    )
)]
struct ApiDoc;

/// The routes with their OpenAPI description.
fn routes() -> OpenApiRouter<AppState> {
    OpenApiRouter::with_openapi(ApiDoc::openapi())
        .routes(routes!(segment::segment))
        .routes(routes!(health::healthz))
        .routes(routes!(health::readyz))
        .routes(routes!(health::metrics_text))
}

/// The OpenAPI document generated from the routes.
pub fn openapi() -> utoipa::openapi::OpenApi {
    routes().into_openapi()
}

/// The application: all routes, limits and middleware over `state`.
pub fn app(state: AppState) -> Router {
    // Install the recorder now: what is recorded before it exists is lost.
    metrics::handle();
    let (router, api) = routes().split_for_parts();
    let body_limit = state.config.max_body_bytes;
    router
        .merge(SwaggerUi::new("/docs").url("/openapi.json", api))
        .fallback(not_found)
        .method_not_allowed_fallback(method_not_allowed)
        .route_layer(middleware::from_fn_with_state(
            state.clone(),
            record_metrics,
        ))
        .layer(DefaultBodyLimit::max(body_limit))
        .layer(middleware::from_fn(request_id::layer))
        .with_state(state)
}

async fn not_found(method: Method, uri: axum::http::Uri) -> ApiError {
    count_request("unmatched", 404, "none");
    ApiError::NotFound(format!("{method} {}", uri.path()))
}

async fn method_not_allowed(method: Method, uri: axum::http::Uri) -> ApiError {
    count_request("unmatched", 405, "none");
    ApiError::MethodNotAllowed(format!("{method} (on {})", uri.path()))
}

fn count_request(route: &str, status: u16, preset: &str) {
    ::metrics::counter!(
        metrics::REQUESTS,
        "route" => route.to_string(),
        "status_class" => metrics::status_class(status),
        "preset" => preset.to_string()
    )
    .increment(1);
}

/// Counts and times every request to a known route.
async fn record_metrics(
    axum::extract::State(state): axum::extract::State<AppState>,
    request: Request,
    next: Next,
) -> Response {
    let started = Instant::now();
    let route = request
        .extensions()
        .get::<MatchedPath>()
        .map_or_else(|| "unmatched".to_string(), |m| m.as_str().to_string());
    let preset = preset_label(&state, request.uri().query());
    let response = next.run(request).await;
    let status = response.status().as_u16();
    count_request(&route, status, &preset);
    ::metrics::histogram!(
        metrics::REQUEST_SECONDS,
        "route" => route,
        "status_class" => metrics::status_class(status)
    )
    .record(started.elapsed().as_secs_f64());
    response
}

/// The preset label of a request: a known preset's name, `default` when none is
/// named, `unknown` otherwise (so callers cannot grow the label set).
fn preset_label(state: &AppState, query: Option<&str>) -> String {
    let named = query.and_then(|q| {
        serde_urlencoded::from_str::<Vec<(String, String)>>(q)
            .ok()?
            .into_iter()
            .find(|(k, _)| k == "preset")
            .map(|(_, v)| v)
    });
    match named {
        None => "default".into(),
        Some(name) if state.presets.get(&name).is_some() => name,
        Some(_) => "unknown".into(),
    }
}

/// Runs one small segmentation on the pool so that the first real request does not pay
/// for lazy initialisation, then marks the service ready. (The detector has already run
/// once per session when it was loaded.)
pub async fn warm_up(state: &AppState) -> Result<(), ApiError> {
    let spec = crate::synth::SceneSpec {
        width: 160,
        height: 120,
        cables: 2,
        cable_width: 8.0,
        background: crate::synth::Background::Plain,
        seed: 1,
    };
    let params = state.presets.get("default").cloned().unwrap_or_default();
    let job = state
        .pool
        .try_submit(move || {
            let scene = crate::synth::scene(&spec);
            crate::engine::segment(&scene.image, &scene.ends(), &params).map(|s| s.cables.len())
        })
        .map_err(|_| ApiError::Internal("pool full during warm-up".into()))?;
    let started = job
        .await
        .map_err(|_| ApiError::Internal("warm-up job dropped".into()))?
        .map_err(|p| ApiError::Internal(format!("warm-up panicked: {}", p.0)))?;
    started.value?;
    state.ready.store(true, Ordering::SeqCst);
    Ok(())
}

/// Serves `state` on `listener` until `shutdown` resolves; then turns not-ready, waits
/// `shutdown_delay_s`, stops accepting and gives in-flight requests
/// `shutdown_grace_s` to finish.
pub async fn serve(
    listener: TcpListener,
    state: AppState,
    shutdown: impl std::future::Future<Output = ()> + Send + 'static,
) -> std::io::Result<()> {
    let delay = Duration::from_secs(state.config.shutdown_delay_s);
    let grace = Duration::from_secs(state.config.shutdown_grace_s);
    let (signalled_tx, mut signalled_rx) = tokio::sync::watch::channel(false);
    let drain_state = state.clone();
    let stop = async move {
        shutdown.await;
        drain_state.draining.store(true, Ordering::SeqCst);
        tracing::info!(
            delay_s = delay.as_secs(),
            "shutdown requested: not ready, draining"
        );
        tokio::time::sleep(delay).await;
        let _ = signalled_tx.send(true);
    };
    let server = axum::serve(listener, app(state)).with_graceful_shutdown(stop);
    let grace_timer = async move {
        while !*signalled_rx.borrow() {
            if signalled_rx.changed().await.is_err() {
                std::future::pending::<()>().await;
            }
        }
        tokio::time::sleep(grace).await;
    };
    tokio::select! {
        result = server => result,
        () = grace_timer => {
            tracing::warn!(grace_s = grace.as_secs(), "grace period over; exiting with requests in flight");
            Ok(())
        }
    }
}

/// Resolves on SIGTERM or SIGINT.
pub async fn shutdown_signal() {
    let ctrl_c = async {
        let _ = tokio::signal::ctrl_c().await;
    };
    #[cfg(unix)]
    let term = async {
        match tokio::signal::unix::signal(tokio::signal::unix::SignalKind::terminate()) {
            Ok(mut s) => {
                s.recv().await;
            }
            Err(_) => std::future::pending::<()>().await,
        }
    };
    #[cfg(not(unix))]
    let term = std::future::pending::<()>();
    tokio::select! {
        () = ctrl_c => {},
        () = term => {},
    }
}

/// Installs the log subscriber (`RUST_LOG` filters, default `info`).
pub fn init_logging(format: LogFormat) {
    let filter = tracing_subscriber::EnvFilter::try_from_default_env()
        .unwrap_or_else(|_| tracing_subscriber::EnvFilter::new("info"));
    let builder = tracing_subscriber::fmt().with_env_filter(filter);
    let _ = match format {
        LogFormat::Text => builder.try_init(),
        LogFormat::Json => builder
            .json()
            .flatten_event(true)
            .with_current_span(true)
            .try_init(),
    };
}

/// `ariadne serve`: load presets and the detector (a bad model stops it here), start
/// the pool, bind, warm up, serve until a signal.
pub fn run(config: ServeArgs) -> Result<(), String> {
    init_logging(config.log_format);
    let presets = Presets::load(config.presets.as_deref()).map_err(|e| e.to_string())?;
    let detector = OnnxDetector::load(&config.detector, config.worker_count())
        .map_err(|e| format!("endpoint detector: {e}"))?;
    tracing::info!(model = %config.detector.model.display(), ?detector, "endpoint detector loaded");
    let runtime = tokio::runtime::Builder::new_multi_thread()
        .enable_all()
        .build()
        .map_err(|e| format!("cannot start the async runtime: {e}"))?;
    let grace = Duration::from_secs(config.shutdown_grace_s);
    let state = runtime.block_on(async move {
        let state = AppState::new(config.clone(), presets, Arc::new(detector))
            .map_err(|e| format!("cannot start workers: {e}"))?;
        let listener = TcpListener::bind(config.bind)
            .await
            .map_err(|e| format!("cannot listen on {}: {e}", config.bind))?;
        tracing::info!(
            bind = %config.bind,
            workers = state.pool.workers(),
            queue = state.pool.queue_capacity(),
            "listening"
        );
        let warm = state.clone();
        tokio::spawn(async move {
            match warm_up(&warm).await {
                Ok(()) => tracing::info!("warmed up: ready"),
                Err(e) => tracing::error!(error = %e, "warm-up failed: staying not ready"),
            }
        });
        serve(listener, state.clone(), shutdown_signal())
            .await
            .map_err(|e| format!("server error: {e}"))?;
        Ok::<_, String>(state)
    })?;
    if !state.pool.wait_idle(grace) {
        tracing::warn!("grace period over with worker jobs still running");
    }
    tracing::info!("stopped");
    Ok(())
}
