//! What every handler shares: settings, presets, the pool, the detector and the
//! life-cycle flags.

use std::ops::Deref;
use std::sync::atomic::AtomicBool;
use std::sync::{Arc, OnceLock};
use std::time::Instant;

use tokio::sync::{Semaphore, watch};

use super::config::{Presets, ServeConfig};
use super::pool::WorkerPool;
use crate::detect::EndpointDetector;

/// Shared state of the service: configuration, presets, the pool and the life-cycle
/// flags. Cheap to clone.
#[derive(Clone)]
pub struct AppState(Arc<Inner>);

/// What [`AppState`] holds.
pub struct Inner {
    /// Settings.
    pub config: ServeConfig,
    /// Named parameter sets.
    pub presets: Presets,
    /// Where CPU work runs.
    pub pool: WorkerPool,
    /// Finds ends when a request gives none.
    pub detector: Arc<dyn EndpointDetector>,
    /// True once warmed up.
    pub ready: AtomicBool,
    /// True once shutdown has begun.
    pub draining: AtomicBool,
    /// When the listener closed and the drain grace period began.
    pub closed_at: OnceLock<Instant>,
    /// The upload budget, one permit per KiB ([`UPLOAD_UNIT`] bytes).
    pub uploads: Arc<Semaphore>,
    /// Set when the drain grace is about to run out: requests still waiting are
    /// answered 503 while their connections can still carry it.
    pub giving_up: watch::Sender<bool>,
}

/// Bytes per permit of [`Inner::uploads`].
pub const UPLOAD_UNIT: usize = 1024;

impl Deref for AppState {
    type Target = Inner;
    fn deref(&self) -> &Inner {
        &self.0
    }
}

impl AppState {
    /// State for `config`: presets loaded, pool started, not yet ready.
    pub fn new(
        config: ServeConfig,
        presets: Presets,
        detector: Arc<dyn EndpointDetector>,
    ) -> std::io::Result<Self> {
        let pool = WorkerPool::new(config.worker_count(), config.queue)?;
        let config_budget = config.upload_budget_bytes;
        Ok(Self(Arc::new(Inner {
            config,
            presets,
            pool,
            detector,
            ready: AtomicBool::new(false),
            draining: AtomicBool::new(false),
            closed_at: OnceLock::new(),
            giving_up: watch::Sender::new(false),
            uploads: Arc::new(Semaphore::new(
                config_budget
                    .div_ceil(UPLOAD_UNIT)
                    .min(Semaphore::MAX_PERMITS),
            )),
        })))
    }
}
