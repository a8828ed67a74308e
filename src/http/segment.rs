//! `POST /segment`: parse the request, run the work in the pool, answer.

use std::sync::Arc;
use std::time::{Duration, Instant};

use tokio::sync::OwnedSemaphorePermit;

use axum::body::Bytes;
use axum::extract::{RawQuery, Request, State};
use axum::http::{HeaderValue, header};
use axum::response::{IntoResponse, Response};
use serde::Deserialize;
use utoipa::{IntoParams, ToSchema};

use super::body::{Body, read_body};
use super::error::{ApiError, ErrorBody, ErrorCode};
use super::metrics;
use super::request_id::RequestId;
use super::state::{AppState, UPLOAD_UNIT};
use crate::decode;
use crate::detect::EndpointDetector;
use crate::engine::{self, Deadline, EngineError, MaskKind, Params};
use crate::pipeline::{self, PipelineError};
use crate::report::{self, SegmentResponse};

/// Query parameters of `POST /segment`.
#[derive(Debug, Default, Deserialize, IntoParams)]
#[serde(deny_unknown_fields)]
#[into_params(parameter_in = Query)]
pub struct SegmentQuery {
    // No `example`s: Swagger UI's "Try it out" would send them as values.
    /// Named parameter set (`default` when absent, `clutter`, `paper`, or one from the
    /// presets file).
    pub preset: Option<String>,
    /// Mask kind: `binary` (0/255, default), `labels` (cable k = k+1), `color`.
    #[param(value_type = Option<String>)]
    pub mask: Option<MaskKind>,
    /// Also return the photo with the curves drawn on it (`overlay_png`).
    pub overlay: Option<bool>,
    /// `json` (default) or `png` to receive only the mask PNG.
    #[param(value_type = Option<String>)]
    pub format: Option<ResponseFormat>,
    /// Cable ends for raw-body requests, URL-encoded JSON such as
    /// `[[120,40],[300,210]]`; absent: the network finds them.
    pub endpoints: Option<String>,
}

/// What the response body is.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum ResponseFormat {
    /// The JSON document.
    #[default]
    Json,
    /// The mask PNG alone.
    Png,
}

/// The multipart form of `POST /segment`.
#[derive(Debug, ToSchema)]
#[allow(dead_code)] // documents the form for OpenAPI; parsed field by field
pub struct SegmentForm {
    /// The photograph, JPEG or PNG.
    #[schema(value_type = String, format = Binary)]
    image: Vec<u8>,
    /// Cable ends as JSON `[[x, y], ...]`, pixels; absent or empty: the network finds
    /// them.
    #[schema(example = "")]
    endpoints: Option<String>,
    /// Parameter overrides as a JSON object, e.g. `{"n_segments": 1500}`; absent or
    /// empty: none.
    #[schema(example = "")]
    options: Option<String>,
}

/// A JPEG or PNG file.
#[derive(Debug, ToSchema)]
#[schema(value_type = String, format = Binary)]
#[allow(dead_code)] // documents binary bodies for OpenAPI; never constructed
pub struct ImageBytes(Vec<u8>);

/// Everything parsed from one request, ready for a worker.
struct Job {
    image: Bytes,
    /// The caller's ends; `None` runs the detector.
    ends: Option<Vec<[f64; 2]>>,
    detector: Arc<dyn EndpointDetector>,
    params: Params,
    mask: MaskKind,
    overlay: bool,
    format: ResponseFormat,
    request_id: String,
    max_pixels: u64,
    /// When the handler stops waiting, and the configured deadline it came from.
    deadline: (Instant, u64),
}

/// The finished work: the mask PNG alone, or the document (its queue time and total
/// are filled in by the handler, which alone knows them).
enum Output {
    Png { png: Vec<u8>, cables: usize },
    Json(Box<SegmentResponse>),
}

/// Segment one image.
#[utoipa::path(
    post,
    path = "/segment",
    params(SegmentQuery),
    request_body(
        description = "The photo: multipart form (each part at most once), or the raw JPEG/PNG as the body (application/octet-stream: the format is read from the bytes)",
        content(
            (SegmentForm = "multipart/form-data"),
            (ImageBytes = "image/jpeg"),
            (ImageBytes = "image/png"),
            (ImageBytes = "application/octet-stream"),
        )
    ),
    responses(
        (status = 200, description = "Cables found", content(
            (SegmentResponse = "application/json"),
            (ImageBytes = "image/png"),
        )),
        (status = 400, description = "Malformed request: no image part, a part or option key given twice, bad JSON in a part, bad query value", body = ErrorBody),
        (status = 413, description = "Body or pixel count over the limit", body = ErrorBody),
        (status = 408, description = "The body did not arrive within --body-timeout-s", body = ErrorBody),
        (status = 415, description = "Not JPEG, PNG or multipart", body = ErrorBody),
        (status = 422, description = "Undecodable or truncated image, ends outside the image or more than --max-endpoints, options out of range", body = ErrorBody),
        (status = 429, description = "Queue full, or the upload budget full; see Retry-After", body = ErrorBody),
        (status = 500, description = "Bug; the server stays up", body = ErrorBody),
        (status = 503, description = "Shutting down: the drain grace ran out before this request could be done", body = ErrorBody),
        (status = 504, description = "Deadline exceeded", body = ErrorBody),
    ),
    tag = "segmentation"
)]
pub async fn segment(
    State(state): State<AppState>,
    RawQuery(query): RawQuery,
    request_id: axum::Extension<RequestId>,
    request: Request,
) -> Result<Response, ApiError> {
    let started = Instant::now();
    let deadline_ms = state.config.deadline_ms;
    let deadline = started + Duration::from_millis(deadline_ms);
    // Admission before the body is read: room in the upload budget for what it
    // declares (held until the work ends) and in the queue.
    let upload = admit(&state, &request)?;
    // The body is read before the query is judged, so that a client still uploading
    // gets its 400 rather than a reset connection.
    let timeout_s = state.config.body_timeout_s;
    let body = tokio::time::timeout(Duration::from_secs(timeout_s), read_body(&state, request))
        .await
        .map_err(|_| {
            metrics::reject("body_timeout");
            ApiError::BodyTimeout { timeout_s }
        })??;
    let job = parse(
        &state,
        query.as_deref(),
        body,
        request_id.0.0.clone(),
        (deadline, deadline_ms),
    )?;
    let span = tracing::Span::current();
    let stopping = state.giving_up.subscribe();
    let spare = state.pool.spare_probe();
    let receiver = state
        .pool
        .try_submit(move || {
            let _entered = span.enter();
            let _upload = upload;
            if *stopping.borrow() {
                // The handler has answered 503: skip the work.
                return Err(ApiError::ShuttingDown);
            }
            if Instant::now() >= deadline {
                // Nobody is waiting for this answer any more: skip the work.
                return Err(ApiError::DeadlineExceeded { deadline_ms });
            }
            // The network beside SLIC only when a worker would otherwise idle: under
            // load every CPU already has a request of its own.
            run_job(job, spare.has_spare_worker())
        })
        .map_err(|_| {
            metrics::reject("queue_full");
            ApiError::QueueFull {
                queue: state.pool.queue_capacity(),
                retry_after_s: state.config.retry_after_s,
            }
        })?;
    let mut giving_up = state.giving_up.subscribe();
    let give_up = async move {
        loop {
            if *giving_up.borrow_and_update() || giving_up.changed().await.is_err() {
                return;
            }
        }
    };
    let finished = tokio::select! {
        finished = tokio::time::timeout_at(deadline.into(), receiver) => finished,
        () = give_up => {
            metrics::reject("shutting_down");
            return Err(ApiError::ShuttingDown);
        }
    };
    let started_job = match finished {
        Err(_) => {
            metrics::reject("deadline");
            return Err(ApiError::DeadlineExceeded { deadline_ms });
        }
        Ok(Err(_)) => return Err(ApiError::Internal("worker dropped the job".into())),
        Ok(Ok(Err(panic))) => {
            return Err(ApiError::Internal(format!("worker panicked: {}", panic.0)));
        }
        Ok(Ok(Ok(started_job))) => started_job,
    };
    let output = started_job.value.inspect_err(|e| {
        if matches!(e, ApiError::DeadlineExceeded { .. }) {
            metrics::reject("deadline");
        }
    })?;
    metrics::stage("queue", started_job.queued_ms);
    match output {
        Output::Png { png, cables } => {
            ::metrics::histogram!(metrics::CABLES).record(cables as f64);
            Ok((
                [(header::CONTENT_TYPE, HeaderValue::from_static("image/png"))],
                png,
            )
                .into_response())
        }
        Output::Json(mut response) => {
            ::metrics::histogram!(metrics::CABLES).record(response.cables.len() as f64);
            response.timings_ms.queue = started_job.queued_ms;
            response.timings_ms.total = started.elapsed().as_secs_f64() * 1e3;
            Ok(axum::Json(response).into_response())
        }
    }
}

/// Admits a request before its body is read: a share of the upload budget for the
/// length it declares (the body limit when it declares none), and a free place in the
/// queue; otherwise 429 at once.
fn admit(state: &AppState, request: &Request) -> Result<OwnedSemaphorePermit, ApiError> {
    let limit = state.config.max_body_bytes;
    let declared = request
        .headers()
        .get(header::CONTENT_LENGTH)
        .and_then(|v| v.to_str().ok()?.parse::<usize>().ok())
        .unwrap_or(limit)
        .min(limit);
    let units = u32::try_from(declared.div_ceil(UPLOAD_UNIT).max(1)).unwrap_or(u32::MAX);
    let retry_after_s = state.config.retry_after_s;
    if state
        .pool
        .counts()
        .queued
        .load(std::sync::atomic::Ordering::SeqCst)
        >= state.pool.queue_capacity()
    {
        metrics::reject("queue_full");
        return Err(ApiError::QueueFull {
            queue: state.pool.queue_capacity(),
            retry_after_s,
        });
    }
    Arc::clone(&state.uploads)
        .try_acquire_many_owned(units)
        .map_err(|_| {
            metrics::reject("upload_budget");
            ApiError::UploadBudgetFull {
                budget_bytes: state.config.upload_budget_bytes,
                retry_after_s,
            }
        })
}

/// Judges the query and the parts, and checks the image's type and pixel count from its
/// header, before any work is queued.
fn parse(
    state: &AppState,
    query: Option<&str>,
    body: Body,
    request_id: String,
    deadline: (Instant, u64),
) -> Result<Job, ApiError> {
    let query: SegmentQuery = match query {
        None | Some("") => SegmentQuery::default(),
        Some(q) => serde_urlencoded::from_str(q).map_err(|e| {
            ApiError::bad_request(ErrorCode::BadQuery, format!("invalid query string: {e}"))
        })?,
    };
    if body.endpoints.is_some() && query.endpoints.is_some() {
        return Err(ApiError::bad_request(
            ErrorCode::BadEndpoints,
            "endpoints given both in the query and in the form; give them once",
        ));
    }
    let ends = match body.endpoints.or(query.endpoints) {
        Some(text) => Some(report::parse_endpoints(&text).map_err(|e| {
            ApiError::bad_request(
                ErrorCode::BadEndpoints,
                format!("endpoints must be a JSON array of [x, y] pairs: {e}"),
            )
        })?),
        None => None,
    };
    let limit = state.config.max_endpoints;
    if let Some(ends) = ends.as_ref().filter(|e| e.len() > limit) {
        metrics::reject("too_many_endpoints");
        return Err(ApiError::Unprocessable {
            code: ErrorCode::TooManyEndpoints,
            message: format!(
                "{} cable ends given, over the limit of {limit} per request",
                ends.len()
            ),
        });
    }
    let preset = query.preset.as_deref().unwrap_or("default");
    let base = state.presets.get(preset).ok_or_else(|| {
        ApiError::bad_request(
            ErrorCode::UnknownPreset,
            format!(
                "unknown preset `{preset}` (known: {})",
                state.presets.names().join(", ")
            ),
        )
    })?;
    let params = match body.options {
        Some(o) => base.with_overrides(&o)?,
        None => base.clone(),
    };
    let (w, h) = decode::dimensions(&body.image)?;
    let pixels = w as u64 * h as u64;
    if pixels > state.config.max_pixels {
        metrics::reject("too_many_pixels");
        return Err(decode::DecodeError::TooManyPixels {
            width: w,
            height: h,
            pixels,
            limit: state.config.max_pixels,
        }
        .into());
    }
    if let Some(ends) = &ends {
        engine::validate_ends(ends, w, h)?;
    }
    Ok(Job {
        image: body.image,
        ends,
        detector: state.detector.clone(),
        params,
        mask: query.mask.unwrap_or_default(),
        overlay: query.overlay.unwrap_or(false),
        format: query.format.unwrap_or_default(),
        request_id,
        max_pixels: state.config.max_pixels,
        deadline,
    })
}

/// The CPU part of a request, on a worker: the pipeline (with `overlap`, the network
/// on a second thread beside SLIC), its stages recorded.
fn run_job(job: Job, overlap: bool) -> Result<Output, ApiError> {
    let json = job.format == ResponseFormat::Json;
    let out = pipeline::run(&pipeline::Job {
        bytes: &job.image,
        ends: job.ends.as_deref(),
        network: Some(job.detector.as_ref()),
        params: &job.params,
        max_pixels: job.max_pixels,
        mask: job.mask,
        overlay: job.overlay && json,
        encode: true,
        deadline: Deadline(Some(job.deadline.0)),
        overlap,
    })
    .map_err(|e| match e {
        PipelineError::Engine(EngineError::DeadlineExceeded) => ApiError::DeadlineExceeded {
            deadline_ms: job.deadline.1,
        },
        other => other.into(),
    })?;
    for (name, ms) in out.timings.stages() {
        // Inference is timed only when it ran.
        if name != "endpoints" || out.network_ran {
            metrics::stage(name, ms);
        }
    }
    Ok(if json {
        Output::Json(Box::new(SegmentResponse::new(&out, job.request_id)))
    } else {
        Output::Png {
            cables: out.segmentation.cables.len(),
            png: out.mask_png.unwrap_or_default(),
        }
    })
}
