//! The real server on 127.0.0.1:0, spoken to over HTTP (shared by the contract tests,
//! which use a stand-in detector, and the end-to-end tests, which use the real model).

use std::sync::Arc;

use ariadne_dlo::detect::EndpointDetector;
use ariadne_dlo::http::{self, AppState, Presets, ServeConfig};
use tokio::sync::oneshot;

/// A running server and a client for it.
pub struct TestApp {
    /// `http://127.0.0.1:PORT`.
    pub base: String,
    /// A client.
    pub client: reqwest::Client,
    shutdown: Option<oneshot::Sender<()>>,
    /// The server task; resolves when it has stopped.
    pub server: tokio::task::JoinHandle<std::io::Result<()>>,
}

impl TestApp {
    /// Starts a server with `detector` and the default settings changed by
    /// `configure` (two workers unless it says otherwise), warmed up if `warm`.
    pub async fn spawn(
        detector: Arc<dyn EndpointDetector>,
        configure: impl FnOnce(&mut ServeConfig),
        warm: bool,
    ) -> Self {
        let mut config = ServeConfig {
            workers: Some(2),
            ..ServeConfig::default()
        };
        configure(&mut config);
        let state = AppState::new(config, Presets::default(), detector).unwrap();
        if warm {
            http::warm_up(&state).await.unwrap();
        }
        let listener = tokio::net::TcpListener::bind("127.0.0.1:0").await.unwrap();
        let addr = listener.local_addr().unwrap();
        let (tx, rx) = oneshot::channel::<()>();
        let server = tokio::spawn(http::serve(listener, state, async move {
            let _ = rx.await;
        }));
        Self {
            base: format!("http://{addr}"),
            client: reqwest::Client::new(),
            shutdown: Some(tx),
            server,
        }
    }

    /// The URL of `path` on this server.
    pub fn url(&self, path: &str) -> String {
        format!("{}{}", self.base, path)
    }

    /// Status code of `GET path`.
    pub async fn get_status(&self, path: &str) -> u16 {
        let response = self.client.get(self.url(path)).send().await.unwrap();
        response.status().as_u16()
    }

    /// Body of `GET path` as text.
    pub async fn get_text(&self, path: &str) -> String {
        let response = self.client.get(self.url(path)).send().await.unwrap();
        response.text().await.unwrap()
    }

    /// `POST /segment` with `jpeg` as the raw body (no ends: the detector runs);
    /// asserts 200 and returns the document.
    pub async fn segment_photo(&self, jpeg: Vec<u8>) -> serde_json::Value {
        let response = self
            .client
            .post(self.url("/segment"))
            .header("content-type", "image/jpeg")
            .body(jpeg)
            .send()
            .await
            .unwrap();
        assert_eq!(response.status(), 200);
        response.json().await.unwrap()
    }

    /// How many endpoint inferences `/metrics` has timed.
    pub async fn endpoint_inferences(&self) -> f64 {
        let metrics = self.get_text("/metrics").await;
        metric_value(
            &metrics,
            "ariadne_stage_duration_seconds_count",
            &["stage=\"endpoints\""],
        )
    }

    /// Sends the shutdown signal.
    pub fn stop(&mut self) {
        if let Some(tx) = self.shutdown.take() {
            let _ = tx.send(());
        }
    }
}

/// The sum of the samples of metric `name` whose labels include all of `labels`.
pub fn metric_value(text: &str, name: &str, labels: &[&str]) -> f64 {
    text.lines()
        .filter(|l| l.starts_with(name) && labels.iter().all(|lab| l.contains(lab)))
        .filter_map(|l| l.rsplit(' ').next()?.parse::<f64>().ok())
        .sum()
}
