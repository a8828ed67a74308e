//! Running the service: warm-up, serving until a signal, graceful shutdown, logging.

use std::io::IsTerminal;
use std::pin::pin;
use std::sync::Arc;
use std::sync::atomic::Ordering;
use std::time::{Duration, Instant};

use hyper::server::conn::http1;
use hyper_util::rt::{TokioIo, TokioTimer};
use hyper_util::service::TowerToHyperService;
use tokio::net::TcpListener;
use tokio::sync::{Semaphore, watch};

use super::config::{LogFormat, Presets, ServeConfig};
use super::error::ApiError;
use super::router::app;
use super::state::AppState;
use crate::detect::OnnxDetector;

/// Largest request head (request line and headers), bytes: hyper answers a longer one
/// 431 (an overlong request line 414), with an empty body. 64 KiB holds the longest
/// `?endpoints=` the ends limit allows.
const MAX_HEAD_BYTES: usize = 64 * 1024;
/// Most headers in one request (hyper answers 431 past it).
const MAX_HEADERS: usize = 64;

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
/// `shutdown_delay_s`, stops accepting and gives open connections `shutdown_grace_s`
/// to finish their requests.
///
/// Each connection is HTTP/1.1 served by hyper with a header-read timeout (which also
/// closes connections idle between requests), and at most `max_connections` are open:
/// more wait in the listen backlog until one closes.
pub async fn serve(
    listener: TcpListener,
    state: AppState,
    shutdown: impl std::future::Future<Output = ()> + Send + 'static,
) -> std::io::Result<()> {
    let config = &state.config;
    let delay = Duration::from_secs(config.shutdown_delay_s);
    let grace = Duration::from_secs(config.shutdown_grace_s);
    let header_timeout = Duration::from_secs(config.header_timeout_s.max(1));
    let slots = Arc::new(Semaphore::new(config.max_connections.max(1)));
    let drain_state = state.clone();
    let mut stop = pin!(async move {
        shutdown.await;
        drain_state.draining.store(true, Ordering::SeqCst);
        tracing::info!(
            delay_s = delay.as_secs(),
            "shutdown requested: not ready, draining"
        );
        tokio::time::sleep(delay).await;
        let _ = drain_state.closed_at.set(Instant::now());
    });
    let router = app(state.clone());
    // Connections watch `closing` to finish gracefully; each holds a receiver of
    // `open`, whose sender sees them all gone when it is closed.
    let (closing_tx, closing_rx) = watch::channel(());
    let (open_tx, open_rx) = watch::channel(());
    loop {
        let slot = tokio::select! {
            slot = Arc::clone(&slots).acquire_owned() => slot.expect("the semaphore is never closed"),
            () = &mut stop => break,
        };
        let stream = tokio::select! {
            accepted = listener.accept() => match accepted {
                Ok((stream, _)) => stream,
                Err(e) => {
                    // Out of descriptors and the like: wait rather than spin.
                    tracing::warn!(error = %e, "accept failed");
                    tokio::time::sleep(Duration::from_millis(50)).await;
                    continue;
                }
            },
            () = &mut stop => break,
        };
        let service = TowerToHyperService::new(router.clone());
        let (mut closing, open) = (closing_rx.clone(), open_rx.clone());
        tokio::spawn(async move {
            let mut builder = http1::Builder::new();
            builder
                .timer(TokioTimer::new())
                .header_read_timeout(header_timeout)
                .max_header_size(MAX_HEAD_BYTES)
                .max_headers(MAX_HEADERS);
            let connection = builder.serve_connection(TokioIo::new(stream), service);
            let mut connection = pin!(connection);
            tokio::select! {
                _ = connection.as_mut() => {}
                _ = closing.changed() => {
                    connection.as_mut().graceful_shutdown();
                    let _ = connection.await;
                }
            }
            drop((slot, open));
        });
    }
    drop(listener);
    let _ = closing_tx.send(());
    drop(open_rx);
    // The last quarter of the grace (at most a second) is kept for answering 503 to
    // the requests that have not finished by then.
    let answering = (grace / 4).min(Duration::from_secs(1));
    if tokio::time::timeout(grace - answering, open_tx.closed())
        .await
        .is_err()
    {
        let _ = state.giving_up.send(true);
        if tokio::time::timeout(answering, open_tx.closed())
            .await
            .is_err()
        {
            tracing::warn!(
                grace_s = grace.as_secs(),
                "grace period over; exiting with connections open"
            );
        }
    }
    Ok(())
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
    // Colours only for a person at a terminal, never in a file or a log collector.
    let builder = tracing_subscriber::fmt()
        .with_env_filter(filter)
        .with_ansi(std::io::stdout().is_terminal());
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
pub fn run(config: ServeConfig) -> Result<(), String> {
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
    // One grace period in all: what the server's drain left of it.
    let spent = state
        .closed_at
        .get()
        .map_or(Duration::ZERO, Instant::elapsed);
    if !state.pool.wait_idle(grace.saturating_sub(spent)) {
        tracing::warn!("grace period over with worker jobs still running");
    }
    tracing::info!("stopped");
    Ok(())
}
