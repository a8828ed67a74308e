//! The command line: `ariadne segment` and `ariadne eval`.

use std::path::{Path, PathBuf};

use clap::{Parser, Subcommand, ValueEnum};
use thiserror::Error;

use crate::decode::{DecodeError, decode_rgb};
use crate::detect::{DetectError, DetectorArgs, EndpointDetector, Ends, OnnxDetector};
use crate::engine::{self, EngineError, MaskKind, Params, render};
use crate::eval::{self, DatasetError, ImageResult};
use crate::report::{self, CableReport, SegmentResponse, Timings};

/// Cable segmentation and B-spline model estimation by walks on superpixel graphs.
#[derive(Debug, Parser)]
#[command(name = "ariadne", version, about)]
pub struct Cli {
    /// What to do.
    #[command(subcommand)]
    pub command: Command,
}

/// Sub-commands.
#[derive(Debug, Subcommand)]
pub enum Command {
    /// Segment one image and write JSON, mask and overlay.
    Segment(SegmentArgs),
    /// Evaluate on a folder laid out like the cables dataset.
    Eval(EvalArgs),
    /// Run the HTTP service.
    Serve(crate::http::ServeArgs),
    /// Print the OpenAPI document generated from the code.
    Openapi,
}

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
    /// Write the JSON result here ('-' for standard output).
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
pub enum EndsSource {
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
    pub endpoints: EndsSource,
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
    /// The endpoint detector, used with --endpoints detect.
    #[command(flatten)]
    pub detector: DetectorArgs,
}

/// Errors of the command line, each with the message a person needs.
#[derive(Debug, Error)]
pub enum CliError {
    /// Bad --endpoints.
    #[error("--endpoints must be a JSON array of [x, y] pairs: {0}")]
    BadEndpoints(String),
    /// The endpoint detector.
    #[error("endpoint detector: {0}")]
    Detect(#[from] DetectError),
    /// Bad --options.
    #[error("--options must be a JSON object of parameter overrides: {0}")]
    BadOptions(String),
    /// The image.
    #[error("{0}: {1}")]
    Image(PathBuf, DecodeError),
    /// The engine.
    #[error(transparent)]
    Engine(#[from] EngineError),
    /// The dataset.
    #[error(transparent)]
    Dataset(#[from] DatasetError),
    /// The service.
    #[error("{0}")]
    Serve(String),
    /// Files.
    #[error("{0}: {1}")]
    Io(PathBuf, std::io::Error),
}

/// Runs the parsed command line.
pub fn run(cli: Cli) -> Result<(), CliError> {
    match cli.command {
        Command::Segment(args) => segment(&args),
        Command::Eval(args) => evaluate(&args),
        Command::Serve(args) => crate::http::run(args).map_err(CliError::Serve),
        Command::Openapi => {
            let text = crate::http::openapi()
                .to_pretty_json()
                .map_err(|e| CliError::Serve(e.to_string()))?;
            println!("{text}");
            Ok(())
        }
    }
}

fn params_from(preset: &str, options: Option<&str>) -> Result<Params, CliError> {
    let base = Params::preset(preset)?;
    match options {
        None => Ok(base),
        Some(text) => {
            let map: serde_json::Map<String, serde_json::Value> =
                serde_json::from_str(text).map_err(|e| CliError::BadOptions(e.to_string()))?;
            Ok(base.with_overrides(&map)?)
        }
    }
}

fn write(path: &Path, bytes: &[u8]) -> Result<(), CliError> {
    if path == Path::new("-") {
        use std::io::Write;
        return std::io::stdout()
            .write_all(bytes)
            .map_err(|e| CliError::Io(path.into(), e));
    }
    std::fs::write(path, bytes).map_err(|e| CliError::Io(path.into(), e))
}

fn segment(args: &SegmentArgs) -> Result<(), CliError> {
    let start = std::time::Instant::now();
    let params = params_from(&args.preset, args.options.as_deref())?;
    let given = match &args.endpoints {
        Some(text) => Some(report::parse_endpoints(text).map_err(CliError::BadEndpoints)?),
        None => None,
    };
    let bytes = std::fs::read(&args.image).map_err(|e| CliError::Io(args.image.clone(), e))?;
    let t = std::time::Instant::now();
    let image = decode_rgb(&bytes, u64::MAX).map_err(|e| CliError::Image(args.image.clone(), e))?;
    let decode = t.elapsed().as_secs_f64() * 1e3;
    let ends = match given {
        Some(points) => Ends::given(points),
        None => Ends::detected(&OnnxDetector::load(&args.detector, 1)?, &image)?,
    };
    let seg = engine::segment_with_confidence(&image, &ends.points, &ends.confidences, &params)?;
    let t = std::time::Instant::now();
    let mask = render::render_mask(&seg, args.mask_kind.into(), params.mask_width_px);
    let overlay = args.overlay.as_ref().map(|_| render::overlay(&image, &seg));
    let mask_time = t.elapsed().as_secs_f64() * 1e3;
    let t = std::time::Instant::now();
    let mask_png = report::mask_png(&mask);
    let overlay_png = overlay.map(|o| {
        report::png(
            o.as_raw(),
            o.width(),
            o.height(),
            image::ExtendedColorType::Rgb8,
        )
    });
    if let Some(path) = &args.mask {
        write(path, &mask_png)?;
    }
    if let (Some(path), Some(png)) = (&args.overlay, &overlay_png) {
        write(path, png)?;
    }
    if let Some(path) = &args.json {
        let mut response = SegmentResponse {
            request_id: format!("cli-{}", uuid::Uuid::new_v4()),
            width: seg.width,
            height: seg.height,
            cables: seg.cables.iter().map(CableReport::from).collect(),
            endpoints: report::endpoint_reports(&seg, &ends.points, &ends.confidences),
            mask_png: report::base64(&mask_png),
            overlay_png: overlay_png.as_deref().map(report::base64),
            timings_ms: Timings {
                decode,
                endpoints: ends.detect_ms,
                mask: mask_time,
                ..Timings::default()
            }
            .with_engine(&seg),
        };
        response.timings_ms.encode = t.elapsed().as_secs_f64() * 1e3;
        response.timings_ms.total = start.elapsed().as_secs_f64() * 1e3;
        let mut text = serde_json::to_vec_pretty(&response)
            .map_err(|e| CliError::BadOptions(e.to_string()))?;
        text.push(b'\n');
        write(path, &text)?;
    }
    eprintln!(
        "{} cable(s) from {} end(s) in {:.1} ms",
        seg.cables.len(),
        ends.points.len(),
        start.elapsed().as_secs_f64() * 1e3
    );
    Ok(())
}

fn evaluate(args: &EvalArgs) -> Result<(), CliError> {
    let dir = args
        .dataset
        .clone()
        .unwrap_or_else(eval::default_dataset_dir);
    let samples = eval::load_dataset(&dir)?;
    let simple = params_from(&args.preset, args.options.as_deref())?;
    let hard = params_from(&args.hard_preset, args.options.as_deref())?;
    let loaded = match args.endpoints {
        EndsSource::Gt => None,
        EndsSource::Detect => Some(OnnxDetector::load(&args.detector, 1)?),
    };
    let print = |r: &ImageResult| {
        if !args.json {
            println!(
                "{:<7} {}  IoU {:.3}  cables {}/{} found {}  ends {} ({}/{} terminals)  ms: ends {:.1} sp {:.1} graph {:.1} walks {:.1} splines {:.1} mask {:.1} total {:.1}",
                r.set,
                r.name,
                r.iou,
                r.matched_cables,
                r.gt_cables,
                r.found_cables,
                r.ends,
                r.terminals_matched,
                r.terminals,
                r.timings_ms.endpoints,
                r.timings_ms.superpixels,
                r.timings_ms.graph,
                r.timings_ms.walks,
                r.timings_ms.splines,
                r.timings_ms.mask,
                r.timings_ms.total
            );
        }
    };
    let detector = loaded.as_ref().map(|d| d as &dyn EndpointDetector);
    let results = eval::evaluate_all(&samples, &simple, &hard, detector, print)?;
    let summaries = eval::summarise(&results);
    if args.json {
        let doc = serde_json::json!({ "dataset": dir, "images": results, "sets": summaries });
        println!("{}", serde_json::to_string_pretty(&doc).unwrap_or_default());
    } else {
        println!();
        println!(
            "set      images  weighted IoU  cable recall  cable precision  matched IoU  end recall  end precision  median ms"
        );
        for s in &summaries {
            println!(
                "{:<8} {:>6}  {:>12.3}  {:>12.3}  {:>15.3}  {:>11.3}  {:>10.3}  {:>13.3}  {:>9.1}",
                s.set,
                s.images,
                s.weighted_iou,
                s.cable_recall,
                s.cable_precision,
                s.matched_iou,
                s.terminal_recall,
                s.terminal_precision,
                s.median_total_ms
            );
        }
    }
    Ok(())
}
