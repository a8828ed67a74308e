//! Service configuration: every setting is a flag with an environment twin.

use std::collections::BTreeMap;
use std::net::SocketAddr;
use std::path::{Path, PathBuf};

use clap::ValueEnum;

use crate::detect::DetectorArgs;
use crate::engine::{EngineError, PRESET_NAMES, Params};

/// Log line format.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum LogFormat {
    /// Human-readable text.
    Text,
    /// One JSON object per line.
    Json,
}

/// Settings of `ariadne serve`.
#[derive(Debug, Clone, clap::Args)]
pub struct ServeArgs {
    /// Address to listen on.
    #[arg(long, env = "ARIADNE_BIND", default_value = "0.0.0.0:8080")]
    pub bind: SocketAddr,
    /// Worker threads for CPU work [default: the CPUs available to the process].
    #[arg(long, env = "ARIADNE_WORKERS")]
    pub workers: Option<usize>,
    /// Requests that may wait for a worker; more are answered 429 at once.
    #[arg(long, env = "ARIADNE_QUEUE", default_value_t = 16)]
    pub queue: usize,
    /// Per-request deadline in milliseconds, queueing included; later answers are 504.
    #[arg(long, env = "ARIADNE_DEADLINE_MS", default_value_t = 10_000)]
    pub deadline_ms: u64,
    /// Largest accepted request body, bytes.
    #[arg(long, env = "ARIADNE_MAX_BODY_BYTES", default_value_t = 16 * 1024 * 1024)]
    pub max_body_bytes: usize,
    /// Largest accepted image, pixels (width × height, read from the header).
    #[arg(long, env = "ARIADNE_MAX_PIXELS", default_value_t = 16_000_000)]
    pub max_pixels: u64,
    /// Seconds `Retry-After` asks rejected clients to wait.
    #[arg(long, env = "ARIADNE_RETRY_AFTER_S", default_value_t = 1)]
    pub retry_after_s: u64,
    /// JSON file of extra or overriding presets: {"name": {"n_segments": 1500, ...}, ...}.
    #[arg(long, env = "ARIADNE_PRESETS")]
    pub presets: Option<PathBuf>,
    /// Log format.
    #[arg(long, env = "ARIADNE_LOG_FORMAT", value_enum, default_value = "text")]
    pub log_format: LogFormat,
    /// Seconds between a shutdown signal and closing the listener, during which
    /// /readyz answers 503 so that load balancers stop sending work.
    #[arg(long, env = "ARIADNE_SHUTDOWN_DELAY_S", default_value_t = 0)]
    pub shutdown_delay_s: u64,
    /// Seconds in-flight requests get to finish after the listener closes.
    #[arg(long, env = "ARIADNE_SHUTDOWN_GRACE_S", default_value_t = 30)]
    pub shutdown_grace_s: u64,
    /// The endpoint detector, run when a request gives no ends.
    #[command(flatten)]
    pub detector: DetectorArgs,
}

impl ServeArgs {
    /// Worker count: the flag, or the CPUs this process may use (container limits
    /// included, as the standard library reads cgroup quotas).
    pub fn worker_count(&self) -> usize {
        self.workers
            .unwrap_or_else(|| std::thread::available_parallelism().map_or(1, |n| n.get()))
            .max(1)
    }
}

/// Named parameter sets: the built-in presets plus those of a presets file.
#[derive(Debug, Clone, PartialEq)]
pub struct Presets(BTreeMap<String, Params>);

/// Errors loading a presets file.
#[derive(Debug, thiserror::Error)]
pub enum PresetsError {
    /// Unreadable file.
    #[error("presets file {0}: {1}")]
    Io(PathBuf, std::io::Error),
    /// Not a JSON object of objects.
    #[error("presets file {0}: {1}")]
    Json(PathBuf, serde_json::Error),
    /// A preset with bad values.
    #[error("presets file {0}, preset `{1}`: {2}")]
    Invalid(PathBuf, String, EngineError),
}

impl Default for Presets {
    fn default() -> Self {
        Self(
            PRESET_NAMES
                .iter()
                .filter_map(|n| Params::preset(n).ok().map(|p| (n.to_string(), p)))
                .collect(),
        )
    }
}

impl Presets {
    /// The built-in presets overlaid with a file's: each entry overrides fields of the
    /// built-in preset of the same name, or of `default` for a new name.
    pub fn load(file: Option<&Path>) -> Result<Self, PresetsError> {
        let mut presets = Self::default();
        let Some(path) = file else {
            return Ok(presets);
        };
        let text = std::fs::read_to_string(path).map_err(|e| PresetsError::Io(path.into(), e))?;
        let entries: BTreeMap<String, serde_json::Map<String, serde_json::Value>> =
            serde_json::from_str(&text).map_err(|e| PresetsError::Json(path.into(), e))?;
        for (name, overrides) in entries {
            let base = presets
                .0
                .get(&name)
                .or_else(|| presets.0.get("default"))
                .cloned()
                .unwrap_or_default();
            let params = base
                .with_overrides(&overrides)
                .map_err(|e| PresetsError::Invalid(path.into(), name.clone(), e))?;
            presets.0.insert(name, params);
        }
        Ok(presets)
    }

    /// The preset of that name.
    pub fn get(&self, name: &str) -> Option<&Params> {
        self.0.get(name)
    }

    /// All names, sorted.
    pub fn names(&self) -> Vec<&str> {
        self.0.keys().map(String::as_str).collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn presets_file_overrides_and_adds() {
        let dir = std::env::temp_dir().join(format!("ariadne-presets-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let file = dir.join("p.json");
        std::fs::write(
            &file,
            r#"{"clutter": {"n_segments": 1200}, "cell-7": {"compactness": 15}}"#,
        )
        .unwrap();
        let p = Presets::load(Some(&file)).unwrap();
        assert_eq!(p.get("clutter").unwrap().n_segments, 1200);
        assert_eq!(p.get("clutter").unwrap().compactness, 10.0);
        assert_eq!(p.get("cell-7").unwrap().compactness, 15.0);
        assert_eq!(p.names(), vec!["cell-7", "clutter", "default"]);
        std::fs::write(&file, r#"{"bad": {"n_segments": 0}}"#).unwrap();
        assert!(matches!(
            Presets::load(Some(&file)),
            Err(PresetsError::Invalid(..))
        ));
        std::fs::write(&file, "[1, 2]").unwrap();
        assert!(matches!(
            Presets::load(Some(&file)),
            Err(PresetsError::Json(..))
        ));
    }
}
