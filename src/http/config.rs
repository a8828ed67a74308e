//! Service configuration, as plain values: the command line (`crate::cli`) fills it
//! from flags and environment variables, tests build it directly.

use std::collections::BTreeMap;
use std::net::SocketAddr;
use std::path::{Path, PathBuf};
use std::str::FromStr;

use crate::detect::DetectorConfig;
use crate::engine::{EngineError, PRESET_NAMES, Params};

/// Log line format.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum LogFormat {
    /// Human-readable text.
    Text,
    /// One JSON object per line.
    Json,
}

impl FromStr for LogFormat {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        crate::choice::parse(
            s,
            &[("text", Self::Text), ("json", Self::Json)],
            "log format",
        )
    }
}

/// Settings of the service (`ariadne serve`); see `--help` for each.
#[derive(Debug, Clone, PartialEq)]
pub struct ServeConfig {
    /// Address to listen on.
    pub bind: SocketAddr,
    /// Worker threads for CPU work; `None`: the CPUs available to the process.
    pub workers: Option<usize>,
    /// Requests that may wait for a worker; more are answered 429 at once.
    pub queue: usize,
    /// Per-request deadline in milliseconds, queueing included; later answers are 504.
    pub deadline_ms: u64,
    /// Largest accepted request body, bytes.
    pub max_body_bytes: usize,
    /// Largest accepted image, pixels (width × height, read from the header).
    pub max_pixels: u64,
    /// Most cable ends one request may give; more are answered 422.
    pub max_endpoints: usize,
    /// Most open connections; more wait in the listen backlog until one closes.
    pub max_connections: usize,
    /// Seconds a connection gets to send a request's headers, and most seconds an
    /// open connection may stay idle between requests.
    pub header_timeout_s: u64,
    /// Seconds a request gets to send its body; slower ones are answered 408.
    pub body_timeout_s: u64,
    /// Request bodies in memory at once, bytes (declared lengths, or `max_body_bytes`
    /// for a body of unknown length), from admission to the end of the request's work;
    /// a request that would go over is answered 429 before its body is read.
    pub upload_budget_bytes: usize,
    /// Seconds `Retry-After` asks rejected clients to wait.
    pub retry_after_s: u64,
    /// JSON file of extra or overriding presets.
    pub presets: Option<PathBuf>,
    /// Log format.
    pub log_format: LogFormat,
    /// Seconds between a shutdown signal and closing the listener (not ready meanwhile).
    pub shutdown_delay_s: u64,
    /// Seconds in-flight requests get to finish after the listener closes.
    pub shutdown_grace_s: u64,
    /// The endpoint detector, run when a request gives no ends.
    pub detector: DetectorConfig,
}

impl Default for ServeConfig {
    fn default() -> Self {
        Self {
            bind: SocketAddr::from(([0, 0, 0, 0], 8080)),
            workers: None,
            queue: 16,
            deadline_ms: 10_000,
            max_body_bytes: 16 * 1024 * 1024,
            max_pixels: 16_000_000,
            max_endpoints: 256,
            max_connections: 512,
            header_timeout_s: 10,
            body_timeout_s: 30,
            upload_budget_bytes: 256 * 1024 * 1024,
            retry_after_s: 1,
            presets: None,
            log_format: LogFormat::Text,
            shutdown_delay_s: 0,
            shutdown_grace_s: 30,
            detector: DetectorConfig::default(),
        }
    }
}

impl ServeConfig {
    /// Worker count: the setting, or the CPUs this process may use (container limits
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
        assert_eq!(p.names(), vec!["cell-7", "clutter", "default", "paper"]);
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
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
