//! Prometheus metrics: names, buckets and recording helpers.
//!
//! Labels come only from bounded sets: route templates, status classes, preset names
//! known at start-up, stage names and rejection reasons.

use std::sync::OnceLock;
use std::time::Instant;

use axum::extract::{MatchedPath, Request, State};
use axum::middleware::Next;
use axum::response::Response;
use metrics_exporter_prometheus::{Matcher, PrometheusBuilder, PrometheusHandle};

use super::state::AppState;

/// Requests answered, by route, status class and preset.
pub const REQUESTS: &str = "ariadne_requests_total";
/// End-to-end latency, seconds, by route and status class.
pub const REQUEST_SECONDS: &str = "ariadne_request_duration_seconds";
/// Per-stage latency, seconds, by stage.
pub const STAGE_SECONDS: &str = "ariadne_stage_duration_seconds";
/// Requests waiting for a worker.
pub const QUEUE_DEPTH: &str = "ariadne_queue_depth";
/// Requests being worked on.
pub const IN_FLIGHT: &str = "ariadne_in_flight";
/// Requests refused, by reason.
pub const REJECTIONS: &str = "ariadne_rejections_total";
/// Cables found per image.
pub const CABLES: &str = "ariadne_cables_per_image";
/// Always 1, labelled with the version and the model file.
pub const BUILD_INFO: &str = "ariadne_build_info";
/// CPU time of the process, seconds (the client libraries' name).
const PROCESS_CPU: &str = "process_cpu_seconds_total";
/// Resident memory of the process, bytes.
const PROCESS_RSS: &str = "process_resident_memory_bytes";
/// Open file descriptors (sockets included).
const PROCESS_FDS: &str = "process_open_fds";

/// Every rejection reason: each counter is exported from the start, at 0.
pub const REJECT_REASONS: [&str; 8] = [
    "body_too_large",
    "body_timeout",
    "too_many_pixels",
    "too_many_endpoints",
    "queue_full",
    "upload_budget",
    "deadline",
    "shutting_down",
];

/// Latency buckets, seconds: 1 ms (endpoint inference) to 30 s.
const SECONDS_BUCKETS: [f64; 16] = [
    0.001, 0.0025, 0.005, 0.01, 0.02, 0.03, 0.05, 0.075, 0.1, 0.2, 0.5, 1.0, 2.0, 5.0, 10.0, 30.0,
];
/// Cable-count buckets.
const CABLE_BUCKETS: [f64; 9] = [0.0, 1.0, 2.0, 3.0, 4.0, 6.0, 8.0, 12.0, 20.0];

/// The process-wide recorder, installed on first use (several servers in one test
/// process share it, so tests compare before and after).
pub fn handle() -> &'static PrometheusHandle {
    static HANDLE: OnceLock<PrometheusHandle> = OnceLock::new();
    HANDLE.get_or_init(|| {
        let builder = PrometheusBuilder::new()
            .set_buckets_for_metric(Matcher::Suffix("_seconds".into()), &SECONDS_BUCKETS)
            .and_then(|b| b.set_buckets_for_metric(Matcher::Full(CABLES.into()), &CABLE_BUCKETS))
            .expect("bucket lists are non-empty constants");
        let recorder = builder.build_recorder();
        let handle = recorder.handle();
        // Another recorder may already be installed (a library user's): then ours
        // still renders what is recorded through it... which is nothing; say so.
        if metrics::set_global_recorder(recorder).is_err() {
            tracing::warn!("a metrics recorder was already installed; /metrics will be empty");
        }
        describe();
        handle
    })
}

/// `# HELP` text for every series, and the rejection counters at 0.
fn describe() {
    use metrics::{describe_counter, describe_gauge, describe_histogram};
    describe_counter!(
        REQUESTS,
        "Requests answered, by route, status class (and preset on /segment)."
    );
    describe_histogram!(
        REQUEST_SECONDS,
        "Time from arrival to response, seconds, by route and status class."
    );
    describe_histogram!(STAGE_SECONDS, "Time per pipeline stage, seconds, by stage.");
    describe_gauge!(QUEUE_DEPTH, "Requests waiting for a worker.");
    describe_gauge!(IN_FLIGHT, "Requests being worked on.");
    describe_counter!(REJECTIONS, "Requests refused, by reason.");
    describe_histogram!(CABLES, "Cables found per image.");
    describe_gauge!(
        BUILD_INFO,
        "Always 1: the service's version and model file."
    );
    describe_gauge!(
        PROCESS_CPU,
        "User and system CPU time of the process, seconds."
    );
    describe_gauge!(PROCESS_RSS, "Resident memory of the process, bytes.");
    describe_gauge!(PROCESS_FDS, "Open file descriptors of the process.");
    for reason in REJECT_REASONS {
        metrics::counter!(REJECTIONS, "reason" => reason).absolute(0);
    }
}

/// Sets `ariadne_build_info{version, model}` to 1.
pub fn record_build_info(model: &str) {
    metrics::gauge!(
        BUILD_INFO,
        "version" => env!("CARGO_PKG_VERSION"),
        "model" => model.to_string()
    )
    .set(1.0);
}

/// Reads the process's CPU time, memory and descriptors from /proc (Linux; elsewhere
/// they are not exported).
pub fn record_process() {
    let stat = std::fs::read_to_string("/proc/self/stat").unwrap_or_default();
    // Fields after the command name (which may hold spaces): utime is the 12th, stime
    // the 13th, in clock ticks of 1/100 s (Linux's fixed USER_HZ).
    let fields: Vec<&str> = stat
        .rsplit_once(')')
        .map_or(Vec::new(), |(_, rest)| rest.split_whitespace().collect());
    let ticks = |i: usize| fields.get(i).and_then(|v| v.parse::<f64>().ok());
    if let (Some(user), Some(system)) = (ticks(11), ticks(12)) {
        metrics::gauge!(PROCESS_CPU).set((user + system) / 100.0);
    }
    let status = std::fs::read_to_string("/proc/self/status").unwrap_or_default();
    let rss_kb = status
        .lines()
        .find_map(|l| l.strip_prefix("VmRSS:"))
        .and_then(|v| v.trim().trim_end_matches("kB").trim().parse::<f64>().ok());
    if let Some(kb) = rss_kb {
        metrics::gauge!(PROCESS_RSS).set(kb * 1024.0);
    }
    if let Ok(fds) = std::fs::read_dir("/proc/self/fd") {
        metrics::gauge!(PROCESS_FDS).set(fds.count() as f64);
    }
}

/// Status class label of a status code: `2xx`, `4xx`, ...
pub fn status_class(status: u16) -> &'static str {
    match status {
        100..=199 => "1xx",
        200..=299 => "2xx",
        300..=399 => "3xx",
        400..=499 => "4xx",
        _ => "5xx",
    }
}

/// Records one stage's duration.
pub fn stage(name: &'static str, ms: f64) {
    metrics::histogram!(STAGE_SECONDS, "stage" => name).record(ms / 1e3);
}

/// Records a rejection (`reason` one of [`REJECT_REASONS`]).
pub fn reject(reason: &'static str) {
    debug_assert!(REJECT_REASONS.contains(&reason), "unlisted reason {reason}");
    metrics::counter!(REJECTIONS, "reason" => reason).increment(1);
}

/// Counts one answered request; the preset is a label of `/segment` only.
pub fn count_request(route: &str, status: u16, preset: Option<String>) {
    count(route.to_string(), status_class(status), preset);
}

/// Counts one request by route, status class and (on `/segment`) preset.
fn count(route: String, class: &'static str, preset: Option<String>) {
    match preset {
        Some(preset) => metrics::counter!(
            REQUESTS,
            "route" => route,
            "status_class" => class,
            "preset" => preset
        )
        .increment(1),
        None => metrics::counter!(REQUESTS, "route" => route, "status_class" => class).increment(1),
    }
}

/// Counts and times every request to a known route. A request whose client goes away
/// before the answer (the server then drops its future) is counted with the status
/// class `client_closed` and logged, so the work it cost still shows.
pub async fn record_requests(
    State(state): State<AppState>,
    request: Request,
    next: Next,
) -> Response {
    let route = request
        .extensions()
        .get::<MatchedPath>()
        .map_or_else(|| "unmatched".to_string(), |m| m.as_str().to_string());
    let preset = (route == "/segment").then(|| preset_label(&state, request.uri().query()));
    let mut pending = Pending {
        route,
        preset,
        started: Instant::now(),
        answered: false,
    };
    let response = next.run(request).await;
    pending.answered = true;
    let status = response.status().as_u16();
    pending.record(status_class(status));
    response
}

/// A request in progress, recorded once: with its status class when answered, as
/// `client_closed` when dropped unanswered.
struct Pending {
    route: String,
    preset: Option<String>,
    started: Instant,
    answered: bool,
}

impl Pending {
    fn record(&self, class: &'static str) {
        count(self.route.clone(), class, self.preset.clone());
        metrics::histogram!(REQUEST_SECONDS, "route" => self.route.clone(), "status_class" => class)
            .record(self.started.elapsed().as_secs_f64());
    }
}

impl Drop for Pending {
    fn drop(&mut self) {
        if !self.answered {
            self.record("client_closed");
            tracing::warn!(
                route = %self.route,
                after_ms = self.started.elapsed().as_millis() as u64,
                "client closed the connection before the answer"
            );
        }
    }
}

/// The preset label of a request: a known preset's name, `default` when none is
/// named, `unknown` otherwise (so callers cannot grow the label set).
fn preset_label(state: &AppState, query: Option<&str>) -> String {
    let named = query.and_then(|q| {
        serde_urlencoded::from_str::<Vec<(String, String)>>(q)
            .ok()?
            .into_iter()
            .find(|(k, _)| k == "preset")
            .map(|(_, v)| v)
    });
    match named {
        None => "default".into(),
        Some(name) if state.presets.get(&name).is_some() => name,
        Some(_) => "unknown".into(),
    }
}
