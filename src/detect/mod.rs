//! Perception: a network run through ONNX Runtime finds the cable ends the engine's
//! walks start from, so a photo alone is enough, and — the bundled cable-field model —
//! the cable field (cable probability and direction per cell) that guides the walks.
//!
//! - [`output`]: decoding of field, heatmap and YOLO outputs (pure, tested on hand-made
//!   tensors);
//! - [`OnnxDetector`]: ONNX Runtime loaded from a shared library at start-up, one session
//!   per worker.

pub mod field;
pub mod locate;
mod onnx;
pub mod output;

use std::path::PathBuf;
use std::str::FromStr;

use image::RgbImage;

use crate::engine::CableField;

pub use locate::default_runtime_candidates;
pub use onnx::OnnxDetector;

/// One detected end, photo pixels.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Detection {
    /// Position `[x, y]`.
    pub point: [f64; 2],
    /// Model confidence in 0..=1.
    pub confidence: f32,
}

/// What a network saw in one photo.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Perception {
    /// Cable ends, most confident first.
    pub ends: Vec<Detection>,
    /// Weaker terminal peaks (under the detection threshold, at or above the confirm
    /// threshold), most confident first: no walk starts from them, but one where a
    /// cable found from the other ends stops is reported as that cable's end
    /// ([`DetectorConfig::detect_confirm_threshold`]).
    pub candidates: Vec<Detection>,
    /// The cable field, from models that predict one.
    pub field: Option<CableField>,
}

impl Perception {
    /// Moves the ends under `threshold` to [`Perception::candidates`].
    pub fn split_candidates(mut self, threshold: f32) -> Self {
        let (ends, candidates) = self
            .ends
            .into_iter()
            .partition(|d| d.confidence >= threshold);
        self.ends = ends;
        self.candidates = candidates;
        self
    }
}

/// Finds cable ends (and, with a cable-field model, the cable field) in a photo.
pub trait EndpointDetector: Send + Sync {
    /// What the network sees in `image`, in `image`'s pixels.
    fn detect(&self, image: &RgbImage) -> Result<Perception, DetectError> {
        self.detect_as(image, [image.width(), image.height()])
    }

    /// What the network sees in `image` shown as a `size` (width, height) photo, in
    /// the pixels of that size: the network's input is resampled from `image` itself,
    /// so a photo segmented enlarged reaches the network without being enlarged first.
    fn detect_as(&self, image: &RgbImage, size: [u32; 2]) -> Result<Perception, DetectError>;
}

/// Errors loading or running a detector.
#[derive(Debug, thiserror::Error)]
pub enum DetectError {
    /// A detector setting is out of range.
    #[error("detector settings: {0}")]
    Settings(String),
    /// ONNX Runtime's shared library is missing or unusable.
    #[error("ONNX Runtime: {0}")]
    Runtime(String),
    /// The model file is missing, unreadable or not a valid model.
    #[error("model {path}: {message}")]
    Model {
        /// The file.
        path: PathBuf,
        /// What went wrong.
        message: String,
    },
    /// Inference failed.
    #[error("inference failed: {0}")]
    Inference(String),
    /// The model's output has an unexpected shape.
    #[error("unexpected model output: {0}")]
    Output(String),
}

/// The output convention of a model.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ModelKind {
    /// The cable field `[1, 6, H/s, W/s]` (the bundled model): cable probability,
    /// terminal heatmap, terminal x/y offsets, cos 2θ, sin 2θ.
    Field,
    /// Keypoint heatmap `[1, 1 or 3, H/s, W/s]` (ends only).
    Heatmap,
    /// Ultralytics YOLO detections: the raw head `[1, 4 + classes, N]`, or `[1, N, 6]`
    /// boxes of an nms=True or end-to-end export (told apart by the model's metadata);
    /// box centres become ends.
    Yolo,
}

impl ModelKind {
    /// What a free input side must be a multiple of: the model's deepest stride (8 for
    /// the cable field, whose stride-8 features are upsampled onto its stride-4 grid; a
    /// heatmap's 8 at most, YOLO's 32).
    pub fn stride(self) -> usize {
        match self {
            Self::Field | Self::Heatmap => 8,
            Self::Yolo => 32,
        }
    }

    /// The grey padding is filled with, in [0, 1]: ultralytics' 114 for YOLO (whose
    /// letterbox is also centred), mid-grey for the others.
    pub fn padding_grey(self) -> f32 {
        match self {
            Self::Field | Self::Heatmap => 0.5,
            Self::Yolo => 114.0 / 255.0,
        }
    }
}

impl FromStr for ModelKind {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        crate::choice::parse(
            s,
            &[
                ("field", Self::Field),
                ("heatmap", Self::Heatmap),
                ("yolo", Self::Yolo),
            ],
            "model kind",
        )
    }
}

/// Detector settings, shared by `ariadne serve`, `segment` and `eval` (the command line
/// fills them from flags; tests build them directly).
#[derive(Debug, Clone, PartialEq)]
pub struct DetectorConfig {
    /// ONNX model of cable ends.
    pub model: PathBuf,
    /// Output convention of the model.
    pub model_kind: ModelKind,
    /// Network input width for a 640x480 photo. A model with free input sides gets
    /// every photo at that scale in its own shape, padded to the kind's stride; a model
    /// that declares its size gets that size, the photo fitted keeping its aspect ratio.
    pub model_input_width: usize,
    /// Network input height.
    pub model_input_height: usize,
    /// Lowest detection confidence kept as an end (0.25: the best of 0.15-0.45 on
    /// backgrounds the network never saw, leave-one-background-out; docs/ACCURACY.md).
    pub detect_threshold: f32,
    /// Terminal peaks at or above this but under `detect_threshold` start no walk, but
    /// one where a cable found from the other ends stops is reported as its end, with
    /// its own confidence (docs/ACCURACY.md, "Ends a cable confirms"; at or above
    /// `detect_threshold`: none).
    pub detect_confirm_threshold: f32,
    /// Ends closer than this many photo pixels are merged (the more confident is kept).
    pub detect_nms_px: f64,
    /// With a cable-field model, ends with no cable probability of at least this within
    /// two cells are dropped (0 keeps every end; docs/ACCURACY.md).
    pub detect_min_cable: f32,
    /// ONNX Runtime threads per inference (it does not read container CPU limits itself).
    pub ort_threads: usize,
    /// ONNX Runtime shared library; `None` looks in the default places
    /// ([`default_runtime_candidates`]).
    pub ort_library: Option<PathBuf>,
}

impl Default for DetectorConfig {
    fn default() -> Self {
        Self {
            model: PathBuf::from("models/cable_field.onnx"),
            model_kind: ModelKind::Field,
            model_input_width: 320,
            model_input_height: 240,
            detect_threshold: 0.25,
            detect_confirm_threshold: 0.15,
            detect_nms_px: 10.0,
            detect_min_cable: 0.2,
            ort_threads: 1,
            ort_library: None,
        }
    }
}

impl DetectorConfig {
    /// Checks values a model cannot be run with.
    pub fn validate(&self) -> Result<(), String> {
        if self.model_input_width < 8 || self.model_input_height < 8 {
            return Err("model input must be at least 8x8 pixels".into());
        }
        if !(0.0..=1.0).contains(&self.detect_threshold) {
            return Err("detect threshold must lie in 0..=1".into());
        }
        if !(0.0..=1.0).contains(&self.detect_confirm_threshold) {
            return Err("detect confirm threshold must lie in 0..=1".into());
        }
        if self.detect_nms_px.is_nan() || self.detect_nms_px < 0.0 {
            return Err("detect NMS radius must be a non-negative number of pixels".into());
        }
        if !(0.0..=1.0).contains(&self.detect_min_cable) {
            return Err("detect minimum cable probability must lie in 0..=1".into());
        }
        if self.ort_threads == 0 {
            return Err("ONNX Runtime threads must be at least 1".into());
        }
        Ok(())
    }
}

/// The ends a segmentation starts from, with their confidences.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Ends {
    /// Positions `[x, y]`, pixels.
    pub points: Vec<[f64; 2]>,
    /// Confidence of each (1 for ends given by the caller).
    pub confidences: Vec<f32>,
}

impl Ends {
    /// Ends given by the caller.
    pub fn given(points: &[[f64; 2]]) -> Self {
        Self {
            confidences: vec![1.0; points.len()],
            points: points.to_vec(),
        }
    }

    /// Ends a network found.
    pub fn detected(found: &[Detection]) -> Self {
        Self {
            points: found.iter().map(|d| d.point).collect(),
            confidences: found.iter().map(|d| d.confidence).collect(),
        }
    }
}
