//! The flags of every sub-command (clap lives here and nowhere below the command line):
//! each settings struct has an environment twin per flag and becomes the plain config
//! the library takes.

use std::net::SocketAddr;
use std::path::PathBuf;

use clap::ValueEnum;

use crate::detect::{DetectorConfig, ModelKind};
use crate::engine::MaskKind;
use crate::http::{LogFormat, ServeConfig};

/// Mask kinds on the command line.
#[derive(Debug, Clone, Copy, ValueEnum)]
pub enum MaskArg {
    /// 0/255.
    Binary,
    /// Cable k has value k+1.
    Labels,
    /// Each cable in its own colour.
    Color,
}

impl From<MaskArg> for MaskKind {
    fn from(m: MaskArg) -> Self {
        match m {
            MaskArg::Binary => MaskKind::Binary,
            MaskArg::Labels => MaskKind::Labels,
            MaskArg::Color => MaskKind::Color,
        }
    }
}

/// Detector flags, shared by `serve`, `segment` and `eval`.
#[derive(Debug, Clone, clap::Args)]
pub struct DetectorArgs {
    /// ONNX model of cable ends.
    #[arg(long, env = "ARIADNE_MODEL", default_value_os_t = DetectorConfig::default().model)]
    pub model: PathBuf,
    /// Output convention of the model: field (the bundled cable-field model: ends and
    /// cable field), heatmap (ends only) or yolo (an ultralytics export: `[1, 4+classes,
    /// N]`, or `[1, 300, 6]` from nms=True / end-to-end exports; box centres become ends).
    #[arg(long, env = "ARIADNE_MODEL_KIND", default_value = "field")]
    pub model_kind: ModelKind,
    /// Network input width; the photo is resized to fit, keeping its aspect ratio.
    #[arg(long, env = "ARIADNE_MODEL_INPUT_WIDTH", default_value_t = DetectorConfig::default().model_input_width)]
    pub model_input_width: usize,
    /// Network input height.
    #[arg(long, env = "ARIADNE_MODEL_INPUT_HEIGHT", default_value_t = DetectorConfig::default().model_input_height)]
    pub model_input_height: usize,
    /// Lowest detection confidence kept as an end.
    #[arg(long, env = "ARIADNE_DETECT_THRESHOLD", default_value_t = DetectorConfig::default().detect_threshold)]
    pub detect_threshold: f32,
    /// Weaker terminal peaks (at or above this, under --detect-threshold) start no
    /// walk, but are reported as ends where a cable found from the other ends stops.
    #[arg(long, env = "ARIADNE_DETECT_CONFIRM_THRESHOLD", default_value_t = DetectorConfig::default().detect_confirm_threshold)]
    pub detect_confirm_threshold: f32,
    /// Ends closer than this many photo pixels are merged (the more confident is kept).
    #[arg(long, env = "ARIADNE_DETECT_NMS_PX", default_value_t = DetectorConfig::default().detect_nms_px)]
    pub detect_nms_px: f64,
    /// With a cable-field model, drop ends with no cable probability of at least this
    /// within two cells (0 keeps every end).
    #[arg(long, env = "ARIADNE_DETECT_MIN_CABLE", default_value_t = DetectorConfig::default().detect_min_cable)]
    pub detect_min_cable: f32,
    /// ONNX Runtime threads per inference (it does not read container CPU limits itself).
    #[arg(long, env = "ARIADNE_ORT_THREADS", default_value_t = DetectorConfig::default().ort_threads)]
    pub ort_threads: usize,
    /// ONNX Runtime shared library (libonnxruntime.so 1.31) [default: .ort/, next to
    /// the executable, /usr/local/lib; `make setup` fetches it].
    #[arg(long, env = "ORT_DYLIB_PATH")]
    pub ort_library: Option<PathBuf>,
}

impl From<DetectorArgs> for DetectorConfig {
    fn from(a: DetectorArgs) -> Self {
        Self {
            model: a.model,
            model_kind: a.model_kind,
            model_input_width: a.model_input_width,
            model_input_height: a.model_input_height,
            detect_threshold: a.detect_threshold,
            detect_confirm_threshold: a.detect_confirm_threshold,
            detect_nms_px: a.detect_nms_px,
            detect_min_cable: a.detect_min_cable,
            ort_threads: a.ort_threads,
            ort_library: a.ort_library,
        }
    }
}

/// Flags of `ariadne serve`.
#[derive(Debug, Clone, clap::Args)]
pub struct ServeArgs {
    /// Address to listen on.
    #[arg(long, env = "ARIADNE_BIND", default_value_t = ServeConfig::default().bind)]
    pub bind: SocketAddr,
    /// Worker threads for CPU work [default: the CPUs available to the process].
    #[arg(long, env = "ARIADNE_WORKERS")]
    pub workers: Option<usize>,
    /// Requests that may wait for a worker; more are answered 429 at once.
    #[arg(long, env = "ARIADNE_QUEUE", default_value_t = ServeConfig::default().queue)]
    pub queue: usize,
    /// Per-request deadline in milliseconds, queueing included; later answers are 504.
    #[arg(long, env = "ARIADNE_DEADLINE_MS", default_value_t = ServeConfig::default().deadline_ms)]
    pub deadline_ms: u64,
    /// Largest accepted request body, bytes.
    #[arg(long, env = "ARIADNE_MAX_BODY_BYTES", default_value_t = ServeConfig::default().max_body_bytes)]
    pub max_body_bytes: usize,
    /// Largest accepted image, pixels (width × height, read from the header).
    #[arg(long, env = "ARIADNE_MAX_PIXELS", default_value_t = ServeConfig::default().max_pixels)]
    pub max_pixels: u64,
    /// Most cable ends one request may give; more are answered 422.
    #[arg(long, env = "ARIADNE_MAX_ENDPOINTS", default_value_t = ServeConfig::default().max_endpoints)]
    pub max_endpoints: usize,
    /// Most open connections; more wait in the listen backlog until one closes.
    #[arg(long, env = "ARIADNE_MAX_CONNECTIONS", default_value_t = ServeConfig::default().max_connections)]
    pub max_connections: usize,
    /// Seconds a connection gets to send a request's headers, and most seconds an
    /// open connection may stay idle between requests.
    #[arg(long, env = "ARIADNE_HEADER_TIMEOUT_S", default_value_t = ServeConfig::default().header_timeout_s)]
    pub header_timeout_s: u64,
    /// Seconds a request gets to send its body; slower ones are answered 408.
    #[arg(long, env = "ARIADNE_BODY_TIMEOUT_S", default_value_t = ServeConfig::default().body_timeout_s)]
    pub body_timeout_s: u64,
    /// Request bodies in memory at once, bytes; a request that would go over is
    /// answered 429 before its body is read.
    #[arg(long, env = "ARIADNE_UPLOAD_BUDGET_BYTES", default_value_t = ServeConfig::default().upload_budget_bytes)]
    pub upload_budget_bytes: usize,
    /// Seconds `Retry-After` asks rejected clients to wait.
    #[arg(long, env = "ARIADNE_RETRY_AFTER_S", default_value_t = ServeConfig::default().retry_after_s)]
    pub retry_after_s: u64,
    /// JSON file of extra or overriding presets: {"name": {"n_segments": 1500, ...}, ...}.
    #[arg(long, env = "ARIADNE_PRESETS")]
    pub presets: Option<PathBuf>,
    /// Log format: text or json.
    #[arg(long, env = "ARIADNE_LOG_FORMAT", default_value = "text")]
    pub log_format: LogFormat,
    /// Seconds between a shutdown signal and closing the listener, during which
    /// /readyz answers 503 so that load balancers stop sending work.
    #[arg(long, env = "ARIADNE_SHUTDOWN_DELAY_S", default_value_t = ServeConfig::default().shutdown_delay_s)]
    pub shutdown_delay_s: u64,
    /// Seconds in-flight requests get to finish after the listener closes.
    #[arg(long, env = "ARIADNE_SHUTDOWN_GRACE_S", default_value_t = ServeConfig::default().shutdown_grace_s)]
    pub shutdown_grace_s: u64,
    /// The endpoint detector, run when a request gives no ends.
    #[command(flatten)]
    pub detector: DetectorArgs,
}

impl From<ServeArgs> for ServeConfig {
    fn from(a: ServeArgs) -> Self {
        Self {
            bind: a.bind,
            workers: a.workers,
            queue: a.queue,
            deadline_ms: a.deadline_ms,
            max_body_bytes: a.max_body_bytes,
            max_pixels: a.max_pixels,
            max_endpoints: a.max_endpoints,
            max_connections: a.max_connections,
            header_timeout_s: a.header_timeout_s,
            body_timeout_s: a.body_timeout_s,
            upload_budget_bytes: a.upload_budget_bytes,
            retry_after_s: a.retry_after_s,
            presets: a.presets,
            log_format: a.log_format,
            shutdown_delay_s: a.shutdown_delay_s,
            shutdown_grace_s: a.shutdown_grace_s,
            detector: a.detector.into(),
        }
    }
}

/// Arguments of `ariadne segment`.
#[derive(Debug, clap::Args)]
pub struct SegmentArgs {
    /// JPEG or PNG photograph.
    pub image: PathBuf,
    /// Cable ends as a JSON array of pixel coordinates, e.g. '[[120,40],[300,210.5]]'.
    #[arg(long)]
    pub endpoints: Option<String>,
    /// Parameter preset (default, clutter).
    #[arg(long, default_value = "default")]
    pub preset: String,
    /// Parameter overrides as a JSON object, e.g. '{"n_segments": 1500}'.
    #[arg(long)]
    pub options: Option<String>,
    /// Write the JSON result here ('-' for standard output). It embeds the mask and
    /// the overlay only when they are not written to files (`mask_png` is then "").
    #[arg(long)]
    pub json: Option<PathBuf>,
    /// Write the mask PNG here.
    #[arg(long)]
    pub mask: Option<PathBuf>,
    /// Kind of mask written by --mask.
    #[arg(long, value_enum, default_value = "binary")]
    pub mask_kind: MaskArg,
    /// Write the photo with the curves drawn on it here (PNG).
    #[arg(long)]
    pub overlay: Option<PathBuf>,
    /// The endpoint detector, used when --endpoints is not given.
    #[command(flatten)]
    pub detector: DetectorArgs,
}

/// Where `eval` takes the cable ends from.
#[derive(Debug, Clone, Copy, ValueEnum)]
pub enum EndsArg {
    /// The true terminals: ends of the annotated centrelines not on the border.
    Gt,
    /// The endpoint detector's.
    Detect,
}

/// Arguments of `ariadne eval`.
#[derive(Debug, clap::Args)]
pub struct EvalArgs {
    /// Dataset folder [default: $ARIADNE_DATASET or ../shared/datasets/cables].
    #[arg(long)]
    pub dataset: Option<PathBuf>,
    /// Source of the cable ends.
    #[arg(long, value_enum, default_value = "gt")]
    pub endpoints: EndsArg,
    /// Parameter preset for the `simple` set (and any other).
    #[arg(long, default_value = "default")]
    pub preset: String,
    /// Parameter preset for the `hard` set.
    #[arg(long, default_value = "clutter")]
    pub hard_preset: String,
    /// Parameter overrides as a JSON object, applied to both presets.
    #[arg(long)]
    pub options: Option<String>,
    /// Print one JSON document instead of tables.
    #[arg(long)]
    pub json: bool,
    /// Resize every photo, with its masks and terminals, by these factors (a camera of
    /// another resolution), one evaluation each, e.g. `0.5,1,2`.
    #[arg(long, value_delimiter = ',', default_value = "1")]
    pub scale: Vec<f64>,
    /// Magnify every photo: its central 1/zoom cropped and enlarged back to the frame's
    /// size (a camera closer to the table: cables look wider), with its masks and
    /// terminals.
    #[arg(long, default_value_t = 1.0)]
    pub zoom: f64,
    /// Darken every photo: its pixel values multiplied by this factor (an underexposed
    /// photo), in (0, 1].
    #[arg(long, default_value_t = 1.0)]
    pub exposure: f64,
    /// Soften every photo: a Gaussian blur of this σ, pixels, over it (a lens out of
    /// focus), in [0, 10].
    #[arg(long, default_value_t = 0.0)]
    pub blur: f64,
    /// Add sensor noise to every photo: Gaussian, of this σ in levels of 0-255, on
    /// every channel of every pixel (the same noise for a photo on every run), in
    /// [0, 50].
    #[arg(long, default_value_t = 0.0)]
    pub noise: f64,
    /// Write every photo, as the engine is given it (made by the flags above, or the
    /// file itself), into this folder as `SET_NAME_xSCALE_zZOOM.png` (`.jpg` for an
    /// unchanged JPEG): to look at, or to segment again with `ariadne segment`.
    #[arg(long)]
    pub save_views: Option<PathBuf>,
    /// The endpoint detector, used with --endpoints detect.
    #[command(flatten)]
    pub detector: DetectorArgs,
}

#[cfg(test)]
mod tests {
    use super::*;
    use clap::{CommandFactory, FromArgMatches, Parser};

    #[derive(Parser)]
    struct Wrapper {
        #[command(flatten)]
        serve: ServeArgs,
    }

    /// `args` parsed as `ariadne serve` would, but blind to the environment (the
    /// `ARIADNE_*` and `ORT_DYLIB_PATH` variables of whoever runs the tests).
    fn parse(args: &[&str]) -> Result<Wrapper, clap::Error> {
        let command = Wrapper::command().mut_args(|arg| arg.env(None::<&str>));
        Wrapper::from_arg_matches(&command.try_get_matches_from(args)?)
    }

    #[test]
    fn flag_defaults_are_the_config_defaults() {
        let parsed: ServeConfig = parse(&["ariadne"]).unwrap().serve.into();
        assert_eq!(parsed, ServeConfig::default());
        let flags = parse(&[
            "ariadne",
            "--workers",
            "3",
            "--log-format",
            "json",
            "--model-kind",
            "yolo",
        ])
        .unwrap();
        let config: ServeConfig = flags.serve.into();
        assert_eq!(config.workers, Some(3));
        assert_eq!(config.log_format, LogFormat::Json);
        assert_eq!(config.detector.model_kind, ModelKind::Yolo);
        assert!(parse(&["ariadne", "--log-format", "xml"]).is_err());
    }
}
