//! The cable field: what a network saw in the photo, cell by cell — the probability
//! that a cable lies there and the cable's unsigned direction — sampled where the
//! engine needs it (superpixels, walk steps, centrelines, the border).
//!
//! The field is a coarse grid (one cell per `cell_px` photo pixels, 8 for the bundled
//! model at 640x480); it is read with bilinear interpolation between cell centres.

use super::superpixels::Superpixels;

/// Spacing of the field's readings along a straight gap (a walk's step, the gap between
/// two exits at the border), pixels: a quarter of a cell at 640x480.
pub const GAP_SAMPLE_PX: f32 = 2.0;

/// A cable-probability and orientation grid over the photo.
#[derive(Debug, Clone, PartialEq)]
pub struct CableField {
    /// Grid width, cells.
    pub width: usize,
    /// Grid height, cells.
    pub height: usize,
    /// Photo pixels per cell, horizontally and vertically.
    pub cell_px: [f32; 2],
    /// Probability in 0..=1 that a cable lies in each cell, row-major.
    pub cable: Vec<f32>,
    /// The cable's unsigned direction θ in each cell as (cos 2θ, sin 2θ); the length
    /// (0..=1) says how sure the network is.
    pub orientation: Vec<[f32; 2]>,
}

/// What the field says about one superpixel.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct VertexField {
    /// Mean cable probability over the superpixel's pixels.
    pub cable: f32,
    /// Mean (cos 2θ, sin 2θ) over its pixels.
    pub orientation: [f32; 2],
}

impl CableField {
    /// Bilinear weights of the four cells around photo point (x, y): the top-left cell
    /// and the fractions towards the next cell in x and y.
    fn locate(&self, x: f32, y: f32) -> (usize, usize, f32, f32) {
        let gx = (x / self.cell_px[0] - 0.5).clamp(0.0, (self.width - 1) as f32);
        let gy = (y / self.cell_px[1] - 0.5).clamp(0.0, (self.height - 1) as f32);
        let (x0, y0) = (gx.floor() as usize, gy.floor() as usize);
        (x0, y0, gx - x0 as f32, gy - y0 as f32)
    }

    fn bilinear<T: Copy>(&self, grid: &[T], x: f32, y: f32, mix: impl Fn(&[(T, f32)]) -> T) -> T {
        let (x0, y0, fx, fy) = self.locate(x, y);
        let x1 = (x0 + 1).min(self.width - 1);
        let y1 = (y0 + 1).min(self.height - 1);
        mix(&[
            (grid[y0 * self.width + x0], (1.0 - fx) * (1.0 - fy)),
            (grid[y0 * self.width + x1], fx * (1.0 - fy)),
            (grid[y1 * self.width + x0], (1.0 - fx) * fy),
            (grid[y1 * self.width + x1], fx * fy),
        ])
    }

    /// Cable probability at photo point (x, y).
    pub fn cable_at(&self, x: f32, y: f32) -> f32 {
        self.bilinear(&self.cable, x, y, |taps| {
            taps.iter().map(|(v, w)| v * w).sum()
        })
    }

    /// Highest cable probability of the cells within `reach` cells (each way) of the
    /// cell holding photo point (x, y).
    pub fn max_cable_near(&self, x: f32, y: f32, reach: usize) -> f32 {
        let cell = |v: f32, size: f32, n: usize| ((v / size).max(0.0) as usize).min(n - 1);
        let (cx, cy) = (
            cell(x, self.cell_px[0], self.width),
            cell(y, self.cell_px[1], self.height),
        );
        let xs = cx.saturating_sub(reach)..(cx + reach + 1).min(self.width);
        (cy.saturating_sub(reach)..(cy + reach + 1).min(self.height))
            .flat_map(|gy| self.cable[gy * self.width + xs.start..gy * self.width + xs.end].iter())
            .fold(0.0, |m, &p| m.max(p))
    }

    /// (cos 2θ, sin 2θ) at photo point (x, y).
    pub fn orientation_at(&self, x: f32, y: f32) -> [f32; 2] {
        self.bilinear(&self.orientation, x, y, |taps| {
            taps.iter().fold([0.0, 0.0], |acc, (v, w)| {
                [acc[0] + v[0] * w, acc[1] + v[1] * w]
            })
        })
    }

    /// Share of the grid's cells whose cable probability is at least `level` (0 for an
    /// empty grid): how much of the photo the network calls cable, whatever its size.
    pub fn cable_share(&self, level: f32) -> f32 {
        self.cable_cells(level) as f32 / self.cable.len().max(1) as f32
    }

    /// How many of the grid's cells have a cable probability of at least `level`.
    pub fn cable_cells(&self, level: f32) -> usize {
        self.cable.iter().filter(|&&p| p >= level).count()
    }

    /// Share of the points of `line` where the cable probability is at least `level`
    /// (0 for an empty line).
    pub fn share_on_cable(&self, line: &[[f32; 2]], level: f32) -> f32 {
        if line.is_empty() {
            return 0.0;
        }
        let on = line
            .iter()
            .filter(|p| self.cable_at(p[0], p[1]) >= level)
            .count();
        on as f32 / line.len() as f32
    }

    /// The field averaged over every superpixel of `sp`, read at every second pixel of
    /// every second row (the field is smooth at the scale of a cell, so a quarter of the
    /// pixels give the same means four times faster); a superpixel that no such pixel
    /// hits is read at all of its pixels.
    pub fn per_vertex(&self, sp: &Superpixels) -> Vec<VertexField> {
        let mut sums = vec![[0.0f32; 4]; sp.count];
        self.accumulate(sp, SAMPLE_STRIDE, &mut sums);
        if sums.iter().any(|s| s[3] == 0.0) {
            let mut missing = vec![[0.0f32; 4]; sp.count];
            self.accumulate(sp, 1, &mut missing);
            for (s, m) in sums.iter_mut().zip(missing) {
                if s[3] == 0.0 {
                    *s = m;
                }
            }
        }
        sums.iter()
            .map(|s| {
                let n = s[3].max(1.0);
                VertexField {
                    cable: s[0] / n,
                    orientation: [s[1] / n, s[2] / n],
                }
            })
            .collect()
    }

    /// Adds, per superpixel, the cable probability, cos 2θ, sin 2θ and a count of the
    /// pixels read, reading every `stride`-th pixel of every `stride`-th row.
    fn accumulate(&self, sp: &Superpixels, stride: usize, sums: &mut [[f32; 4]]) {
        // Bilinear weights depend on x alone along a row: computed once per column.
        let columns: Vec<(usize, usize, usize, f32)> = (0..sp.width)
            .step_by(stride)
            .map(|x| {
                let (x0, _, fx, _) = self.locate(x as f32 + 0.5, 0.0);
                (x, x0, (x0 + 1).min(self.width - 1), fx)
            })
            .collect();
        for y in (0..sp.height).step_by(stride) {
            let (_, y0, _, fy) = self.locate(0.0, y as f32 + 0.5);
            let y1 = (y0 + 1).min(self.height - 1);
            let (r0, r1) = (y0 * self.width, y1 * self.width);
            for &(x, x0, x1, fx) in &columns {
                let w = [
                    (1.0 - fx) * (1.0 - fy),
                    fx * (1.0 - fy),
                    (1.0 - fx) * fy,
                    fx * fy,
                ];
                let cells = [r0 + x0, r0 + x1, r1 + x0, r1 + x1];
                let s = &mut sums[sp.labels[y * sp.width + x] as usize];
                for (&c, wk) in cells.iter().zip(w) {
                    s[0] += wk * self.cable[c];
                    s[1] += wk * self.orientation[c][0];
                    s[2] += wk * self.orientation[c][1];
                }
                s[3] += 1.0;
            }
        }
    }
}

/// [`CableField::per_vertex`] reads every this many pixels and rows.
const SAMPLE_STRIDE: usize = 2;

/// How well a step along the unit vector `dir` follows a field direction given as
/// (cos 2θ, sin 2θ) with confidence = its length: 1 along it, 0 across it, and 1/2
/// (no opinion) where the field has none.
pub fn alignment(dir: [f32; 2], orientation: [f32; 2]) -> f32 {
    let [c2, s2] = orientation_of(dir);
    (0.5 * (1.0 + c2 * orientation[0] + s2 * orientation[1])).clamp(0.0, 1.0)
}

/// The unsigned direction of the unit vector `dir` as the field gives one: (cos 2θ,
/// sin 2θ), of length 1.
pub fn orientation_of(dir: [f32; 2]) -> [f32; 2] {
    [dir[0] * dir[0] - dir[1] * dir[1], 2.0 * dir[0] * dir[1]]
}

#[cfg(test)]
mod tests {
    use super::*;

    fn field() -> CableField {
        // 4x3 cells of 10 px; a horizontal cable along the middle row.
        let (w, h) = (4, 3);
        let cable = (0..w * h)
            .map(|i| if i / w == 1 { 1.0 } else { 0.0 })
            .collect();
        CableField {
            width: w,
            height: h,
            cell_px: [10.0, 10.0],
            cable,
            orientation: vec![[1.0, 0.0]; w * h],
        }
    }

    #[test]
    fn sampling_interpolates_between_cell_centres() {
        let f = field();
        assert!(
            (f.cable_at(20.0, 15.0) - 1.0).abs() < 1e-6,
            "on the cable row"
        );
        assert!(
            (f.cable_at(20.0, 10.0) - 0.5).abs() < 1e-6,
            "half way to the row above"
        );
        assert!(f.cable_at(-50.0, 2.0).abs() < 1e-6, "clamped outside");
        assert_eq!(f.share_on_cable(&[[5.0, 15.0], [5.0, 25.0]], 0.5), 0.5);
        assert!(
            (f.cable_share(0.5) - 1.0 / 3.0).abs() < 1e-6,
            "one row of three"
        );
    }

    #[test]
    fn the_strongest_cable_near_a_point_is_found_within_its_reach() {
        // A 6x5 field of 10 px cells, one cell of cable at column 1, row 1.
        let mut cable = vec![0.1; 30];
        cable[6 + 1] = 0.8;
        let f = CableField {
            width: 6,
            height: 5,
            cell_px: [10.0, 10.0],
            cable,
            orientation: vec![[1.0, 0.0]; 30],
        };
        assert_eq!(f.max_cable_near(15.0, 15.0, 0), 0.8, "its own cell");
        assert_eq!(
            f.max_cable_near(35.0, 35.0, 2),
            0.8,
            "two cells off diagonally"
        );
        assert_eq!(f.max_cable_near(45.0, 15.0, 2), 0.1, "three cells off");
        assert_eq!(
            f.max_cable_near(-40.0, 500.0, 1),
            0.1,
            "clamped into the grid"
        );
    }

    #[test]
    fn alignment_is_unsigned_and_neutral_without_a_direction() {
        let along = [1.0, 0.0];
        assert!((alignment([1.0, 0.0], along) - 1.0).abs() < 1e-6);
        assert!(
            (alignment([-1.0, 0.0], along) - 1.0).abs() < 1e-6,
            "unsigned"
        );
        assert!(alignment([0.0, 1.0], along).abs() < 1e-6);
        assert!((alignment([0.6, 0.8], [0.0, 0.0]) - 0.5).abs() < 1e-6);
    }

    #[test]
    fn per_vertex_means_follow_the_labels() {
        let f = field();
        let sp = Superpixels {
            width: 40,
            height: 30,
            labels: (0..1200)
                .map(|i| if (i / 40) < 10 { 0 } else { 1 })
                .collect(),
            count: 2,
            step: 10.0,
        };
        let v = f.per_vertex(&sp);
        assert!(v[0].cable < 0.5 && v[1].cable > 0.4, "{v:?}");
        assert!((v[0].orientation[0] - 1.0).abs() < 1e-5);
    }
}
