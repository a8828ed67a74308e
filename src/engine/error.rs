//! Errors of the engine: every variant carries the offending values.

use thiserror::Error;

/// Everything that can go wrong inside the pure engine.
#[derive(Debug, Error, Clone, PartialEq)]
pub enum EngineError {
    /// The caller's deadline passed before the work was done.
    #[error("the deadline passed before the segmentation was done")]
    DeadlineExceeded,
    /// A parameter is outside its allowed range.
    #[error("parameter `{name}` = {value} is out of range: {expected}")]
    InvalidParameter {
        /// Parameter name as spelled in presets and option overrides.
        name: &'static str,
        /// The rejected value, printed.
        value: String,
        /// What would have been accepted.
        expected: String,
    },
    /// An options object that does not parse as parameter overrides (unknown field,
    /// wrong type).
    #[error("invalid options: {0}")]
    BadOptions(String),
    /// An unknown preset name was asked for.
    #[error("unknown preset `{0}` (known: {1})")]
    UnknownPreset(String, String),
    /// An end point lies outside the image.
    #[error(
        "endpoint #{index} ({}, {}) lies outside the {width}x{height} image",
        compact(*.x),
        compact(*.y)
    )]
    EndpointOutside {
        /// Position of the end in the given list.
        index: usize,
        /// Horizontal coordinate, pixels.
        x: f64,
        /// Vertical coordinate, pixels.
        y: f64,
        /// Image width, pixels.
        width: u32,
        /// Image height, pixels.
        height: u32,
    },
    /// An end point is not a finite number.
    #[error("endpoint #{index} is not a finite coordinate pair")]
    EndpointNotFinite {
        /// Position of the end in the given list.
        index: usize,
    },
    /// [`crate::engine::segment_oversegmented`] was given the superpixels of an image
    /// of another size (a bug of the caller).
    #[error("superpixels of a {}x{} image given with a {}x{} image", .superpixels[0], .superpixels[1], .image[0], .image[1])]
    OtherImage {
        /// Width and height the superpixels were made for.
        superpixels: [usize; 2],
        /// Width and height of the image given with them.
        image: [u32; 2],
    },
    /// Not one confidence per end.
    #[error("{confidences} confidences for {ends} ends")]
    BadConfidences {
        /// Number of ends.
        ends: usize,
        /// Number of confidences.
        confidences: usize,
    },
    /// The image is too small to segment with the given parameters.
    #[error("image {width}x{height} is too small: at least {min}x{min} pixels are needed")]
    ImageTooSmall {
        /// Image width, pixels.
        width: u32,
        /// Image height, pixels.
        height: u32,
        /// Smallest accepted side, pixels.
        min: u32,
    },
    /// The photo is too small even at the largest enlargement the parameters allow.
    #[error(
        "photo {width}x{height} is too small: enlarged as far as allowed (max_upscale {max_upscale}) \
         it is {working_width}x{working_height} pixels, and at least {min}x{min} are needed"
    )]
    PhotoTooSmall {
        /// Photo width, pixels.
        width: u32,
        /// Photo height, pixels.
        height: u32,
        /// Width it would be segmented at, pixels.
        working_width: u32,
        /// Height it would be segmented at, pixels.
        working_height: u32,
        /// The largest enlargement allowed.
        max_upscale: f32,
        /// Smallest accepted side of the working image, pixels.
        min: u32,
    },
}

/// A number as a person reads it in a message: plain when moderate, in scientific
/// notation when huge or tiny (`1e308`, not 309 digits).
pub fn compact(v: f64) -> String {
    let a = v.abs();
    if a != 0.0 && !(1e-3..1e6).contains(&a) {
        format!("{v:e}")
    } else {
        format!("{v}")
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn numbers_in_messages_are_compact() {
        assert_eq!(compact(1e308), "1e308");
        assert_eq!(compact(-2.5e-7), "-2.5e-7");
        assert_eq!(compact(640.5), "640.5");
        assert_eq!(compact(0.0), "0");
        let e = EngineError::EndpointOutside {
            index: 0,
            x: 1e308,
            y: 2.0,
            width: 640,
            height: 480,
        };
        assert_eq!(
            e.to_string(),
            "endpoint #0 (1e308, 2) lies outside the 640x480 image"
        );
    }
}
