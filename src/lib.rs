//! Ariadne: cable (deformable linear object) segmentation and B-spline model
//! estimation by walks on superpixel graphs, after De Gregorio, Palli and Di Stefano,
//! "Let's take a Walk on Superpixels Graphs" (ACCV 2018).
//!
//! - [`decode`]: image decoding with header-checked limits;
//! - [`detect`]: cable-end detection with an ONNX model;
//! - [`engine`]: the pure algorithm (SLIC → graph → walks → pairing → splines → masks);
//! - [`http`]: the HTTP service (axum) around the engine;
//! - [`pipeline`]: one request from bytes to masks (decode → ends → engine → masks →
//!   PNG), timed in one [`timings::Timings`]: the service, the command line, the
//!   evaluator and the benchmarks all run it;
//! - [`eval`]: dataset reading and the paper's metrics;
//! - [`synth`]: deterministic synthetic cable scenes with known truth;
//! - [`report`]: the JSON document shared by the command line and the service;
//! - [`cli`]: the command line, the only layer that knows clap; [`choice`]: parsing
//!   named setting values.

pub mod choice;
pub mod cli;
pub mod decode;
pub mod detect;
pub mod engine;
pub mod eval;
pub mod http;
pub mod pipeline;
pub mod report;
pub mod synth;
pub mod timings;
