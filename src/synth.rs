//! Deterministic synthetic cable scenes with known truth, for tests (and training).
//!
//! A scene is a plain or textured background with smooth random curves of given width
//! and colour drawn on it, later ones over earlier ones, so that they cross. Each cable
//! keeps its exact centreline; its ends are where a detector would find terminals.

use image::{GrayImage, Luma, Rgb, RgbImage};

use crate::engine::render::stroke;

/// A small, fast, deterministic generator (SplitMix64).
#[derive(Debug, Clone)]
pub struct Rng(u64);

impl Rng {
    /// A generator from a seed.
    pub fn new(seed: u64) -> Self {
        Self(seed)
    }

    /// Next 64 random bits.
    pub fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }

    /// Uniform in [lo, hi).
    pub fn range(&mut self, lo: f32, hi: f32) -> f32 {
        lo + (hi - lo) * ((self.next_u64() >> 40) as f32 / (1u64 << 24) as f32)
    }
}

/// A PNG that is only a signature and an IHDR chunk (correct CRC) announcing
/// `width` x `height` RGB pixels, with no pixel data: the "pixel bomb" a server must
/// refuse from the header alone.
pub fn png_header_only(width: u32, height: u32) -> Vec<u8> {
    let mut ihdr = b"IHDR".to_vec();
    ihdr.extend_from_slice(&width.to_be_bytes());
    ihdr.extend_from_slice(&height.to_be_bytes());
    ihdr.extend_from_slice(&[8, 2, 0, 0, 0]);
    let mut crc = !0u32;
    for &b in &ihdr {
        crc ^= b as u32;
        for _ in 0..8 {
            crc = if crc & 1 == 1 {
                (crc >> 1) ^ 0xEDB8_8320
            } else {
                crc >> 1
            };
        }
    }
    let mut out = b"\x89PNG\r\n\x1a\n".to_vec();
    out.extend_from_slice(&13u32.to_be_bytes());
    out.extend_from_slice(&ihdr);
    out.extend_from_slice(&(!crc).to_be_bytes());
    out
}

/// Background kinds.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Background {
    /// One light colour with mild noise (like paper or a table).
    Plain,
    /// Random coloured blobs and strokes (like the dataset's complex scenes).
    Textured,
}

/// What to generate.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SceneSpec {
    /// Image width, pixels.
    pub width: u32,
    /// Image height, pixels.
    pub height: u32,
    /// Number of cables.
    pub cables: usize,
    /// Cable width, pixels.
    pub cable_width: f32,
    /// Background kind.
    pub background: Background,
    /// Seed: the same spec and seed give the same scene.
    pub seed: u64,
}

/// A cable of a synthetic scene.
#[derive(Debug, Clone, PartialEq)]
pub struct SynthCable {
    /// Exact centreline, about one point per pixel.
    pub centreline: Vec<[f32; 2]>,
    /// Colour.
    pub color: [u8; 3],
}

/// A generated scene with its truth.
#[derive(Debug, Clone)]
pub struct Scene {
    /// The picture.
    pub image: RgbImage,
    /// Its cables.
    pub cables: Vec<SynthCable>,
    /// Union mask of the cable bodies (0/255).
    pub mask: GrayImage,
}

impl Scene {
    /// The ends of the cables that lie inside the frame (more than 12 px from the
    /// border): the terminals a photo shows.
    pub fn terminals(&self) -> Vec<[f64; 2]> {
        let (w, h) = (self.image.width() as f64, self.image.height() as f64);
        self.ends()
            .into_iter()
            .filter(|p| p[0] > 12.0 && p[1] > 12.0 && p[0] < w - 13.0 && p[1] < h - 13.0)
            .collect()
    }

    /// Both ends of every cable, in cable order.
    pub fn ends(&self) -> Vec<[f64; 2]> {
        self.cables
            .iter()
            .flat_map(|c| [c.centreline[0], c.centreline[c.centreline.len() - 1]])
            .map(|p| [p[0] as f64, p[1] as f64])
            .collect()
    }
}

/// Saturated cable colours, distinct from each other and from light backgrounds.
const CABLE_COLOURS: [[u8; 3]; 6] = [
    [200, 30, 30],
    [30, 60, 190],
    [30, 150, 50],
    [230, 120, 20],
    [40, 40, 40],
    [150, 40, 160],
];

/// Generates the scene described by `spec`.
pub fn scene(spec: &SceneSpec) -> Scene {
    let mut rng = Rng::new(spec.seed);
    let (w, h) = (spec.width, spec.height);
    let mut image = background(spec, &mut rng);
    let mut mask = GrayImage::new(w, h);
    let mut cables = Vec::new();
    for k in 0..spec.cables {
        let centreline = random_curve(&mut rng, w as f32, h as f32);
        let color = CABLE_COLOURS[k % CABLE_COLOURS.len()];
        stroke(&centreline, spec.cable_width, w, h, |x, y| {
            image.put_pixel(x, y, Rgb(color));
            mask.put_pixel(x, y, Luma([255]));
        });
        cables.push(SynthCable { centreline, color });
    }
    Scene {
        image,
        cables,
        mask,
    }
}

fn background(spec: &SceneSpec, rng: &mut Rng) -> RgbImage {
    let (w, h) = (spec.width, spec.height);
    let base = [
        rng.range(200.0, 250.0),
        rng.range(200.0, 250.0),
        rng.range(190.0, 240.0),
    ];
    let mut img = RgbImage::from_fn(w, h, |_, _| {
        let n = rng.range(-6.0, 6.0);
        Rgb(base.map(|c| (c + n).clamp(0.0, 255.0) as u8))
    });
    if spec.background == Background::Textured {
        let strokes = (w * h / 2500) as usize;
        for _ in 0..strokes {
            let colour = [
                rng.range(60.0, 250.0),
                rng.range(60.0, 250.0),
                rng.range(60.0, 250.0),
            ]
            .map(|c| c as u8);
            let a = [rng.range(0.0, w as f32), rng.range(0.0, h as f32)];
            let b = [a[0] + rng.range(-40.0, 40.0), a[1] + rng.range(-40.0, 40.0)];
            let width = rng.range(1.0, 3.0);
            stroke(&[a, b], width, w, h, |x, y| {
                img.put_pixel(x, y, Rgb(colour))
            });
        }
    }
    img
}

/// A smooth random curve fully inside the frame (with a margin), 1 px steps: heading
/// driven by a few low-frequency sines. Curves that leave the frame are drawn again,
/// shorter after every hundred failures, so small frames terminate too.
fn random_curve(rng: &mut Rng, w: f32, h: f32) -> Vec<[f32; 2]> {
    let margin = (w.min(h) / 6.0).min(25.0);
    let mut scale = 1.0f32;
    for attempt in 1.. {
        if attempt % 100 == 0 {
            scale *= 0.8;
        }
        let len = (rng.range(0.35, 0.8) * w.min(h) * 1.4 * scale).max(4.0);
        let mut p = [rng.range(margin, w - margin), rng.range(margin, h - margin)];
        let theta0 = rng.range(0.0, std::f32::consts::TAU);
        let waves: Vec<(f32, f32, f32)> = (0..3)
            .map(|k| {
                (
                    rng.range(-0.8, 0.8) / (k + 1) as f32,
                    rng.range(0.5, 2.0) * (k + 1) as f32,
                    rng.range(0.0, 6.3),
                )
            })
            .collect();
        let mut pts = vec![p];
        let mut ok = true;
        for i in 1..len as usize {
            let s = i as f32 / len;
            let theta = theta0
                + waves
                    .iter()
                    .map(|(a, f, ph)| a * (f * s * std::f32::consts::PI + ph).sin())
                    .sum::<f32>();
            p = [p[0] + theta.cos(), p[1] + theta.sin()];
            if p[0] < margin || p[1] < margin || p[0] > w - margin || p[1] > h - margin {
                ok = false;
                break;
            }
            pts.push(p);
        }
        if ok {
            return pts;
        }
    }
    unreachable!("the attempt loop only ends by returning")
}

/// The hard cases the cable field is for, each one 640x480 photo.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Case {
    /// A black cable on dark grey paper (little colour contrast).
    DarkOnDark,
    /// Two cables of the same colour running side by side, two cable widths apart.
    SideBySide,
    /// A cable crossing the frame from border to border (no end in view), and one
    /// with both ends in view.
    NoEndInView,
    /// A cable bent round in two tight arcs (it does not cross itself).
    Loop,
    // Later cases come last: a case's noise is seeded by its discriminant.
    /// `SideBySide` at the width cables have in a 640x480 photo of a work cell (8 px):
    /// the strip of background between them is as wide as a superpixel and reads as a
    /// cable with an edge on either side.
    SideBySideThin,
    /// A cable that crosses itself in a loop.
    CrossingLoop,
    /// A cable whose terminal lies against the side of another cable (a T-junction):
    /// the walks along the other cable pass within reach of that end.
    TerminalAgainstCable,
    /// Two cables crossing at 60°, all four ends in view: with no end detected, the
    /// field shows one X-shaped piece.
    Crossing,
    /// Two cables of the same colour laid together, a sliver of background (1 px)
    /// between them: one band to the network and to the superpixels.
    Twins,
    /// Two cables of one colour laid together across the whole frame, light on a dark
    /// background: no end in view, one band to the network and the superpixels.
    TwinsNoEndInView,
    /// A cable that turns a full circle and a little more on its way, crossing itself at
    /// a shallow angle (about 25°): at the crossing the way on is straighter than the
    /// way into the loop.
    Curl,
    /// A power cable 16 px wide across two wires 5 px wide, all ends in view: the
    /// wires read thin and the photo is segmented again enlarged for them, where the
    /// power cable is too wide to follow (the first pass's is taken in).
    Mixed,
    /// A pale grey cable on a white board crossing the frame (no end in view), and a
    /// dark one with both ends in view: little colour or contrast to walk by, yet the
    /// network's field sees it whole.
    PaleNoEndInView,
    /// `Curl` with an orange cable (ends in view) across its loop, 20 px above the
    /// loop's centre: a chord of it, so the loop leaves and comes back to the orange
    /// cable too, 80 px apart.
    LoopCrossedByAnother,
    /// Two grey cables of one colour laid a sliver of black card apart (4 px, about
    /// half a cable): one band to the network and the walks, whose profile closes
    /// over the sliver only when read with a gap as wide as a cable.
    TwinsApart,
    /// A cable that runs in at a shallow angle (about 17°) to end beside another, its
    /// terminal 15 px off the other's centreline: the walks along the other cable pass
    /// within reach of that end, heading nearly the way the field runs there.
    TerminalBesideCable,
    /// A cable that turns a full circle and a little more (0.6 rad, 34°) at 60 px
    /// radius on its way: wider than `Curl`'s, its way in and its way on meet it
    /// tangentially on either side of its lowest point, so the walk follows the loop's
    /// lowest arc between them, and where the loop leaves and comes back lie far apart
    /// along the cable (the stress scenes' loops drawn so).
    TangentLoop,
}

impl Case {
    /// Every case.
    pub const ALL: [Case; 17] = [
        Case::DarkOnDark,
        Case::SideBySide,
        Case::SideBySideThin,
        Case::NoEndInView,
        Case::Loop,
        Case::CrossingLoop,
        Case::TerminalAgainstCable,
        Case::Crossing,
        Case::Twins,
        Case::TwinsNoEndInView,
        Case::Curl,
        Case::Mixed,
        Case::PaleNoEndInView,
        Case::LoopCrossedByAnother,
        Case::TwinsApart,
        Case::TerminalBesideCable,
        Case::TangentLoop,
    ];

    /// Width of the case's `k`-th cable, pixels.
    fn cable_width(self, k: usize) -> f32 {
        match self {
            Case::SideBySideThin => 8.0,
            Case::Twins | Case::TwinsNoEndInView | Case::TwinsApart => 9.0,
            Case::Mixed if k == 0 => 16.0,
            Case::Mixed => 5.0,
            _ => 11.0,
        }
    }
}

/// `Curl`'s cable, in 1 px steps: 220 px to the right from (70, 330), a turn of 2π +
/// 0.45 rad towards the top at 45 px radius (the loop above the line, about
/// (290, 285)), 220 px on.
fn curl() -> Vec<[f32; 2]> {
    looped([70.0, 330.0], 0.0, 45.0, std::f32::consts::TAU + 0.45)
}

/// A cable with a loop, in 1 px steps: 220 px from `from` setting off at `heading`
/// (radians, y pointing down), a turn of `turn` radians towards the top (anticlockwise
/// on screen) at `radius` pixels, and 220 px on.
fn looped(from: [f32; 2], heading: f32, radius: f32, turn: f32) -> Vec<[f32; 2]> {
    let straight = 220;
    let round = (turn * radius).round() as usize;
    let mut path = turning(from, heading, 0.0, straight);
    path.extend(turning(path[path.len() - 1], heading, -turn, round).split_off(1));
    path.extend(turning(path[path.len() - 1], heading - turn, 0.0, straight).split_off(1));
    path
}

/// A path in 1 px steps from `from`, `length` steps long, setting off at `heading`
/// (radians, y pointing down) and turning uniformly by `turn` over its length: a
/// straight run with no turn, an arc of radius `length / turn` with one.
pub fn turning(from: [f32; 2], heading: f32, turn: f32, length: usize) -> Vec<[f32; 2]> {
    let mut p = from;
    let mut out = vec![p];
    for i in 0..length {
        let a = heading + turn * i as f32 / length as f32;
        p = [p[0] + a.cos(), p[1] + a.sin()];
        out.push(p);
    }
    out
}

/// A cable to draw: centreline and colour.
type Drawn = (Vec<[f32; 2]>, [u8; 3]);

/// The line `offset` pixels beside `line` (centre to centre), along its normals: to
/// the right of its direction, y pointing down.
fn alongside(line: &[[f32; 2]], offset: f32) -> Vec<[f32; 2]> {
    (0..line.len())
        .map(|i| {
            let (p, q) = (line[i.saturating_sub(1)], line[(i + 1).min(line.len() - 1)]);
            let (dx, dy) = (q[0] - p[0], q[1] - p[1]);
            let k = offset / dx.hypot(dy);
            [line[i][0] - dy * k, line[i][1] + dx * k]
        })
        .collect()
}

/// A [`Case`] scene: shaded cables (a darker rim, a lighter core) with crimped metal
/// terminals beyond every end inside the frame, on a noisy plain background.
pub fn case(case: Case) -> Scene {
    let (w, h) = (640u32, 480u32);
    let width = case.cable_width(0);
    let line = |f: &dyn Fn(f32) -> [f32; 2], n: usize| -> Vec<[f32; 2]> {
        (0..=n).map(|i| f(i as f32 / n as f32)).collect()
    };
    let arc = |x0: f32, y0: f32, x1: f32, y1: f32, bend: f32| {
        move |t: f32| {
            let (nx, ny) = (-(y1 - y0), x1 - x0);
            let b = bend * 4.0 * t * (1.0 - t);
            [x0 + (x1 - x0) * t + nx * b, y0 + (y1 - y0) * t + ny * b]
        }
    };
    let (background, cables): ([u8; 3], Vec<Drawn>) = match case {
        Case::DarkOnDark => (
            [58, 54, 52],
            vec![(
                line(&arc(120.0, 380.0, 520.0, 120.0, 0.25), 600),
                [14, 14, 16],
            )],
        ),
        Case::SideBySide | Case::SideBySideThin => {
            let a = line(&arc(90.0, 300.0, 560.0, 260.0, 0.2), 600);
            let b = a.iter().map(|p| [p[0], p[1] + 3.0 * width]).collect();
            (
                [225, 222, 215],
                vec![(a, [200, 40, 35]), (b, [200, 40, 35])],
            )
        }
        Case::Twins => {
            let a = line(&arc(110.0, 140.0, 540.0, 330.0, 0.15), 600);
            let b = alongside(&a, width + 1.0);
            (
                [226, 224, 218],
                vec![(a, [40, 90, 200]), (b, [40, 90, 200])],
            )
        }
        Case::TwinsApart => {
            let a = line(&arc(130.0, 110.0, 520.0, 360.0, -0.2), 600);
            let b = alongside(&a, width + 4.0);
            (
                [26, 26, 28],
                vec![(a, [150, 150, 152]), (b, [150, 150, 152])],
            )
        }
        Case::TwinsNoEndInView => {
            // From beyond the left edge to beyond the right one.
            let a = line(&arc(-30.0, 110.0, 670.0, 320.0, 0.12), 800);
            let b = alongside(&a, width);
            ([40, 38, 36], vec![(a, [215, 190, 40]), (b, [215, 190, 40])])
        }
        Case::NoEndInView => (
            [222, 226, 230],
            vec![
                (
                    line(&arc(0.0, 150.0, 639.0, 330.0, 0.1), 800),
                    [30, 70, 190],
                ),
                (
                    line(&arc(150.0, 420.0, 480.0, 400.0, -0.3), 500),
                    [30, 150, 60],
                ),
            ],
        ),
        Case::Loop => {
            // A prolate cycloid x = a u − b sin u, y = −b cos u, a = 32, b = 90, over
            // u in -1.2..2π + 1.2: arcs of two of its loops, which would close beyond
            // that range (at u = ±2.23 about 0 and 2π), so it does not cross itself; its
            // tightest bends are (b − a)² / b = 37 px.
            let f = |t: f32| {
                let u = -1.2 + t * (std::f32::consts::TAU + 2.4);
                [140.0 + 32.0 * u - 90.0 * u.sin(), 250.0 - 90.0 * u.cos()]
            };
            ([230, 228, 220], vec![(line(&f, 900), [220, 150, 20])])
        }
        Case::Curl => ([228, 226, 220], vec![(curl(), [40, 90, 200])]),
        Case::TangentLoop => {
            // 220 px from (80, 200) heading down and right (0.5 rad), a turn of 2π + 0.6
            // rad towards the top at 60 px radius, 220 px on, heading up and right.
            let path = looped([80.0, 200.0], 0.5, 60.0, std::f32::consts::TAU + 0.6);
            ([226, 224, 218], vec![(path, [200, 40, 40])])
        }
        Case::LoopCrossedByAnother => (
            [228, 226, 220],
            vec![
                (
                    line(&arc(60.0, 265.0, 600.0, 265.0, 0.0), 540),
                    [220, 120, 30],
                ),
                (curl(), [40, 90, 200]),
            ],
        ),
        Case::CrossingLoop => {
            // The same curve with a = 40, b = 100 over one period about u = 0: it
            // crosses itself at u = ±2.13 (a u = b sin u), at (320, 273), its two
            // branches 85° apart; its tightest bend, at the top, is 36 px.
            let f = |t: f32| {
                let u = -4.0 + t * 8.0;
                [320.0 + 40.0 * u - 100.0 * u.sin(), 220.0 - 100.0 * u.cos()]
            };
            ([230, 228, 220], vec![(line(&f, 900), [220, 150, 20])])
        }
        Case::TerminalAgainstCable => (
            // The first cable sags through (318, 254); the second rises from the bottom
            // edge to an end 17 px below that, its metal tip touching the first.
            [226, 224, 218],
            vec![
                (
                    line(&arc(100.0, 200.0, 540.0, 220.0, 0.1), 600),
                    [30, 150, 50],
                ),
                (
                    line(&arc(340.0, 479.0, 320.0, 271.0, 0.08), 300),
                    [40, 40, 44],
                ),
            ],
        ),
        Case::TerminalBesideCable => (
            // The first cable runs straight through (330, 211); the second ends at
            // (330, 226), its metal tip pointing along the first, 4 px short of its rim.
            [226, 224, 218],
            vec![
                (
                    line(&arc(40.0, 180.0, 600.0, 240.0, 0.0), 600),
                    [30, 150, 50],
                ),
                (
                    line(&arc(90.0, 330.0, 330.0, 226.0, 0.05), 300),
                    [120, 70, 40],
                ),
            ],
        ),
        Case::Mixed => (
            // The power cable sags across the lower half; the wires cross it.
            [222, 220, 214],
            vec![
                (
                    line(&arc(60.0, 330.0, 580.0, 300.0, 0.12), 600),
                    [35, 35, 38],
                ),
                (
                    line(&arc(90.0, 90.0, 520.0, 420.0, -0.1), 600),
                    [200, 30, 30],
                ),
                (
                    line(&arc(560.0, 80.0, 250.0, 440.0, 0.1), 500),
                    [30, 60, 190],
                ),
            ],
        ),
        Case::PaleNoEndInView => (
            [232, 231, 227],
            vec![
                (
                    line(&arc(0.0, 320.0, 639.0, 140.0, -0.12), 800),
                    [200, 200, 196],
                ),
                (
                    line(&arc(140.0, 90.0, 470.0, 420.0, 0.15), 600),
                    [40, 40, 44],
                ),
            ],
        ),
        Case::Crossing => (
            // Straight-ish cables through (320, 240), 60° apart.
            [224, 222, 216],
            vec![
                (
                    line(&arc(110.0, 180.0, 530.0, 300.0, 0.05), 500),
                    [30, 70, 190],
                ),
                (
                    line(&arc(220.0, 420.0, 420.0, 60.0, -0.05), 500),
                    [230, 120, 20],
                ),
            ],
        ),
    };
    let mut rng = Rng::new(case as u64 + 1);
    let mut image = RgbImage::from_fn(w, h, |_, _| {
        let n = rng.range(-5.0, 5.0);
        Rgb(background.map(|c| (c as f32 + n).clamp(0.0, 255.0) as u8))
    });
    let mut mask = GrayImage::new(w, h);
    let mut out = Vec::new();
    for (k, (centreline, color)) in cables.into_iter().enumerate() {
        let width = case.cable_width(k);
        let rim = color.map(|c| (c as f32 * 0.55) as u8);
        let core = color.map(|c| (c as f32 * 1.25 + 25.0).min(255.0) as u8);
        for (stroke_width, colour) in [(width, rim), (width - 3.0, color), (3.0, core)] {
            stroke(&centreline, stroke_width, w, h, |x, y| {
                image.put_pixel(x, y, Rgb(colour))
            });
        }
        stroke(&centreline, width, w, h, |x, y| {
            mask.put_pixel(x, y, Luma([255]))
        });
        for (end, before) in [
            (centreline[0], centreline[8]),
            (
                centreline[centreline.len() - 1],
                centreline[centreline.len() - 9],
            ),
        ] {
            let inside = end[0] > 12.0 && end[1] > 12.0 && end[0] < 627.0 && end[1] < 467.0;
            if inside {
                let d = [end[0] - before[0], end[1] - before[1]];
                let n = (d[0] * d[0] + d[1] * d[1]).sqrt().max(1e-3);
                let tip = [end[0] + d[0] / n * 14.0, end[1] + d[1] / n * 14.0];
                stroke(&[end, tip], width - 4.0, w, h, |x, y| {
                    image.put_pixel(x, y, Rgb([175, 170, 160]))
                });
            }
        }
        out.push(SynthCable { centreline, color });
    }
    Scene {
        image,
        cables: out,
        mask,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn scenes_are_deterministic_and_consistent() {
        let spec = SceneSpec {
            width: 200,
            height: 150,
            cables: 3,
            cable_width: 9.0,
            background: Background::Textured,
            seed: 7,
        };
        let (a, b) = (scene(&spec), scene(&spec));
        assert_eq!(a.image, b.image);
        assert_eq!(a.cables.len(), 3);
        assert_eq!(a.ends().len(), 6);
        assert!(a.mask.pixels().filter(|p| p.0[0] == 255).count() > 100);
        for c in &a.cables {
            for p in &c.centreline {
                assert!(p[0] >= 0.0 && p[1] >= 0.0 && p[0] < 200.0 && p[1] < 150.0);
            }
        }
    }
}
