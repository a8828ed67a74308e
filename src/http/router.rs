//! The routes with their OpenAPI description, the fallbacks and the layers.

use axum::Router;
use axum::extract::DefaultBodyLimit;
use axum::http::Method;
use axum::middleware;
use utoipa::OpenApi;
use utoipa_axum::router::OpenApiRouter;
use utoipa_axum::routes;
use utoipa_swagger_ui::SwaggerUi;

use super::error::ApiError;
use super::state::AppState;
use super::{health, metrics, page, request_id, segment};

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
    let model = &state.config.detector.model;
    metrics::record_build_info(
        &model
            .file_name()
            .unwrap_or(model.as_os_str())
            .to_string_lossy(),
    );
    let (router, api) = routes().split_for_parts();
    let body_limit = state.config.max_body_bytes;
    router
        .merge(SwaggerUi::new("/docs").url("/openapi.json", api))
        .route("/", axum::routing::get(page::index))
        .fallback(not_found)
        .method_not_allowed_fallback(method_not_allowed)
        .route_layer(middleware::from_fn_with_state(
            state.clone(),
            metrics::record_requests,
        ))
        .layer(DefaultBodyLimit::max(body_limit))
        .layer(middleware::from_fn(request_id::layer))
        .with_state(state)
}

async fn not_found(method: Method, uri: axum::http::Uri) -> ApiError {
    metrics::count_request("unmatched", 404, None);
    ApiError::NotFound(format!("{method} {}", uri.path()))
}

async fn method_not_allowed(method: Method, uri: axum::http::Uri) -> ApiError {
    metrics::count_request("unmatched", 405, None);
    ApiError::MethodNotAllowed(format!("{method} (on {})", uri.path()))
}
