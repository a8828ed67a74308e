//! `POST /segment`: parse the request, run the work in the pool, answer.

use std::sync::Arc;
use std::time::{Duration, Instant};

use axum::body::Bytes;
use axum::extract::{FromRequest, Multipart, RawQuery, Request, State};
use axum::http::{HeaderValue, header};
use axum::response::{IntoResponse, Response};
use serde::Deserialize;
use serde_json::{Map, Value};
use utoipa::{IntoParams, ToSchema};

use super::AppState;
use super::error::{ApiError, ErrorBody};
use super::metrics;
use super::request_id::RequestId;
use crate::decode;
use crate::detect::{EndpointDetector, Ends};
use crate::engine::{self, MaskKind, Params, render};
use crate::report::{self, CableReport, SegmentResponse, Timings};

/// Query parameters of `POST /segment`.
#[derive(Debug, Default, Deserialize, IntoParams)]
#[serde(deny_unknown_fields)]
#[into_params(parameter_in = Query)]
pub struct SegmentQuery {
    /// Named parameter set (`default`, `clutter`, or one from the presets file).
    #[param(example = "default")]
    pub preset: Option<String>,
    /// Mask kind: `binary` (0/255, default), `labels` (cable k = k+1), `color`.
    #[param(value_type = Option<String>, example = "binary")]
    pub mask: Option<MaskKind>,
    /// Also return the photo with the curves drawn on it (`overlay_png`).
    pub overlay: Option<bool>,
    /// `json` (default) or `png` to receive only the mask PNG.
    #[param(value_type = Option<String>, example = "json")]
    pub format: Option<ResponseFormat>,
    /// Cable ends for raw-body requests, URL-encoded JSON `[[x,y],...]`.
    #[param(example = "[[120,40],[300,210]]")]
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
    /// Cable ends as JSON `[[x, y], ...]`, pixels; when given, detection is skipped.
    endpoints: Option<String>,
    /// Parameter overrides as a JSON object, e.g. `{"n_segments": 1500}`.
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
        description = "The photo: multipart form, or the raw JPEG/PNG as the body",
        content(
            (SegmentForm = "multipart/form-data"),
            (ImageBytes = "image/jpeg"),
            (ImageBytes = "image/png"),
        )
    ),
    responses(
        (status = 200, description = "Cables found", content(
            (SegmentResponse = "application/json"),
            (ImageBytes = "image/png"),
        )),
        (status = 400, description = "Malformed request: no image part, bad JSON in a part, bad query value", body = ErrorBody),
        (status = 413, description = "Body or pixel count over the limit", body = ErrorBody),
        (status = 415, description = "Not JPEG, PNG or multipart", body = ErrorBody),
        (status = 422, description = "Undecodable or truncated image, ends outside the image, options out of range", body = ErrorBody),
        (status = 429, description = "Queue full; see Retry-After", body = ErrorBody),
        (status = 500, description = "Bug; the server stays up", body = ErrorBody),
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
    let deadline = started + Duration::from_millis(state.config.deadline_ms);
    // The body is read before the query is judged, so that a client still uploading
    // gets its 400 rather than a reset connection.
    let (image, part_ends, options) = read_body(&state, request).await?;
    let query: SegmentQuery = match query.as_deref() {
        None | Some("") => SegmentQuery::default(),
        Some(q) => serde_urlencoded::from_str(q).map_err(|e| {
            ApiError::bad_request("bad_query", format!("invalid query string: {e}"))
        })?,
    };
    if part_ends.is_some() && query.endpoints.is_some() {
        return Err(ApiError::bad_request(
            "bad_endpoints",
            "endpoints given both in the query and in the form; give them once",
        ));
    }
    let ends = match part_ends.or(query.endpoints) {
        Some(text) => Some(report::parse_endpoints(&text).map_err(|e| {
            ApiError::bad_request(
                "bad_endpoints",
                format!("endpoints must be a JSON array of [x, y] pairs: {e}"),
            )
        })?),
        None => None,
    };
    let preset = query.preset.as_deref().unwrap_or("default");
    let base = state.presets.get(preset).ok_or_else(|| {
        ApiError::bad_request(
            "unknown_preset",
            format!(
                "unknown preset `{preset}` (known: {})",
                state.presets.names().join(", ")
            ),
        )
    })?;
    let params = match options {
        Some(o) => base.with_overrides(&o)?,
        None => base.clone(),
    };
    // Header-only checks before the work is queued: type, then pixel count.
    let (w, h) = decode::dimensions(&image)?;
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

    let job = Job {
        image,
        ends,
        detector: state.detector.clone(),
        params,
        mask: query.mask.unwrap_or_default(),
        overlay: query.overlay.unwrap_or(false),
        format: query.format.unwrap_or_default(),
        request_id: request_id.0.0.clone(),
    };
    let span = tracing::Span::current();
    let max_pixels = state.config.max_pixels;
    let receiver = state
        .pool
        .try_submit(move || {
            let _entered = span.enter();
            if Instant::now() >= deadline {
                // Nobody is waiting for this answer any more: skip the work.
                return Err(ApiError::DeadlineExceeded(0));
            }
            run_job(job, max_pixels)
        })
        .map_err(|_| {
            metrics::reject("queue_full");
            ApiError::QueueFull {
                queue: state.pool.queue_capacity(),
                retry_after_s: state.config.retry_after_s,
            }
        })?;
    let finished = tokio::time::timeout_at(deadline.into(), receiver).await;
    let started_job = match finished {
        Err(_) => {
            metrics::reject("deadline");
            return Err(ApiError::DeadlineExceeded(state.config.deadline_ms));
        }
        Ok(Err(_)) => return Err(ApiError::Internal("worker dropped the job".into())),
        Ok(Ok(Err(panic))) => {
            return Err(ApiError::Internal(format!("worker panicked: {}", panic.0)));
        }
        Ok(Ok(Ok(started_job))) => started_job,
    };
    let output = match started_job.value {
        Err(ApiError::DeadlineExceeded(_)) => {
            metrics::reject("deadline");
            return Err(ApiError::DeadlineExceeded(state.config.deadline_ms));
        }
        other => other?,
    };
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

/// Reads the image and the optional `endpoints` and `options` from a multipart form or
/// a raw JPEG/PNG body.
async fn read_body(
    state: &AppState,
    request: Request,
) -> Result<(Bytes, Option<String>, Option<Map<String, Value>>), ApiError> {
    let content_type = request
        .headers()
        .get(header::CONTENT_TYPE)
        .and_then(|v| v.to_str().ok())
        .unwrap_or("")
        .to_ascii_lowercase();
    if let Some(len) = request
        .headers()
        .get(header::CONTENT_LENGTH)
        .and_then(|v| v.to_str().ok()?.parse::<usize>().ok())
        && len > state.config.max_body_bytes
    {
        metrics::reject("body_too_large");
        return Err(too_large_body(state.config.max_body_bytes));
    }
    if content_type.starts_with("multipart/form-data") {
        let mut form = Multipart::from_request(request, state)
            .await
            .map_err(|e| ApiError::bad_request("bad_multipart", e.body_text()))?;
        let (mut image, mut ends, mut options) = (None, None, None);
        loop {
            let field = match form.next_field().await {
                Ok(Some(f)) => f,
                Ok(None) => break,
                Err(e) => return Err(multipart_error(state, e)),
            };
            let name = field.name().unwrap_or("").to_string();
            match name.as_str() {
                "image" => {
                    image = Some(field.bytes().await.map_err(|e| multipart_error(state, e))?)
                }
                "endpoints" => {
                    ends = Some(field.text().await.map_err(|e| multipart_error(state, e))?)
                }
                "options" => {
                    let text = field.text().await.map_err(|e| multipart_error(state, e))?;
                    let map: Map<String, Value> = serde_json::from_str(&text).map_err(|e| {
                        ApiError::bad_request(
                            "bad_options",
                            format!("`options` must be a JSON object: {e}"),
                        )
                    })?;
                    options = Some(map);
                }
                other => {
                    return Err(ApiError::bad_request(
                        "bad_multipart",
                        format!("unknown form part `{other}` (expected image, endpoints, options)"),
                    ));
                }
            }
        }
        let image = image.ok_or_else(|| {
            ApiError::bad_request("missing_image", "the form has no `image` part")
        })?;
        if image.is_empty() {
            return Err(ApiError::bad_request(
                "empty_image",
                "the `image` part is empty",
            ));
        }
        return Ok((image, ends, options));
    }
    if content_type.starts_with("image/jpeg") || content_type.starts_with("image/png") {
        let body = Bytes::from_request(request, state)
            .await
            .map_err(|e| body_error(state, e.status(), e.body_text(), "bad_body"))?;
        if body.is_empty() {
            return Err(ApiError::bad_request(
                "empty_image",
                "the request body is empty",
            ));
        }
        return Ok((body, None, None));
    }
    Err(ApiError::UnsupportedMediaType(format!(
        "unsupported Content-Type `{content_type}`: send multipart/form-data with an `image` part, or the raw image as image/jpeg or image/png"
    )))
}

fn too_large_body(limit: usize) -> ApiError {
    ApiError::TooLarge {
        code: "body_too_large",
        message: format!("the request body is over the limit of {limit} bytes"),
    }
}

fn multipart_error(state: &AppState, e: axum::extract::multipart::MultipartError) -> ApiError {
    body_error(state, e.status(), e.body_text(), "bad_multipart")
}

/// A body that could not be read: over the limit (413, counted), or malformed (400 with
/// `code`).
fn body_error(
    state: &AppState,
    status: axum::http::StatusCode,
    text: String,
    code: &'static str,
) -> ApiError {
    if status == axum::http::StatusCode::PAYLOAD_TOO_LARGE {
        metrics::reject("body_too_large");
        too_large_body(state.config.max_body_bytes)
    } else {
        ApiError::bad_request(code, text)
    }
}

/// The CPU part of a request: decode, segment, draw, encode. Runs on a worker.
fn run_job(job: Job, max_pixels: u64) -> Result<Output, ApiError> {
    let t = Instant::now();
    let image = decode::decode_rgb(&job.image, max_pixels)?;
    let decode_ms = ms(t);
    let ends = match job.ends {
        Some(points) => Ends::given(points),
        None => {
            let found = Ends::detected(job.detector.as_ref(), &image)?;
            metrics::stage("endpoints", found.detect_ms);
            found
        }
    };
    let seg =
        engine::segment_with_confidence(&image, &ends.points, &ends.confidences, &job.params)?;
    let t = Instant::now();
    let mask = render::render_mask(&seg, job.mask, job.params.mask_width_px);
    let overlay = job.overlay.then(|| render::overlay(&image, &seg));
    let mask_ms = ms(t);
    let t = Instant::now();
    let mask_png = report::mask_png(&mask);
    let output = match job.format {
        ResponseFormat::Png => Output::Png {
            png: mask_png,
            cables: seg.cables.len(),
        },
        ResponseFormat::Json => {
            let overlay_png = overlay.map(|o| {
                report::base64(&report::png(
                    o.as_raw(),
                    o.width(),
                    o.height(),
                    image::ExtendedColorType::Rgb8,
                ))
            });
            Output::Json(Box::new(SegmentResponse {
                request_id: job.request_id,
                width: seg.width,
                height: seg.height,
                cables: seg.cables.iter().map(CableReport::from).collect(),
                endpoints: report::endpoint_reports(&seg, &ends.points, &ends.confidences),
                mask_png: report::base64(&mask_png),
                overlay_png,
                timings_ms: Timings {
                    decode: decode_ms,
                    endpoints: ends.detect_ms,
                    mask: mask_ms,
                    encode: ms(t),
                    ..Timings::default()
                }
                .with_engine(&seg),
            }))
        }
    };
    for (name, value) in [
        ("decode", decode_ms),
        ("superpixels", seg.timings.superpixels),
        ("graph", seg.timings.graph),
        ("walks", seg.timings.walks),
        ("splines", seg.timings.splines),
        ("mask", mask_ms),
        ("encode", ms(t)),
    ] {
        metrics::stage(name, value);
    }
    Ok(output)
}

fn ms(t: Instant) -> f64 {
    t.elapsed().as_secs_f64() * 1e3
}
