//! Integration tests: the real server on 127.0.0.1:0, spoken to over HTTP.

#![allow(clippy::unwrap_used)] // test and benchmark code: a failure should panic

mod common;

use std::path::PathBuf;
use std::sync::{Arc, OnceLock};
use std::time::Duration;

use ariadne_dlo::detect::{DetectError, Detection, EndpointDetector, Perception};
use ariadne_dlo::http::{self, ServeConfig};
use ariadne_dlo::synth::{self, Background, SceneSpec};
use common::app::{TestApp, metric_value};
use reqwest::multipart::{Form, Part};
use serde_json::Value;

/// The contract tests' photo: a deterministic synthetic scene, 640x480, four cables.
fn scene() -> &'static synth::Scene {
    static SCENE: OnceLock<synth::Scene> = OnceLock::new();
    SCENE.get_or_init(|| {
        synth::scene(&SceneSpec {
            width: 640,
            height: 480,
            cables: 4,
            cable_width: 10.0,
            background: Background::Plain,
            seed: 7,
        })
    })
}

/// A stand-in for the endpoint model (no ONNX Runtime, no model file): it "detects"
/// the scene's true ends with confidence 0.9, whatever the photo.
struct FakeDetector;

impl EndpointDetector for FakeDetector {
    fn detect_as(
        &self,
        _image: &image::RgbImage,
        _size: [u32; 2],
    ) -> Result<Perception, DetectError> {
        let ends = scene()
            .ends()
            .into_iter()
            .map(|point| Detection {
                point,
                confidence: 0.9,
            })
            .collect();
        Ok(Perception {
            ends,
            ..Perception::default()
        })
    }
}

/// Starts a server with the stand-in detector and settings changed by `configure`.
async fn spawn_app_with(configure: impl FnOnce(&mut ServeConfig), warm: bool) -> TestApp {
    TestApp::spawn(Arc::new(FakeDetector), configure, warm).await
}

async fn spawn_app(configure: impl FnOnce(&mut ServeConfig)) -> TestApp {
    spawn_app_with(configure, true).await
}

/// The scene as a JPEG file.
/// The scene photo with its true ends, posted as multipart to `path` (query included).
async fn post_scene(app: &TestApp, path: &str) -> reqwest::Response {
    app.client
        .post(app.url(path))
        .multipart(form(photo(), Some(ends_json())))
        .send()
        .await
        .unwrap()
}

fn photo() -> Vec<u8> {
    let mut jpeg = Vec::new();
    scene()
        .image
        .write_to(
            &mut std::io::Cursor::new(&mut jpeg),
            image::ImageFormat::Jpeg,
        )
        .unwrap();
    jpeg
}

/// The scene's true ends, as the JSON the API takes.
fn ends_json() -> String {
    serde_json::to_string(&scene().ends()).unwrap()
}

/// The document is consistent: some cables, each end assigned to an existing cable or
/// none.
fn assert_cables_and_ends_agree(body: &Value) {
    let cables = body["cables"].as_array().unwrap();
    assert!(!cables.is_empty(), "no cable in {body}");
    let ends = body["endpoints"].as_array().unwrap();
    let assigned: Vec<u64> = ends.iter().filter_map(|e| e["cable"].as_u64()).collect();
    assert!(assigned.iter().all(|&c| (c as usize) < cables.len()));
}

fn form(image: Vec<u8>, ends: Option<String>) -> Form {
    let mut f = Form::new().part(
        "image",
        Part::bytes(image)
            .file_name("photo.jpg")
            .mime_str("image/jpeg")
            .unwrap(),
    );
    if let Some(e) = ends {
        f = f.text("endpoints", e);
    }
    f
}

fn png_dimensions(bytes: &[u8]) -> (u32, u32) {
    let img = image::load_from_memory(bytes).unwrap();
    (img.width(), img.height())
}

fn b64(text: &str) -> Vec<u8> {
    use base64::Engine as _;
    base64::engine::general_purpose::STANDARD
        .decode(text)
        .unwrap()
}

async fn expect_error(response: reqwest::Response, status: u16, code: &str) -> Value {
    assert_eq!(response.status().as_u16(), status, "wrong status");
    assert!(
        response.headers()["content-type"]
            .to_str()
            .unwrap()
            .starts_with("application/json")
    );
    let body: Value = response.json().await.unwrap();
    assert_eq!(body["error"]["code"], code, "{body}");
    assert!(
        body["error"]["message"].as_str().unwrap().len() > 10,
        "{body}"
    );
    body
}

/// Asserts that an error body's message mentions `needle`.
fn assert_mentions(body: &Value, needle: &str) {
    let message = body["error"]["message"].as_str().unwrap();
    assert!(
        message.contains(needle),
        "{message:?} does not mention {needle:?}"
    );
}

#[tokio::test(flavor = "multi_thread")]
async fn multipart_json_happy_path() {
    let app = spawn_app(|_| {}).await;
    let response = app
        .client
        .post(app.url("/segment?overlay=true"))
        .header("x-request-id", "cell-7-frame-42")
        .multipart(form(photo(), Some(ends_json())))
        .send()
        .await
        .unwrap();
    assert_eq!(response.status(), 200);
    assert_eq!(response.headers()["x-request-id"], "cell-7-frame-42");
    let body: Value = response.json().await.unwrap();
    assert_eq!(body["request_id"], "cell-7-frame-42");
    assert_eq!(
        (body["width"].as_u64(), body["height"].as_u64()),
        (Some(640), Some(480))
    );
    let cables = body["cables"].as_array().unwrap();
    assert_cables_and_ends_agree(&body);
    for c in cables {
        let poly = c["polyline"].as_array().unwrap();
        assert!(poly.len() > 10);
        assert_eq!(c["spline"]["degree"], 3);
        let k = c["spline"]["knots"].as_array().unwrap().len();
        assert_eq!(
            k,
            c["spline"]["control_points"].as_array().unwrap().len() + 4
        );
        assert!(c["color"].as_str().unwrap().starts_with('#'));
        let score = c["score"].as_f64().unwrap();
        assert!((0.0..=1.0).contains(&score));
    }
    let ends = body["endpoints"].as_array().unwrap();
    assert_eq!(ends.len(), scene().ends().len());
    assert!(
        ends.iter()
            .all(|e| e["confidence"] == 1.0 && e["point"].as_array().unwrap().len() == 2)
    );
    assert_eq!(
        png_dimensions(&b64(body["mask_png"].as_str().unwrap())),
        (640, 480)
    );
    assert_eq!(
        png_dimensions(&b64(body["overlay_png"].as_str().unwrap())),
        (640, 480)
    );
    for stage in [
        "queue",
        "decode",
        "endpoints",
        "superpixels",
        "graph",
        "walks",
        "splines",
        "mask",
        "encode",
        "total",
    ] {
        assert!(
            body["timings_ms"][stage].as_f64().unwrap() >= 0.0,
            "{stage}"
        );
    }
    assert!(
        body["timings_ms"]["total"].as_f64().unwrap()
            >= body["timings_ms"]["superpixels"].as_f64().unwrap()
    );
}

/// No ends in the request: the detector runs, and every reported end carries its
/// confidence and cable.
#[tokio::test(flavor = "multi_thread")]
async fn a_photo_alone_runs_the_detector() {
    let app = spawn_app(|_| {}).await;
    let body = app.segment_photo(photo()).await;
    let ends = body["endpoints"].as_array().unwrap();
    assert_eq!(ends.len(), scene().ends().len());
    assert!(ends.iter().all(|e| e["confidence"] == 0.9), "{ends:?}");
    assert_cables_and_ends_agree(&body);
    assert!(
        app.endpoint_inferences().await >= 1.0,
        "endpoint inference time is recorded"
    );
    // A form whose text parts were left blank (as Swagger UI sends it) is a photo alone.
    let blank = form(photo(), Some(String::new())).text("options", "");
    let response = app
        .client
        .post(app.url("/segment"))
        .multipart(blank)
        .send()
        .await
        .unwrap();
    assert_eq!(response.status(), 200);
    let body: Value = response.json().await.unwrap();
    assert_eq!(body["endpoints"].as_array().unwrap().len(), ends.len());
    // And the OpenAPI document pre-fills nothing that would become a value.
    let doc: Value = serde_json::from_str(&app.get_text("/openapi.json").await).unwrap();
    for p in doc["paths"]["/segment"]["post"]["parameters"]
        .as_array()
        .unwrap()
    {
        assert!(p.get("example").is_none(), "{p}");
    }
}

#[tokio::test(flavor = "multi_thread")]
async fn raw_body_png_format_and_mask_kinds() {
    let app = spawn_app(|_| {}).await;
    let ends = ends_json();
    let raw = |query: String| {
        app.client
            .post(app.url(&format!("/segment?{query}")))
            .header("content-type", "image/jpeg")
            .body(photo())
            .send()
    };
    let q = serde_urlencoded::to_string([("endpoints", ends.as_str())]).unwrap();
    let json: Value = raw(q.clone()).await.unwrap().json().await.unwrap();
    let n = json["cables"].as_array().unwrap().len();
    assert!(n >= 1);
    assert!(json.get("overlay_png").is_none());

    let png = raw(format!("{q}&format=png")).await.unwrap();
    assert_eq!(png.status(), 200);
    assert_eq!(png.headers()["content-type"], "image/png");
    let mask = image::load_from_memory(&png.bytes().await.unwrap())
        .unwrap()
        .into_luma8();
    assert_eq!(mask.dimensions(), (640, 480));
    assert!(mask.pixels().all(|p| p.0[0] == 0 || p.0[0] == 255));

    let labels = raw(format!("{q}&format=png&mask=labels"))
        .await
        .unwrap()
        .bytes()
        .await
        .unwrap();
    let labels = image::load_from_memory(&labels).unwrap().into_luma8();
    let max = labels.pixels().map(|p| p.0[0]).max().unwrap();
    assert_eq!(max as usize, n, "label values run 1..=cables");

    let color = raw(format!("{q}&format=png&mask=color"))
        .await
        .unwrap()
        .bytes()
        .await
        .unwrap();
    let color = image::load_from_memory(&color).unwrap();
    assert_eq!(color.color(), image::ColorType::Rgb8);
}

#[tokio::test(flavor = "multi_thread")]
async fn bad_inputs_get_precise_json_errors_and_the_server_stays_up() {
    let app = spawn_app(|c| {
        c.max_body_bytes = 1_000_000;
        c.max_pixels = 1_000_000;
    })
    .await;
    let c = &app.client;
    let ends = ends_json();
    let post = |query: &str| c.post(app.url(&format!("/segment{query}")));

    // No image part.
    let f = Form::new().text("endpoints", ends.clone());
    expect_error(
        post("").multipart(f).send().await.unwrap(),
        400,
        "missing_image",
    )
    .await;
    // Empty raw body.
    expect_error(
        post("")
            .header("content-type", "image/jpeg")
            .send()
            .await
            .unwrap(),
        400,
        "empty_image",
    )
    .await;
    // Garbage declared as JPEG.
    let q = format!(
        "?{}",
        serde_urlencoded::to_string([("endpoints", ends.as_str())]).unwrap()
    );
    let garbage: Vec<u8> = (0..5000u32).map(|i| (i * 7919 % 251) as u8).collect();
    expect_error(
        post(&q)
            .header("content-type", "image/jpeg")
            .body(garbage)
            .send()
            .await
            .unwrap(),
        422,
        "undecodable_image",
    )
    .await;
    // Truncated JPEG.
    let mut half = photo();
    half.truncate(half.len() / 2);
    expect_error(
        post(&q)
            .header("content-type", "image/jpeg")
            .body(half)
            .send()
            .await
            .unwrap(),
        422,
        "undecodable_image",
    )
    .await;
    // Unsupported types: a text body, a GIF in a form.
    expect_error(
        post(&q)
            .header("content-type", "text/plain")
            .body("hello")
            .send()
            .await
            .unwrap(),
        415,
        "unsupported_media_type",
    )
    .await;
    let gif = b"GIF89a\x01\x00\x01\x00\x80\x00\x00\x00\x00\x00\xff\xff\xff!\xf9\x04\x01\x00\x00\x00\x00,\x00\x00\x00\x00\x01\x00\x01\x00\x00\x02\x02D\x01\x00;".to_vec();
    expect_error(
        post("")
            .multipart(form(gif, Some(ends.clone())))
            .send()
            .await
            .unwrap(),
        415,
        "unsupported_media_type",
    )
    .await;
    // Pixel bomb: a valid PNG header announcing 60000 x 60000.
    let bomb = ariadne_dlo::synth::png_header_only(60000, 60000);
    expect_error(
        post(&q)
            .header("content-type", "image/png")
            .body(bomb)
            .send()
            .await
            .unwrap(),
        413,
        "too_many_pixels",
    )
    .await;
    // Body over the limit.
    // Just over the limit, so the whole body usually fits the socket buffers and the
    // client reads the early answer instead of failing on a closed connection. The
    // server answers and closes before the body is all sent, so the client may still
    // find the connection closed while writing (HTTP/1.1 has no way to wait for that
    // answer): such a try is made again, a few times, and only an answer counts.
    let big = vec![0u8; 1_000_500];
    let mut refused = None;
    for _ in 0..5 {
        let sent = post(&q)
            .header("content-type", "image/jpeg")
            .body(big.clone())
            .send()
            .await;
        match sent {
            Ok(response) => {
                refused = Some(response);
                break;
            }
            Err(e) if e.is_request() => continue,
            Err(e) => panic!("{e}"),
        }
    }
    let refused = refused.expect("an answer to the body over the limit in 5 tries");
    // The unread body is still on its way: the connection is not reused.
    assert_eq!(refused.headers()["connection"], "close");
    expect_error(refused, 413, "body_too_large").await;
    // Malformed ends, ends outside, no ends.
    let f = form(photo(), Some("[[1, 2], [3]]".into()));
    expect_error(
        post("").multipart(f).send().await.unwrap(),
        400,
        "bad_endpoints",
    )
    .await;
    let f = form(photo(), Some("[[10, 10], [640, 100]]".into()));
    let body = expect_error(
        post("").multipart(f).send().await.unwrap(),
        422,
        "endpoint_outside_image",
    )
    .await;
    assert!(body["error"]["message"].as_str().unwrap().contains("#1"));
    // Bad query values.
    for bad in [
        "?mask=rainbow",
        "?overlay=maybe",
        "?format=gif",
        "?colour=red",
    ] {
        let f = form(photo(), Some(ends.clone()));
        expect_error(
            post(bad).multipart(f).send().await.unwrap(),
            400,
            "bad_query",
        )
        .await;
    }
    let f = form(photo(), Some(ends.clone()));
    expect_error(
        post("?preset=nope").multipart(f).send().await.unwrap(),
        400,
        "unknown_preset",
    )
    .await;
    // Options: bad JSON, unknown field, out of range.
    for (options, status, code) in [
        ("{not json", 400, "bad_options"),
        (r#"{"segments": 5}"#, 400, "bad_options"),
        (r#"{"n_segments": 0}"#, 422, "option_out_of_range"),
    ] {
        let f = form(photo(), Some(ends.clone())).text("options", options);
        expect_error(post("").multipart(f).send().await.unwrap(), status, code).await;
    }
    // Wrong method, unknown route.
    expect_error(
        c.get(app.url("/segment")).send().await.unwrap(),
        405,
        "method_not_allowed",
    )
    .await;
    expect_error(
        c.get(app.url("/nowhere")).send().await.unwrap(),
        404,
        "not_found",
    )
    .await;

    // Still up and still right.
    let ok = post("")
        .multipart(form(photo(), Some(ends)))
        .send()
        .await
        .unwrap();
    assert_eq!(ok.status(), 200);
}

/// A large photo (the scene scaled 3x) and options that make the work slow.
fn slow_request(app: &TestApp) -> reqwest::RequestBuilder {
    let img = image::load_from_memory(&photo()).unwrap().resize_exact(
        1920,
        1440,
        image::imageops::FilterType::Triangle,
    );
    let mut jpeg = Vec::new();
    img.write_to(
        &mut std::io::Cursor::new(&mut jpeg),
        image::ImageFormat::Jpeg,
    )
    .unwrap();
    let f = form(jpeg, Some("[[400, 400]]".into())).text(
        "options",
        r#"{"slic_iterations": 50, "n_segments": 8000, "working_pixels": 2764800}"#,
    );
    app.client.post(app.url("/segment")).multipart(f)
}

/// Careless or hostile requests are refused exactly: too many ends, media types that
/// only start like an accepted one, repeated form parts or option keys, a header of
/// zero pixels; a raw body sent as `application/octet-stream` is read like an image,
/// and a caller's request id is kept only when it is safe to log.
#[tokio::test(flavor = "multi_thread")]
async fn hostile_inputs_are_refused_exactly() {
    let app = spawn_app(|c| c.max_endpoints = 8).await;
    let c = &app.client;
    let post = |query: &str| c.post(app.url(&format!("/segment{query}")));

    // Nine ends against a limit of eight: 422 before any work.
    let nine = serde_json::to_string(&vec![[10.0, 10.0]; 9]).unwrap();
    let body = expect_error(
        post("")
            .multipart(form(photo(), Some(nine)))
            .send()
            .await
            .unwrap(),
        422,
        "too_many_endpoints",
    )
    .await;
    assert_mentions(&body, "limit of 8");
    // The media type is matched whole, parameters aside.
    expect_error(
        post("")
            .header("content-type", "image/jpegfoo")
            .body(photo())
            .send()
            .await
            .unwrap(),
        415,
        "unsupported_media_type",
    )
    .await;
    let ends = ends_json();
    let q = format!(
        "?{}",
        serde_urlencoded::to_string([("endpoints", ends.as_str())]).unwrap()
    );
    for content_type in ["image/jpeg; charset=binary", "application/octet-stream"] {
        let response = post(&q)
            .header("content-type", content_type)
            .body(photo())
            .send()
            .await
            .unwrap();
        assert_eq!(response.status(), 200, "{content_type}");
    }
    // A part given twice is an error naming it, not "last one wins".
    let twice = form(photo(), Some(ends.clone())).text("endpoints", ends.clone());
    let body = expect_error(
        post("").multipart(twice).send().await.unwrap(),
        400,
        "bad_multipart",
    )
    .await;
    assert_mentions(&body, "`endpoints`");
    let two_images = form(photo(), None).part("image", Part::bytes(photo()).file_name("b.jpg"));
    let body = expect_error(
        post("").multipart(two_images).send().await.unwrap(),
        400,
        "bad_multipart",
    )
    .await;
    assert_mentions(&body, "`image`");
    let keys = form(photo(), Some(ends.clone())).text("options", r#"{"kappa": 1, "kappa": 3}"#);
    let body = expect_error(
        post("").multipart(keys).send().await.unwrap(),
        400,
        "bad_options",
    )
    .await;
    assert_mentions(&body, "`kappa` appears twice");
    // A PNG header announcing 0 pixels of width.
    let empty = ariadne_dlo::synth::png_header_only(0, 480);
    expect_error(
        post(&q)
            .header("content-type", "image/png")
            .body(empty)
            .send()
            .await
            .unwrap(),
        422,
        "undecodable_image",
    )
    .await;
    // Corrupt JPEGs: cut in half with an end-of-image marker appended, and 400 bytes
    // of its entropy data overwritten (decoders fill both in silently).
    let jpeg = photo();
    let mut cut = jpeg[..jpeg.len() / 2].to_vec();
    cut.extend([0xFF, 0xD9]);
    let mut overwritten = jpeg.clone();
    let mut rng = ariadne_dlo::synth::Rng::new(3);
    let start = jpeg.len() / 3;
    for b in &mut overwritten[start..start + 400] {
        *b = rng.next_u64() as u8;
    }
    for corrupt in [cut, overwritten] {
        expect_error(
            post(&q)
                .header("content-type", "image/jpeg")
                .body(corrupt)
                .send()
                .await
                .unwrap(),
            422,
            "undecodable_image",
        )
        .await;
    }
    // Request ids: a safe one is echoed, one with quotes or spaces is replaced.
    for (sent, kept) in [("cell-7/job:42", true), ("a\"b c", false)] {
        let response = c
            .get(app.url("/healthz"))
            .header("x-request-id", sent)
            .send()
            .await
            .unwrap();
        let echoed = response.headers()["x-request-id"]
            .to_str()
            .unwrap()
            .to_string();
        assert_eq!(echoed == sent, kept, "{sent} -> {echoed}");
    }
    // Heads over hyper's limits get its plain answers (documented): 431, empty body.
    let huge = "x".repeat(100_000);
    let response = c
        .get(app.url("/healthz"))
        .header("x-huge", huge)
        .send()
        .await
        .unwrap();
    assert_eq!(response.status(), 431);
    let mut many = c.get(app.url("/healthz"));
    for i in 0..80 {
        many = many.header(format!("x-h{i}"), "1");
    }
    assert_eq!(many.send().await.unwrap().status(), 431);
    // And the server still answers.
    let response = post("")
        .multipart(form(photo(), Some(ends)))
        .send()
        .await
        .unwrap();
    assert_eq!(response.status(), 200);
}

#[tokio::test(flavor = "multi_thread")]
async fn overload_is_answered_429_with_retry_after() {
    let app = spawn_app(|c| {
        c.workers = Some(1);
        c.queue = 1;
        c.retry_after_s = 3;
    })
    .await;
    let requests: Vec<_> = (0..4).map(|_| slow_request(&app).send()).collect();
    let responses = futures_join(requests).await;
    let statuses: Vec<u16> = responses.iter().map(|r| r.status().as_u16()).collect();
    assert!(
        statuses.iter().all(|&s| s == 200 || s == 429),
        "{statuses:?}"
    );
    assert!(statuses.contains(&200), "{statuses:?}");
    let rejected: Vec<&reqwest::Response> =
        responses.iter().filter(|r| r.status() == 429).collect();
    assert!(!rejected.is_empty(), "{statuses:?}");
    assert_eq!(rejected[0].headers()["retry-after"], "3");
}

async fn futures_join<
    F: std::future::Future<Output = reqwest::Result<reqwest::Response>> + Send + 'static,
>(
    futures: Vec<F>,
) -> Vec<reqwest::Response> {
    let handles: Vec<_> = futures.into_iter().map(tokio::spawn).collect();
    let mut out = Vec::new();
    for h in handles {
        out.push(h.await.unwrap().unwrap());
    }
    out
}

#[tokio::test(flavor = "multi_thread")]
async fn deadline_gives_504() {
    let app = spawn_app(|c| c.deadline_ms = 40).await;
    let response = slow_request(&app).send().await.unwrap();
    expect_error(response, 504, "deadline_exceeded").await;
    // The server is fine afterwards.
    assert_eq!(app.get_status("/healthz").await, 200);
}

/// Work past the deadline is abandoned, not only its answer: with one worker, a request
/// that would run for seconds gets its 504 and the next request is served at once.
#[tokio::test(flavor = "multi_thread")]
async fn a_request_past_its_deadline_frees_its_worker() {
    let app = spawn_app(|c| {
        c.workers = Some(1);
        c.deadline_ms = 300;
    })
    .await;
    let started = std::time::Instant::now();
    let response = slow_request(&app).send().await.unwrap();
    expect_error(response, 504, "deadline_exceeded").await;
    let response = post_scene(&app, "/segment").await;
    assert_eq!(response.status(), 200, "the worker was still busy");
    assert!(started.elapsed() < std::time::Duration::from_millis(1500));
}

#[tokio::test(flavor = "multi_thread")]
async fn metrics_change_after_requests() {
    let app = spawn_app(|_| {}).await;
    let labels = [
        "route=\"/segment\"",
        "status_class=\"2xx\"",
        "preset=\"clutter\"",
    ];
    let before = app.get_text("/metrics").await;
    let r = post_scene(&app, "/segment?preset=clutter").await;
    assert_eq!(r.status(), 200);
    let after = app.get_text("/metrics").await;
    let delta = metric_value(&after, "ariadne_requests_total", &labels)
        - metric_value(&before, "ariadne_requests_total", &labels);
    assert!(delta >= 1.0, "requests counter did not move");
    for name in [
        "ariadne_request_duration_seconds_bucket",
        "ariadne_stage_duration_seconds_bucket{stage=\"superpixels\"",
        "ariadne_cables_per_image_bucket",
        "ariadne_queue_depth",
        "ariadne_in_flight",
    ] {
        assert!(after.contains(name), "{name} missing from /metrics");
    }
}

/// The scrape follows the conventions: a `# HELP` line for every series, rejection
/// counters present at 0 before any rejection, build info, process metrics, and the
/// preset label only on `/segment`.
#[tokio::test(flavor = "multi_thread")]
async fn metrics_follow_the_prometheus_conventions() {
    let app = spawn_app(|_| {}).await;
    assert_eq!(app.get_status("/healthz").await, 200);
    for asset in [
        "/docs/",
        "/docs/swagger-ui.css",
        "/docs/swagger-ui-bundle.js",
    ] {
        assert_eq!(app.get_status(asset).await, 200, "{asset}");
    }
    // One segmentation too: the process's CPU time is read in ticks of 1/100 s, and a
    // test process that has served only the small requests above may not have used
    // one yet (run alone, as `cargo nextest` runs each test, it read 0 three times in
    // four).
    assert_eq!(post_scene(&app, "/segment").await.status(), 200);
    let text = app.get_text("/metrics").await;
    // Swagger UI's files share one route label, not one each.
    assert!(
        !text.contains("route=\"/docs/swagger-ui.css\""),
        "per-file route label"
    );
    let families: std::collections::BTreeSet<&str> = text
        .lines()
        .filter_map(|l| l.strip_prefix("# TYPE "))
        .filter_map(|l| l.split_whitespace().next())
        .collect();
    assert!(families.len() >= 9, "{families:?}");
    for family in &families {
        assert!(
            text.contains(&format!("# HELP {family} ")),
            "no HELP for {family}"
        );
    }
    for reason in ariadne_dlo::http::metrics::REJECT_REASONS {
        let line = format!("ariadne_rejections_total{{reason=\"{reason}\"}}");
        assert!(text.contains(&line), "{line} missing");
    }
    assert!(text.contains(&format!(
        "ariadne_build_info{{version=\"{}\",model=\"",
        env!("CARGO_PKG_VERSION")
    )));
    for name in [
        "process_cpu_seconds_total",
        "process_resident_memory_bytes",
        "process_open_fds",
    ] {
        let value = metric_value(&text, name, &[]);
        assert!(value > 0.0, "{name} = {value}");
    }
    // /healthz was counted without a preset label.
    let health = text
        .lines()
        .find(|l| l.starts_with("ariadne_requests_total") && l.contains("route=\"/healthz\""))
        .expect("healthz counted");
    assert!(!health.contains("preset="), "{health}");
}

/// A raw blocking connection to the server.
fn raw_connection(app: &TestApp) -> std::net::TcpStream {
    std::net::TcpStream::connect(app.base.trim_start_matches("http://")).unwrap()
}

/// Reads until the server closes `stream` or `within` passes; what it sent, and
/// whether it closed.
fn read_until_closed(stream: &mut std::net::TcpStream, within: Duration) -> (String, bool) {
    use std::io::Read;
    let until = std::time::Instant::now() + within;
    let mut received = Vec::new();
    let mut buf = [0u8; 4096];
    loop {
        let left = until.saturating_duration_since(std::time::Instant::now());
        if left.is_zero() {
            return (String::from_utf8_lossy(&received).into(), false);
        }
        stream.set_read_timeout(Some(left)).unwrap();
        match stream.read(&mut buf) {
            Ok(0) => return (String::from_utf8_lossy(&received).into(), true),
            Ok(n) => received.extend_from_slice(&buf[..n]),
            Err(e)
                if e.kind() == std::io::ErrorKind::WouldBlock
                    || e.kind() == std::io::ErrorKind::TimedOut =>
            {
                return (String::from_utf8_lossy(&received).into(), false);
            }
            Err(_) => return (String::from_utf8_lossy(&received).into(), true),
        }
    }
}

/// Writes `chunk` every `every` up to `times` times, stopping when the server has
/// closed the connection; how long it was written to.
fn drip(stream: &mut std::net::TcpStream, chunk: &[u8], every: Duration, times: usize) -> Duration {
    use std::io::Write;
    let started = std::time::Instant::now();
    for _ in 0..times {
        if stream.write_all(chunk).is_err() {
            break;
        }
        std::thread::sleep(every);
    }
    started.elapsed()
}

/// Slow and idle clients are cut (headers dripped, a body dripped, a connection left
/// idle), and the connection cap holds others in the backlog until a slot frees, so
/// normal clients keep being served.
#[tokio::test(flavor = "multi_thread")]
async fn slow_and_idle_clients_are_cut_and_connections_are_capped() {
    use std::io::Write;
    let app = spawn_app(|c| {
        c.header_timeout_s = 1;
        c.body_timeout_s = 1;
        c.max_connections = 3;
    })
    .await;
    let (mut headers, mut idle) = (raw_connection(&app), raw_connection(&app));
    let addr = app.base.trim_start_matches("http://").to_string();
    let slow = tokio::task::spawn_blocking(move || {
        // Headers at one byte per 200 ms: closed at the header timeout.
        headers
            .write_all(b"POST /segment HTTP/1.1\r\nHost: x\r\n")
            .unwrap();
        drip(&mut headers, b"a", Duration::from_millis(200), 10);
        let (_, headers_closed) = read_until_closed(&mut headers, Duration::from_secs(2));
        // An idle connection: closed after the header timeout.
        let (_, idle_closed) = read_until_closed(&mut idle, Duration::from_secs(2));
        // A body at 10 bytes per 200 ms: 408 at the body timeout.
        let mut body = std::net::TcpStream::connect(&addr).unwrap();
        body.write_all(
            b"POST /segment HTTP/1.1\r\nHost: x\r\nContent-Type: image/jpeg\r\nContent-Length: 100000\r\n\r\n",
        )
        .unwrap();
        drip(&mut body, &[0u8; 10], Duration::from_millis(200), 8);
        let (answer, _) = read_until_closed(&mut body, Duration::from_secs(3));
        (headers_closed, idle_closed, answer)
    });
    let (headers_closed, idle_closed, answer) = slow.await.unwrap();
    assert!(headers_closed, "header drip not cut");
    assert!(idle_closed, "idle connection kept open");
    assert!(answer.starts_with("HTTP/1.1 408"), "{answer}");
    assert!(answer.contains("body_timeout"), "{answer}");
    // Three idle connections take every slot: a normal request waits in the backlog
    // until the header timeout cuts them, then is served.
    let hogs: Vec<_> = (0..3).map(|_| raw_connection(&app)).collect();
    tokio::time::sleep(Duration::from_millis(100)).await;
    let started = std::time::Instant::now();
    let response = post_scene(&app, "/segment").await;
    assert_eq!(response.status(), 200);
    let waited = started.elapsed();
    assert!(
        waited > Duration::from_millis(500),
        "the cap let a fourth connection in at once ({waited:?})"
    );
    assert!(waited < Duration::from_secs(3), "{waited:?}");
    drop(hogs);
}

/// Request bodies held in memory are bounded: an upload is admitted against a budget
/// from its declared length before its body is read; one that does not fit is answered
/// 429 at once, and the budget is returned when a request ends.
#[tokio::test(flavor = "multi_thread")]
async fn uploads_are_admitted_within_the_memory_budget() {
    use std::io::Write;
    let app = spawn_app(|c| {
        c.max_body_bytes = 1_000_000;
        c.upload_budget_bytes = 1_000_000;
    })
    .await;
    let head = |length: usize| {
        format!(
            "POST /segment HTTP/1.1\r\nHost: x\r\nContent-Type: image/jpeg\r\nContent-Length: {length}\r\n\r\n"
        )
    };
    // A 600 KB upload in progress holds 600 KB of the budget.
    let mut holder = raw_connection(&app);
    holder.write_all(head(600_000).as_bytes()).unwrap();
    holder.write_all(&[0u8; 1000]).unwrap();
    tokio::time::sleep(Duration::from_millis(200)).await;
    // A second one of 500 KB does not fit: 429 before a byte of its body is sent.
    let mut refused = raw_connection(&app);
    refused.write_all(head(500_000).as_bytes()).unwrap();
    let (answer, _) = tokio::task::spawn_blocking(move || {
        read_until_closed(&mut refused, Duration::from_secs(2))
    })
    .await
    .unwrap();
    assert!(answer.starts_with("HTTP/1.1 429"), "{answer}");
    assert!(answer.contains("upload_budget_full"), "{answer}");
    // A small one fits beside the first.
    let response = post_scene(&app, "/segment").await;
    assert_eq!(response.status(), 200);
    // Once the first ends, its share is back: a 500 KB declaration is admitted (and
    // its garbage body then refused for what it is).
    drop(holder);
    tokio::time::sleep(Duration::from_millis(200)).await;
    let response = app
        .client
        .post(app.url("/segment"))
        .header("content-type", "image/jpeg")
        .body(vec![7u8; 500_000])
        .send()
        .await
        .unwrap();
    expect_error(response, 422, "undecodable_image").await;
}

/// A client that hangs up while its request is worked on is still counted (status
/// class `client_closed`).
#[tokio::test(flavor = "multi_thread")]
async fn requests_whose_client_left_are_counted() {
    let app = spawn_app(|_| {}).await;
    let labels = ["route=\"/segment\"", "status_class=\"client_closed\""];
    let before = metric_value(
        &app.get_text("/metrics").await,
        "ariadne_requests_total",
        &labels,
    );
    // The client gives up 300 ms into a request that works for over a second.
    let abandoned =
        tokio::time::timeout(Duration::from_millis(300), slow_request(&app).send()).await;
    assert!(
        abandoned.is_err(),
        "the slow request answered within 300 ms"
    );
    let started = std::time::Instant::now();
    loop {
        let now = metric_value(
            &app.get_text("/metrics").await,
            "ariadne_requests_total",
            &labels,
        );
        if now > before {
            break;
        }
        assert!(started.elapsed() < Duration::from_secs(5), "never counted");
        tokio::time::sleep(Duration::from_millis(50)).await;
    }
}

/// Polls `condition` until it holds (panics after 30 s): waits for a state, never
/// for a guessed duration.
async fn wait_until<F: std::future::Future<Output = bool>>(mut condition: impl FnMut() -> F) {
    let deadline = tokio::time::Instant::now() + Duration::from_secs(30);
    while !condition().await {
        assert!(
            tokio::time::Instant::now() < deadline,
            "condition never held"
        );
        tokio::time::sleep(Duration::from_millis(10)).await;
    }
}

#[tokio::test(flavor = "multi_thread")]
async fn readiness_follows_warm_up_and_shutdown_and_drains_in_flight_work() {
    let mut app = spawn_app_with(|c| c.shutdown_delay_s = 1, false).await;
    assert_eq!(
        app.get_status("/readyz").await,
        503,
        "not ready before warm-up"
    );
    assert_eq!(app.get_status("/healthz").await, 200);

    let mut app2 = spawn_app(|c| c.shutdown_delay_s = 1).await;
    assert_eq!(app2.get_status("/readyz").await, 200);
    // A slow request in flight, then the shutdown signal.
    let in_flight = tokio::spawn(slow_request(&app2).send());
    wait_until(|| async {
        metric_value(&app2.get_text("/metrics").await, "ariadne_in_flight", &[]) >= 1.0
    })
    .await;
    app2.stop();
    wait_until(|| async { app2.get_status("/readyz").await == 503 }).await;
    let response = in_flight.await.unwrap().unwrap();
    assert_eq!(response.status(), 200, "in-flight request finished");
    let server = tokio::time::timeout(Duration::from_secs(30), app2.server)
        .await
        .unwrap();
    assert!(server.unwrap().is_ok(), "server exits cleanly");
    app.stop();
}

/// When the drain grace runs out, requests that cannot finish are answered 503 JSON
/// (not dropped with their connection), within the grace.
#[tokio::test(flavor = "multi_thread")]
async fn requests_left_when_the_grace_runs_out_get_503() {
    let mut app = spawn_app(|c| {
        c.workers = Some(1);
        c.shutdown_grace_s = 1;
        c.deadline_ms = 60_000;
    })
    .await;
    // One slow request running and two queued behind it: more than a second of work.
    let requests: Vec<_> = (0..3)
        .map(|_| tokio::spawn(slow_request(&app).send()))
        .collect();
    wait_until(|| async {
        metric_value(&app.get_text("/metrics").await, "ariadne_queue_depth", &[]) >= 2.0
    })
    .await;
    let stopped = std::time::Instant::now();
    app.stop();
    let mut refused = 0;
    for request in requests {
        let response = request
            .await
            .unwrap()
            .expect("an answer, not a dropped connection");
        // The running one may just make it; the queued ones cannot.
        if response.status() != 200 {
            expect_error(response, 503, "shutting_down").await;
            refused += 1;
        }
    }
    assert!(refused >= 2, "{refused} of 3 refused");
    tokio::time::timeout(Duration::from_secs(5), app.server)
        .await
        .unwrap()
        .unwrap()
        .unwrap();
    assert!(
        stopped.elapsed() < Duration::from_millis(1500),
        "{:?}",
        stopped.elapsed()
    );
}

#[tokio::test(flavor = "multi_thread")]
async fn openapi_is_served_committed_and_complete() {
    let app = spawn_app(|_| {}).await;
    let served: Value = app
        .client
        .get(app.url("/openapi.json"))
        .send()
        .await
        .unwrap()
        .json()
        .await
        .unwrap();
    let generated: Value = serde_json::to_value(http::openapi()).unwrap();
    assert_eq!(served, generated);
    // Tests run in the package root (as tests/deploy.rs relies on too): a path baked in
    // at compile time would point at whichever clone built the binary last.
    let committed_path = PathBuf::from("openapi/openapi.json");
    let committed: Value =
        serde_json::from_str(&std::fs::read_to_string(&committed_path).unwrap()).unwrap();
    assert_eq!(
        committed, generated,
        "openapi/openapi.json is stale: regenerate with `cargo run -- openapi > openapi/openapi.json`"
    );
    let responses = &generated["paths"]["/segment"]["post"]["responses"];
    for code in ["200", "400", "413", "415", "422", "429", "500", "504"] {
        assert!(responses.get(code).is_some(), "status {code} undocumented");
    }
    let docs = app.client.get(app.url("/docs/")).send().await.unwrap();
    assert_eq!(docs.status(), 200);
    assert!(docs.text().await.unwrap().contains("swagger"));
}
