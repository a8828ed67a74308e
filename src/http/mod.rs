//! The HTTP service: a thin shell that parses requests, schedules the engine on a
//! bounded worker pool and serialises its results.
//!
//! Routes: `GET /` (a page to try it), `POST /segment`, `GET /healthz`, `GET /readyz`, `GET /metrics`,
//! `GET /openapi.json`, `GET /docs`.
//!
//! - [`config`]: settings and presets; [`state`]: what every handler shares;
//! - [`router`]: routes, OpenAPI, fallbacks, layers; [`server`]: warm-up, serving,
//!   shutdown, logging;
//! - `segment` and [`body`]: `POST /segment`; `health`: the operations routes;
//!   `page`: the page at `/`;
//! - [`error`]: errors to responses; [`metrics`]; [`pool`]; [`request_id`].

pub mod body;
pub mod config;
pub mod error;
mod health;
pub mod metrics;
mod page;
pub mod pool;
pub mod request_id;
pub mod router;
mod segment;
pub mod server;
pub mod state;

pub use config::{LogFormat, Presets, ServeConfig};
pub use error::{ApiError, ErrorCode};
pub use router::{app, openapi};
pub use server::{init_logging, run, serve, shutdown_signal, warm_up};
pub use state::AppState;
