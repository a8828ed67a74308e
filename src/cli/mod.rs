//! The command line: `ariadne segment`, `eval`, `serve` and `openapi`. The only layer
//! that knows clap: [`args`] turns flags into the library's plain configs.

pub mod args;
mod commands;

use std::path::{Path, PathBuf};

use clap::{Parser, Subcommand};
use thiserror::Error;

use crate::detect::DetectError;
use crate::engine::{EngineError, Params};
use crate::eval::DatasetError;
use crate::pipeline::PipelineError;
pub use args::{DetectorArgs, EndsArg, EvalArgs, MaskArg, SegmentArgs, ServeArgs};

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
    Serve(ServeArgs),
    /// Print the OpenAPI document generated from the code.
    Openapi,
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
    /// A numeric argument outside its range.
    #[error("{0}")]
    OutOfRange(String),
    /// The image could not be segmented.
    #[error("{0}: {1}")]
    Image(PathBuf, PipelineError),
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
        Command::Segment(args) => commands::segment(args),
        Command::Eval(args) => commands::evaluate(args),
        Command::Serve(args) => crate::http::run(args.into()).map_err(CliError::Serve),
        Command::Openapi => {
            let text = crate::http::openapi()
                .to_pretty_json()
                .map_err(|e| CliError::Serve(e.to_string()))?;
            println!("{text}");
            Ok(())
        }
    }
}

/// The preset of that name with the `--options` JSON applied.
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

/// Writes `bytes` to `path`, or to standard output for `-`.
fn write(path: &Path, bytes: &[u8]) -> Result<(), CliError> {
    if path == Path::new("-") {
        use std::io::Write;
        return std::io::stdout()
            .write_all(bytes)
            .map_err(|e| CliError::Io(path.into(), e));
    }
    std::fs::write(path, bytes).map_err(|e| CliError::Io(path.into(), e))
}
