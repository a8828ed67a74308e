//! Golden outputs: the cables the engine finds on deterministic synthetic scenes,
//! compared with committed JSON (`tests/golden/*.json`) within a tolerance, so that a
//! change that moves cables is seen even when accuracy floors still pass.
//!
//! After a deliberate change, regenerate with
//! `ARIADNE_BLESS=1 cargo test --release --test golden` and review the diff.

#![allow(clippy::unwrap_used)] // test code: a failure should panic

use std::path::PathBuf;

use ariadne_dlo::engine::{self, Params};
use ariadne_dlo::synth::{Background, SceneSpec, scene};
use serde::{Deserialize, Serialize};

/// Positions may move this much, pixels.
const POSITION_TOLERANCE_PX: f32 = 1.5;
/// Lengths and widths may change this much, relative.
const SIZE_TOLERANCE: f32 = 0.05;
/// Scores may change this much.
const SCORE_TOLERANCE: f32 = 0.05;
/// Points kept per cable: evenly spaced along the polyline, ends included.
const POINTS_PER_CABLE: usize = 9;

#[derive(Debug, Serialize, Deserialize, PartialEq)]
struct GoldenCable {
    points: Vec<[f32; 2]>,
    length_px: f32,
    width_px: f32,
    score: f32,
}

fn scenes() -> Vec<(&'static str, SceneSpec)> {
    let spec = |cables, background, seed| SceneSpec {
        width: 320,
        height: 240,
        cables,
        cable_width: 9.0,
        background,
        seed,
    };
    vec![
        ("plain-3", spec(3, Background::Plain, 21)),
        ("plain-5", spec(5, Background::Plain, 22)),
        ("textured-3", spec(3, Background::Textured, 23)),
    ]
}

fn golden_cables(name: &str, spec: &SceneSpec) -> Vec<GoldenCable> {
    let s = scene(spec);
    let seg = engine::segment(&s.image, &s.ends(), &Params::default())
        .unwrap_or_else(|e| panic!("{name}: {e}"));
    seg.cables
        .iter()
        .map(|c| {
            let n = c.polyline.len();
            GoldenCable {
                points: (0..POINTS_PER_CABLE)
                    .map(|i| c.polyline[i * (n - 1) / (POINTS_PER_CABLE - 1)])
                    .collect(),
                length_px: c.length_px,
                width_px: c.width_px,
                score: c.score,
            }
        })
        .collect()
}

fn close(a: f32, b: f32, relative: f32) -> bool {
    (a - b).abs() <= relative * a.abs().max(b.abs()).max(1.0)
}

#[test]
fn synthetic_scenes_match_their_golden_cables() {
    let dir = PathBuf::from("tests/golden");
    let bless = std::env::var_os("ARIADNE_BLESS").is_some();
    for (name, spec) in scenes() {
        let got = golden_cables(name, &spec);
        let path = dir.join(format!("{name}.json"));
        if bless {
            std::fs::write(&path, serde_json::to_string_pretty(&got).unwrap() + "\n").unwrap();
            continue;
        }
        let text = std::fs::read_to_string(&path)
            .unwrap_or_else(|e| panic!("{}: {e} (ARIADNE_BLESS=1 writes it)", path.display()));
        let want: Vec<GoldenCable> = serde_json::from_str(&text).unwrap();
        assert_eq!(got.len(), want.len(), "{name}: cable count");
        for (i, (g, w)) in got.iter().zip(&want).enumerate() {
            for (p, q) in g.points.iter().zip(&w.points) {
                let d = ((p[0] - q[0]).powi(2) + (p[1] - q[1]).powi(2)).sqrt();
                assert!(
                    d <= POSITION_TOLERANCE_PX,
                    "{name} cable {i}: {p:?} vs {q:?}"
                );
            }
            assert!(
                close(g.length_px, w.length_px, SIZE_TOLERANCE),
                "{name} cable {i} length: {g:?} vs {w:?}"
            );
            assert!(
                close(g.width_px, w.width_px, SIZE_TOLERANCE),
                "{name} cable {i} width: {g:?} vs {w:?}"
            );
            assert!(
                (g.score - w.score).abs() <= SCORE_TOLERANCE,
                "{name} cable {i} score: {g:?} vs {w:?}"
            );
        }
    }
}
