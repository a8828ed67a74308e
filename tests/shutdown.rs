//! The real binary's shutdown: SIGTERM with a long request in flight exits after one
//! drain grace period, not two; and its text logs, written to a pipe, carry no colour
//! codes (needs `make setup`: the service loads the model).

#![allow(clippy::unwrap_used)] // test code: a failure should panic

use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

/// A free loopback port (bound, then released for the service).
fn free_port() -> u16 {
    std::net::TcpListener::bind("127.0.0.1:0")
        .unwrap()
        .local_addr()
        .unwrap()
        .port()
}

/// Kills the service if the test fails half-way.
struct Service(Child);

impl Drop for Service {
    fn drop(&mut self) {
        let _ = self.0.kill();
    }
}

#[tokio::test(flavor = "multi_thread")]
async fn the_drain_grace_is_applied_once() {
    let port = free_port();
    let mut service = Service(
        Command::new(env!("CARGO_BIN_EXE_ariadne"))
            .args(["serve", "--bind", &format!("127.0.0.1:{port}")])
            .args(["--workers", "1", "--shutdown-grace-s", "1"])
            .args(["--deadline-ms", "20000"])
            .stdout(Stdio::piped())
            .stderr(Stdio::null())
            .spawn()
            .unwrap(),
    );
    let base = format!("http://127.0.0.1:{port}");
    let client = reqwest::Client::new();
    let started = Instant::now();
    loop {
        let ready = client.get(format!("{base}/readyz")).send().await;
        if ready.is_ok_and(|r| r.status() == 200) {
            break;
        }
        assert!(started.elapsed() < Duration::from_secs(30), "never ready");
        tokio::time::sleep(Duration::from_millis(50)).await;
    }
    // A request that works for about 3 s on this machine: a 2560x1920 photo segmented
    // at 4 MP with 20,000 superpixels, 50 SLIC iterations and the widest walks.
    let photo = image::RgbImage::from_fn(2560, 1920, |x, y| {
        image::Rgb([(x % 251) as u8, (y % 241) as u8, ((x + y) % 239) as u8])
    });
    let mut png = Vec::new();
    photo
        .write_to(&mut std::io::Cursor::new(&mut png), image::ImageFormat::Png)
        .unwrap();
    let options = r#"{"slic_iterations": 50, "n_segments": 20000, "working_pixels": 4000000,
        "neighbourhood_order": 8, "jump_order": 12}"#;
    let form = reqwest::multipart::Form::new()
        .part(
            "image",
            reqwest::multipart::Part::bytes(png).file_name("p.png"),
        )
        .text(
            "endpoints",
            "[[400, 400], [1000, 1000], [1500, 300], [2000, 1500]]",
        )
        .text("options", options);
    let slow = tokio::spawn(
        client
            .post(format!("{base}/segment"))
            .multipart(form)
            .send(),
    );
    tokio::time::sleep(Duration::from_millis(500)).await;
    let signalled = Instant::now();
    let pid = service.0.id().to_string();
    assert!(
        Command::new("kill")
            .args(["-TERM", &pid])
            .status()
            .unwrap()
            .success()
    );
    let status = loop {
        if let Some(status) = service.0.try_wait().unwrap() {
            break status;
        }
        assert!(
            signalled.elapsed() < Duration::from_secs(10),
            "still running"
        );
        tokio::time::sleep(Duration::from_millis(20)).await;
    };
    let took = signalled.elapsed();
    assert!(status.success(), "{status}");
    // One grace period (1 s) and a little; two would be over 2 s.
    assert!(
        took < Duration::from_millis(1700),
        "exited {took:?} after SIGTERM"
    );
    assert!(
        took >= Duration::from_millis(900),
        "exited {took:?}: no grace at all"
    );
    let _ = slow.await;
    let mut logs = String::new();
    std::io::Read::read_to_string(&mut service.0.stdout.take().unwrap(), &mut logs).unwrap();
    assert!(logs.contains("listening"), "{logs}");
    assert!(
        !logs.contains('\u{1b}'),
        "colour codes in logs written to a pipe"
    );
}
