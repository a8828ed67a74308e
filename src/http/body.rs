//! Reading the body of `POST /segment`: a multipart form (`image`, optional
//! `endpoints` and `options`, each at most once) or a raw JPEG/PNG. Media types are
//! matched exactly (parameters allowed); `application/octet-stream` is read as a raw
//! image whose format the decoder tells from its bytes.

use axum::body::Bytes;
use axum::extract::{FromRequest, Multipart, Request};
use axum::http::header;
use serde_json::{Map, Value};

use super::error::{ApiError, ErrorCode};
use super::metrics;
use super::state::AppState;

/// What a request body holds.
pub struct Body {
    /// The image file.
    pub image: Bytes,
    /// The `endpoints` part, unparsed.
    pub endpoints: Option<String>,
    /// The `options` part.
    pub options: Option<Map<String, Value>>,
}

/// Reads the image and the optional `endpoints` and `options` from a multipart form or
/// a raw JPEG/PNG body.
pub async fn read_body(state: &AppState, request: Request) -> Result<Body, ApiError> {
    let content_type = request
        .headers()
        .get(header::CONTENT_TYPE)
        .and_then(|v| v.to_str().ok())
        .unwrap_or("")
        .to_ascii_lowercase();
    let media_type = content_type.split(';').next().unwrap_or("").trim();
    if let Some(len) = request
        .headers()
        .get(header::CONTENT_LENGTH)
        .and_then(|v| v.to_str().ok()?.parse::<usize>().ok())
        && len > state.config.max_body_bytes
    {
        metrics::reject("body_too_large");
        return Err(too_large_body(state.config.max_body_bytes));
    }
    if media_type == "multipart/form-data" {
        let mut form = Multipart::from_request(request, state)
            .await
            .map_err(|e| ApiError::bad_request(ErrorCode::BadMultipart, e.body_text()))?;
        let (mut image, mut ends, mut options) = (None, None, None);
        loop {
            let field = match form.next_field().await {
                Ok(Some(f)) => f,
                Ok(None) => break,
                Err(e) => return Err(multipart_error(state, e)),
            };
            let name = field.name().unwrap_or("").to_string();
            let seen = match name.as_str() {
                "image" => image.is_some(),
                "endpoints" => ends.is_some(),
                "options" => options.is_some(),
                other => {
                    return Err(ApiError::bad_request(
                        ErrorCode::BadMultipart,
                        format!("unknown form part `{other}` (expected image, endpoints, options)"),
                    ));
                }
            };
            if seen {
                return Err(ApiError::bad_request(
                    ErrorCode::BadMultipart,
                    format!("the form has more than one `{name}` part; give it once"),
                ));
            }
            match name.as_str() {
                "image" => {
                    image = Some(field.bytes().await.map_err(|e| multipart_error(state, e))?)
                }
                // An empty text part is no part (a form left blank).
                "endpoints" => {
                    let text = field.text().await.map_err(|e| multipart_error(state, e))?;
                    ends = Some(text).filter(|t| !t.trim().is_empty());
                }
                _ => {
                    let text = field.text().await.map_err(|e| multipart_error(state, e))?;
                    if !text.trim().is_empty() {
                        options = Some(parse_options(&text)?);
                    }
                }
            }
        }
        let image = image.ok_or_else(|| {
            ApiError::bad_request(ErrorCode::MissingImage, "the form has no `image` part")
        })?;
        if image.is_empty() {
            return Err(ApiError::bad_request(
                ErrorCode::EmptyImage,
                "the `image` part is empty",
            ));
        }
        return Ok(Body {
            image,
            endpoints: ends,
            options,
        });
    }
    if matches!(
        media_type,
        "image/jpeg" | "image/png" | "application/octet-stream"
    ) {
        let body = Bytes::from_request(request, state)
            .await
            .map_err(|e| body_error(state, e.status(), e.body_text(), ErrorCode::BadBody))?;
        if body.is_empty() {
            return Err(ApiError::bad_request(
                ErrorCode::EmptyImage,
                "the request body is empty",
            ));
        }
        return Ok(Body {
            image: body,
            endpoints: None,
            options: None,
        });
    }
    Err(ApiError::UnsupportedMediaType(format!(
        "unsupported Content-Type `{content_type}`: send multipart/form-data with an `image` part, or the raw image as image/jpeg, image/png or application/octet-stream"
    )))
}

/// The `options` part: a JSON object, each key at most once.
fn parse_options(text: &str) -> Result<Map<String, Value>, ApiError> {
    let bad = |message: String| ApiError::bad_request(ErrorCode::BadOptions, message);
    let UniqueKeys(map) = serde_json::from_str(text).map_err(|e| {
        bad(format!(
            "`options` must be a JSON object, each key once: {e}"
        ))
    })?;
    Ok(map)
}

/// A JSON object whose keys are all different (serde_json would keep the last of two).
struct UniqueKeys(Map<String, Value>);

impl<'de> serde::Deserialize<'de> for UniqueKeys {
    fn deserialize<D: serde::Deserializer<'de>>(deserializer: D) -> Result<Self, D::Error> {
        struct Visitor;
        impl<'de> serde::de::Visitor<'de> for Visitor {
            type Value = UniqueKeys;
            fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
                f.write_str("a JSON object")
            }
            fn visit_map<A: serde::de::MapAccess<'de>>(
                self,
                mut access: A,
            ) -> Result<UniqueKeys, A::Error> {
                let mut map = Map::new();
                while let Some((key, value)) = access.next_entry::<String, Value>()? {
                    if map.contains_key(&key) {
                        return Err(serde::de::Error::custom(format_args!(
                            "key `{key}` appears twice"
                        )));
                    }
                    map.insert(key, value);
                }
                Ok(UniqueKeys(map))
            }
        }
        deserializer.deserialize_map(Visitor)
    }
}

fn too_large_body(limit: usize) -> ApiError {
    ApiError::TooLarge {
        code: ErrorCode::BodyTooLarge,
        message: format!("the request body is over the limit of {limit} bytes"),
    }
}

fn multipart_error(state: &AppState, e: axum::extract::multipart::MultipartError) -> ApiError {
    body_error(state, e.status(), e.body_text(), ErrorCode::BadMultipart)
}

/// A body that could not be read: over the limit (413, counted), or malformed (400 with
/// `code`).
fn body_error(
    state: &AppState,
    status: axum::http::StatusCode,
    text: String,
    code: ErrorCode,
) -> ApiError {
    if status == axum::http::StatusCode::PAYLOAD_TOO_LARGE {
        metrics::reject("body_too_large");
        too_large_body(state.config.max_body_bytes)
    } else {
        ApiError::bad_request(code, text)
    }
}
