//! Liveness, readiness and metrics routes.

use std::sync::atomic::Ordering;

use axum::Json;
use axum::extract::State;
use axum::http::{StatusCode, header};
use axum::response::IntoResponse;
use serde::Serialize;
use utoipa::ToSchema;

use super::AppState;

/// Body of the health routes.
#[derive(Debug, Serialize, serde::Deserialize, ToSchema)]
pub struct Health {
    /// `ok`, `starting` or `draining`.
    pub status: String,
}

/// Liveness: the process answers. Never touches the model or the pool.
#[utoipa::path(get, path = "/healthz", responses((status = 200, description = "Alive", body = Health)), tag = "operations")]
pub async fn healthz() -> Json<Health> {
    Json(Health {
        status: "ok".into(),
    })
}

/// Readiness: 200 once warmed up, 503 before that and while draining.
#[utoipa::path(
    get,
    path = "/readyz",
    responses(
        (status = 200, description = "Ready for work", body = Health),
        (status = 503, description = "Starting or draining", body = Health),
    ),
    tag = "operations"
)]
pub async fn readyz(State(state): State<AppState>) -> (StatusCode, Json<Health>) {
    let status = if state.draining.load(Ordering::SeqCst) {
        "draining"
    } else if !state.ready.load(Ordering::SeqCst) {
        "starting"
    } else {
        return (
            StatusCode::OK,
            Json(Health {
                status: "ok".into(),
            }),
        );
    };
    (
        StatusCode::SERVICE_UNAVAILABLE,
        Json(Health {
            status: status.into(),
        }),
    )
}

/// Prometheus metrics in the text exposition format.
#[utoipa::path(
    get,
    path = "/metrics",
    responses((status = 200, description = "Prometheus text format", content_type = "text/plain")),
    tag = "operations"
)]
pub async fn metrics_text(State(state): State<AppState>) -> impl IntoResponse {
    let counts = state.pool.counts();
    ::metrics::gauge!(super::metrics::QUEUE_DEPTH).set(counts.queued.load(Ordering::SeqCst) as f64);
    ::metrics::gauge!(super::metrics::IN_FLIGHT).set(counts.running.load(Ordering::SeqCst) as f64);
    super::metrics::record_process();
    (
        [(header::CONTENT_TYPE, "text/plain; version=0.0.4")],
        super::metrics::handle().render(),
    )
}
