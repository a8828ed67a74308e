//! The one place where errors become HTTP responses.

use axum::Json;
use axum::http::{HeaderValue, StatusCode, header};
use axum::response::{IntoResponse, Response};
use serde::Serialize;
use utoipa::ToSchema;

use crate::decode::DecodeError;
use crate::detect::DetectError;
use crate::engine::EngineError;

/// Everything a request can fail with; each variant maps to exactly one status.
#[derive(Debug, thiserror::Error)]
pub enum ApiError {
    /// Malformed request: missing part, bad JSON, bad query value.
    #[error("{message}")]
    BadRequest {
        /// Machine-readable code.
        code: &'static str,
        /// What is wrong and how to fix it.
        message: String,
    },
    /// Body or pixel count over the configured limit.
    #[error("{message}")]
    TooLarge {
        /// Machine-readable code.
        code: &'static str,
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
        code: &'static str,
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
    /// The request took longer than its deadline.
    #[error("the request exceeded its deadline of {0} ms")]
    DeadlineExceeded(u64),
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
    pub code: String,
    /// What went wrong, for a person.
    pub message: String,
}

impl ApiError {
    /// A 400 with this code and message.
    pub fn bad_request(code: &'static str, message: impl Into<String>) -> Self {
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
            Self::QueueFull { .. } => StatusCode::TOO_MANY_REQUESTS,
            Self::DeadlineExceeded(_) => StatusCode::GATEWAY_TIMEOUT,
            Self::NotFound(_) => StatusCode::NOT_FOUND,
            Self::MethodNotAllowed(_) => StatusCode::METHOD_NOT_ALLOWED,
            Self::Internal(_) => StatusCode::INTERNAL_SERVER_ERROR,
        }
    }

    /// The stable code of this error.
    pub fn code(&self) -> &'static str {
        match self {
            Self::BadRequest { code, .. }
            | Self::TooLarge { code, .. }
            | Self::Unprocessable { code, .. } => code,
            Self::UnsupportedMediaType(_) => "unsupported_media_type",
            Self::QueueFull { .. } => "queue_full",
            Self::DeadlineExceeded(_) => "deadline_exceeded",
            Self::NotFound(_) => "not_found",
            Self::MethodNotAllowed(_) => "method_not_allowed",
            Self::Internal(_) => "internal",
        }
    }
}

impl From<DecodeError> for ApiError {
    fn from(e: DecodeError) -> Self {
        match e {
            DecodeError::Empty => Self::bad_request("empty_image", e.to_string()),
            DecodeError::Unsupported(_) => Self::UnsupportedMediaType(e.to_string()),
            DecodeError::TooManyPixels { .. } => Self::TooLarge {
                code: "too_many_pixels",
                message: e.to_string(),
            },
            DecodeError::Corrupt(_) | DecodeError::Unrecognised => Self::Unprocessable {
                code: "undecodable_image",
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
            EngineError::BadOptions(_) => return Self::bad_request("bad_options", e.to_string()),
            EngineError::UnknownPreset(..) => {
                return Self::bad_request("unknown_preset", e.to_string());
            }
            EngineError::InvalidParameter { .. } => "option_out_of_range",
            EngineError::EndpointOutside { .. } | EngineError::EndpointNotFinite { .. } => {
                "endpoint_outside_image"
            }
            EngineError::ImageTooSmall { .. } => "image_too_small",
            EngineError::BadConfidences { .. } => return Self::Internal(e.to_string()),
        };
        Self::Unprocessable {
            code,
            message: e.to_string(),
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
                code: self.code().to_string(),
                message,
            },
        };
        let mut response = (status, Json(body)).into_response();
        if let Self::QueueFull { retry_after_s, .. } = self {
            response
                .headers_mut()
                .insert(header::RETRY_AFTER, HeaderValue::from(retry_after_s));
        }
        response
    }
}
