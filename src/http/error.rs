//! The one place where errors become HTTP responses.

use axum::Json;
use axum::http::{HeaderValue, StatusCode, header};
use axum::response::{IntoResponse, Response};
use serde::Serialize;
use utoipa::ToSchema;

use crate::decode::DecodeError;
use crate::detect::DetectError;
use crate::engine::EngineError;
use crate::pipeline::PipelineError;

/// The stable, machine-readable code of every error the API answers with (the
/// `error.code` of the body).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, serde::Deserialize, ToSchema)]
#[serde(rename_all = "snake_case")]
pub enum ErrorCode {
    /// 400: the form has no `image` part.
    MissingImage,
    /// 400: the image part or body is empty.
    EmptyImage,
    /// 400: the multipart body is malformed or has an unknown part.
    BadMultipart,
    /// 400: the raw body could not be read.
    BadBody,
    /// 400: `endpoints` is not a JSON array of `[x, y]` pairs, or given twice.
    BadEndpoints,
    /// 400: `options` is not a JSON object of known parameters.
    BadOptions,
    /// 400: a query parameter is malformed.
    BadQuery,
    /// 400: no preset of that name.
    UnknownPreset,
    /// 413: the body is over the limit.
    BodyTooLarge,
    /// 413: the image has more pixels than allowed.
    TooManyPixels,
    /// 415: neither JPEG, PNG nor multipart.
    UnsupportedMediaType,
    /// 422: the image cannot be decoded.
    UndecodableImage,
    /// 422: an end lies outside the image or is not finite.
    EndpointOutsideImage,
    /// 422: more cable ends than `--max-endpoints`.
    TooManyEndpoints,
    /// 422: an option is out of its range.
    OptionOutOfRange,
    /// 422: the image is too small to segment.
    ImageTooSmall,
    /// 408: the body did not arrive within `--body-timeout-s`.
    BodyTimeout,
    /// 429: the queue is full.
    QueueFull,
    /// 429: the bodies in memory fill the upload budget.
    UploadBudgetFull,
    /// 503: the service is shutting down and cannot finish the request.
    ShuttingDown,
    /// 504: the deadline passed.
    DeadlineExceeded,
    /// 404: no such route.
    NotFound,
    /// 405: the route does not take this method.
    MethodNotAllowed,
    /// 500: a bug.
    Internal,
}

impl ErrorCode {
    /// The code as it appears in the body.
    pub fn as_str(self) -> &'static str {
        match self {
            Self::MissingImage => "missing_image",
            Self::EmptyImage => "empty_image",
            Self::BadMultipart => "bad_multipart",
            Self::BadBody => "bad_body",
            Self::BadEndpoints => "bad_endpoints",
            Self::BadOptions => "bad_options",
            Self::BadQuery => "bad_query",
            Self::UnknownPreset => "unknown_preset",
            Self::BodyTooLarge => "body_too_large",
            Self::TooManyPixels => "too_many_pixels",
            Self::UnsupportedMediaType => "unsupported_media_type",
            Self::UndecodableImage => "undecodable_image",
            Self::EndpointOutsideImage => "endpoint_outside_image",
            Self::TooManyEndpoints => "too_many_endpoints",
            Self::OptionOutOfRange => "option_out_of_range",
            Self::ImageTooSmall => "image_too_small",
            Self::BodyTimeout => "body_timeout",
            Self::QueueFull => "queue_full",
            Self::UploadBudgetFull => "upload_budget_full",
            Self::ShuttingDown => "shutting_down",
            Self::DeadlineExceeded => "deadline_exceeded",
            Self::NotFound => "not_found",
            Self::MethodNotAllowed => "method_not_allowed",
            Self::Internal => "internal",
        }
    }
}

/// Everything a request can fail with; each variant maps to exactly one status.
#[derive(Debug, thiserror::Error)]
pub enum ApiError {
    /// Malformed request: missing part, bad JSON, bad query value.
    #[error("{message}")]
    BadRequest {
        /// Machine-readable code.
        code: ErrorCode,
        /// What is wrong and how to fix it.
        message: String,
    },
    /// Body or pixel count over the configured limit.
    #[error("{message}")]
    TooLarge {
        /// Machine-readable code.
        code: ErrorCode,
        /// The limit and the offending size.
        message: String,
    },
    /// Neither JPEG/PNG nor multipart.
    #[error("{0}")]
    UnsupportedMediaType(String),
    /// Well-formed but unprocessable: undecodable image, ends outside, options out of range.
    #[error("{message}")]
    Unprocessable {
        /// Machine-readable code.
        code: ErrorCode,
        /// What is wrong.
        message: String,
    },
    /// The queue is full.
    #[error("the server is at capacity ({queue} requests queued); retry after {retry_after_s} s")]
    QueueFull {
        /// Queue length.
        queue: usize,
        /// Seconds to wait.
        retry_after_s: u64,
    },
    /// The request bodies in memory leave no room for this one's.
    #[error(
        "the request bodies being worked on fill the upload budget of {budget_bytes} bytes; retry after {retry_after_s} s"
    )]
    UploadBudgetFull {
        /// The configured budget.
        budget_bytes: usize,
        /// Seconds to wait.
        retry_after_s: u64,
    },
    /// The body was sent too slowly.
    #[error("the request body did not arrive within {timeout_s} s")]
    BodyTimeout {
        /// The configured limit.
        timeout_s: u64,
    },
    /// The service stopped before the request could be done.
    #[error(
        "the service is shutting down and could not finish this request; retry (another replica will answer)"
    )]
    ShuttingDown,
    /// The request took longer than its deadline.
    #[error("the request exceeded its deadline of {deadline_ms} ms")]
    DeadlineExceeded {
        /// The configured deadline.
        deadline_ms: u64,
    },
    /// No such route.
    #[error("no route for {0}")]
    NotFound(String),
    /// Route exists, method does not.
    #[error("method {0} is not allowed here")]
    MethodNotAllowed(String),
    /// A bug. The cause is logged, not sent.
    #[error("internal error")]
    Internal(String),
}

/// The JSON error body: `{"error": {"code": "...", "message": "..."}}`.
#[derive(Debug, Serialize, serde::Deserialize, ToSchema)]
pub struct ErrorBody {
    /// The error.
    pub error: ErrorDetail,
}

/// Code and message of an error.
#[derive(Debug, Serialize, serde::Deserialize, ToSchema)]
pub struct ErrorDetail {
    /// Stable machine-readable code, e.g. `queue_full`.
    pub code: ErrorCode,
    /// What went wrong, for a person.
    pub message: String,
}

impl ApiError {
    /// A 400 with this code and message.
    pub fn bad_request(code: ErrorCode, message: impl Into<String>) -> Self {
        Self::BadRequest {
            code,
            message: message.into(),
        }
    }

    /// The HTTP status of this error.
    pub fn status(&self) -> StatusCode {
        match self {
            Self::BadRequest { .. } => StatusCode::BAD_REQUEST,
            Self::TooLarge { .. } => StatusCode::PAYLOAD_TOO_LARGE,
            Self::UnsupportedMediaType(_) => StatusCode::UNSUPPORTED_MEDIA_TYPE,
            Self::Unprocessable { .. } => StatusCode::UNPROCESSABLE_ENTITY,
            Self::BodyTimeout { .. } => StatusCode::REQUEST_TIMEOUT,
            Self::ShuttingDown => StatusCode::SERVICE_UNAVAILABLE,
            Self::QueueFull { .. } | Self::UploadBudgetFull { .. } => StatusCode::TOO_MANY_REQUESTS,
            Self::DeadlineExceeded { .. } => StatusCode::GATEWAY_TIMEOUT,
            Self::NotFound(_) => StatusCode::NOT_FOUND,
            Self::MethodNotAllowed(_) => StatusCode::METHOD_NOT_ALLOWED,
            Self::Internal(_) => StatusCode::INTERNAL_SERVER_ERROR,
        }
    }

    /// True for the refusals answered before the request's body was read (or while it
    /// still arrived): over the body limit, no room in the queue or the upload budget,
    /// too slow.
    fn leaves_body_unread(&self) -> bool {
        matches!(
            self,
            Self::TooLarge {
                code: ErrorCode::BodyTooLarge,
                ..
            } | Self::QueueFull { .. }
                | Self::UploadBudgetFull { .. }
                | Self::BodyTimeout { .. }
        )
    }

    /// The stable code of this error.
    pub fn code(&self) -> ErrorCode {
        match self {
            Self::BadRequest { code, .. }
            | Self::TooLarge { code, .. }
            | Self::Unprocessable { code, .. } => *code,
            Self::UnsupportedMediaType(_) => ErrorCode::UnsupportedMediaType,
            Self::BodyTimeout { .. } => ErrorCode::BodyTimeout,
            Self::ShuttingDown => ErrorCode::ShuttingDown,
            Self::QueueFull { .. } => ErrorCode::QueueFull,
            Self::UploadBudgetFull { .. } => ErrorCode::UploadBudgetFull,
            Self::DeadlineExceeded { .. } => ErrorCode::DeadlineExceeded,
            Self::NotFound(_) => ErrorCode::NotFound,
            Self::MethodNotAllowed(_) => ErrorCode::MethodNotAllowed,
            Self::Internal(_) => ErrorCode::Internal,
        }
    }
}

impl From<DecodeError> for ApiError {
    fn from(e: DecodeError) -> Self {
        match e {
            DecodeError::Empty => Self::bad_request(ErrorCode::EmptyImage, e.to_string()),
            DecodeError::Unsupported(_) => Self::UnsupportedMediaType(e.to_string()),
            DecodeError::TooManyPixels { .. } => Self::TooLarge {
                code: ErrorCode::TooManyPixels,
                message: e.to_string(),
            },
            DecodeError::Corrupt(_) | DecodeError::Unrecognised => Self::Unprocessable {
                code: ErrorCode::UndecodableImage,
                message: e.to_string(),
            },
        }
    }
}

impl From<DetectError> for ApiError {
    fn from(e: DetectError) -> Self {
        Self::Internal(format!("endpoint detection: {e}"))
    }
}

impl From<EngineError> for ApiError {
    fn from(e: EngineError) -> Self {
        let code = match e {
            EngineError::BadOptions(_) => {
                return Self::bad_request(ErrorCode::BadOptions, e.to_string());
            }
            EngineError::UnknownPreset(..) => {
                return Self::bad_request(ErrorCode::UnknownPreset, e.to_string());
            }
            EngineError::InvalidParameter { .. } => ErrorCode::OptionOutOfRange,
            EngineError::EndpointOutside { .. } | EngineError::EndpointNotFinite { .. } => {
                ErrorCode::EndpointOutsideImage
            }
            EngineError::ImageTooSmall { .. } | EngineError::PhotoTooSmall { .. } => {
                ErrorCode::ImageTooSmall
            }
            // The service maps a passed deadline itself (it knows the configured one).
            EngineError::BadConfidences { .. }
            | EngineError::OtherImage { .. }
            | EngineError::DeadlineExceeded => {
                return Self::Internal(e.to_string());
            }
        };
        Self::Unprocessable {
            code,
            message: e.to_string(),
        }
    }
}

impl From<PipelineError> for ApiError {
    fn from(e: PipelineError) -> Self {
        match e {
            PipelineError::Decode(e) => e.into(),
            PipelineError::Detect(e) => e.into(),
            PipelineError::Engine(e) => e.into(),
            PipelineError::Encode(message) => Self::Internal(message),
            // The service always has a network: this is a bug.
            PipelineError::NoEnds(message) => Self::Internal(message.into()),
        }
    }
}

impl IntoResponse for ApiError {
    fn into_response(self) -> Response {
        let status = self.status();
        let message = match &self {
            Self::Internal(cause) => {
                tracing::error!(%cause, "internal error");
                "internal error; the cause is in the server log".to_string()
            }
            other => other.to_string(),
        };
        let body = ErrorBody {
            error: ErrorDetail {
                code: self.code(),
                message,
            },
        };
        let unread_body = self.leaves_body_unread();
        let mut response = (status, Json(body)).into_response();
        if let Self::QueueFull { retry_after_s, .. }
        | Self::UploadBudgetFull { retry_after_s, .. } = self
        {
            response
                .headers_mut()
                .insert(header::RETRY_AFTER, HeaderValue::from(retry_after_s));
        }
        // The rest of the body is still on the way: the connection cannot carry another
        // request, and saying so keeps a client from sending one on it.
        if unread_body {
            response
                .headers_mut()
                .insert(header::CONNECTION, HeaderValue::from_static("close"));
        }
        response
    }
}
