//! Ends a cable confirms: a terminal peak too weak to start a walk from, lying where a
//! cable found from the other ends stops inside the frame, is that cable's end. On a
//! background the network never saw it is less sure of the terminals it does see
//! (docs/ACCURACY.md, "Ends a cable confirms"); walking from every weak peak would
//! start false cables, but a cable that stops on one confirms it. That includes a peak
//! lying on another cable: in a heap, ends lie against and over other cables, and the
//! network is least sure of those (docs/ACCURACY.md, "Ends against other cables").

use super::Segmentation;
use super::geometry::{border_inset, dist};

impl Segmentation {
    /// Reports `candidates` (weaker terminal peaks, pixels of this segmentation) as
    /// ends of the cables that stop on them. Each cable end that is no given end takes
    /// the nearest candidate within `reach_px`, both farther than `margin_px` from the
    /// frame's border (a cable that stops there leaves the frame); each candidate ends
    /// at most one cable, nearest pairs first. Every candidate taken becomes a new end,
    /// numbered after the given ones in the order returned (indices into `candidates`),
    /// and is recorded in [`Segmentation::end_cables`] and its cable's `end_indices`. A
    /// reach of 0 takes none.
    pub fn confirm_ends(
        &mut self,
        candidates: &[[f64; 2]],
        reach_px: f32,
        margin_px: f32,
    ) -> Vec<usize> {
        if reach_px <= 0.0 {
            return Vec::new();
        }
        let [w, h] = [self.width, self.height].map(|v| v as usize);
        let inside = |p: [f32; 2]| border_inset(p, w, h) > margin_px;
        let points: Vec<[f32; 2]> = candidates.iter().map(|q| q.map(|v| v as f32)).collect();
        let mut pairs: Vec<(f32, usize, usize, usize)> = Vec::new();
        for (c, cable) in self.cables.iter().enumerate() {
            for k in 0..2 {
                let end = cable.ends[k];
                if cable.end_indices[k].is_some() || !inside(end) {
                    continue;
                }
                for (i, &q) in points.iter().enumerate() {
                    let d = dist(end, q);
                    if d <= reach_px && inside(q) {
                        pairs.push((d, c, k, i));
                    }
                }
            }
        }
        pairs.sort_by(|a, b| a.0.total_cmp(&b.0));
        let mut taken = Vec::new();
        for (_, c, k, i) in pairs {
            let cable = &mut self.cables[c];
            if cable.end_indices[k].is_some() || taken.contains(&i) {
                continue;
            }
            cable.end_indices[k] = Some(self.end_cables.len());
            self.end_cables.push(Some(cable.id));
            taken.push(i);
        }
        taken
    }

    /// Reports the ends of twins beside given ends: where a cable walked from an end
    /// lay over two alike cables side by side (`twins`), the network saw one terminal
    /// peak for their two terminals, and the second twin's end on that side is the
    /// other terminal. Each such end that is no end yet becomes a new end, numbered
    /// after the existing ones in the order returned, and is recorded in
    /// [`Segmentation::end_cables`] and its cable's `end_indices`. Returns each new
    /// end's point (pixels of this segmentation) with the end it lies beside.
    pub fn twin_ends(&mut self) -> Vec<([f64; 2], usize)> {
        let mut added = Vec::new();
        for cable in &mut self.cables {
            for k in 0..2 {
                let Some(beside) = cable.twin_ends[k].filter(|_| cable.end_indices[k].is_none())
                else {
                    continue;
                };
                cable.end_indices[k] = Some(self.end_cables.len());
                self.end_cables.push(Some(cable.id));
                added.push((cable.ends[k].map(f64::from), beside));
            }
        }
        added
    }
}

#[cfg(test)]
mod tests {
    use crate::engine::cable::{found, straight as cable};

    #[test]
    fn a_free_end_inside_the_frame_takes_the_nearest_weak_peak() {
        // Cable 0 runs from given end 0 to a free end at (300, 200); cable 1 from
        // given end 1 out of the frame at (0, 240); cable 2 from a free end at
        // (400, 300), where it ends against cable 3, to given end 2; cable 4 from
        // given end 5 to a free end 20 px from the frame's left side.
        let mut seg = found(
            1.0,
            vec![
                cable(0, [[100.0, 100.0], [300.0, 200.0]], [Some(0), None]),
                cable(1, [[200.0, 240.0], [0.0, 240.0]], [Some(1), None]),
                cable(2, [[400.0, 300.0], [400.0, 400.0]], [None, Some(2)]),
                cable(3, [[350.0, 296.0], [450.0, 296.0]], [Some(3), Some(4)]),
                cable(4, [[100.0, 440.0], [20.0, 440.0]], [Some(5), None]),
            ],
            vec![Some(0), Some(1), Some(2), Some(3), Some(3), Some(4)],
        );
        let candidates = [
            [309.0, 200.0], // 9 px from cable 0's free end
            [305.0, 203.0], // 5.8 px: the nearer one is taken
            [4.0, 240.0],   // by cable 1's end, but that leaves the frame
            [100.0, 104.0], // by a given end: not taken
            [400.0, 292.0], // 8 px from cable 2's free end, lying on cable 3
            [9.0, 440.0],   // by cable 4's free end, but at the border
        ];
        let taken = seg.confirm_ends(&candidates, 12.0, 12.0);
        assert_eq!(taken, vec![1, 4]);
        assert_eq!(seg.end_cables[6..], [Some(0), Some(2)]);
        assert_eq!(seg.cables[0].end_indices, [Some(0), Some(6)]);
        assert_eq!(seg.cables[2].end_indices, [Some(7), Some(2)]);
        assert_eq!(seg.cables[4].end_indices, [Some(5), None]);
        assert_eq!(seg.cables[1].end_indices, [Some(1), None]);
        // A confirmed end takes no other peak, and a reach of 0 takes none.
        assert!(seg.confirm_ends(&[[302.0, 200.0]], 12.0, 12.0).is_empty());
        assert!(seg.confirm_ends(&[[20.0, 440.0]], 0.0, 12.0).is_empty());
    }

    #[test]
    fn the_second_twin_takes_the_terminal_beside_its_siblings_end() {
        // Twins 0 and 1 split from a cable walked from end 0 to end 1; twin 1's start
        // already holds an end (a peak of its own), its far end does not.
        let mut twin = cable(1, [[100.0, 110.0], [300.0, 110.0]], [Some(2), None]);
        twin.twin_ends = [Some(0), Some(1)];
        let mut seg = found(
            1.0,
            vec![
                cable(0, [[100.0, 100.0], [300.0, 100.0]], [Some(0), Some(1)]),
                twin,
            ],
            vec![Some(0), Some(0), Some(1)],
        );
        assert_eq!(seg.twin_ends(), vec![([300.0, 110.0], 1)]);
        assert_eq!(seg.end_cables[3..], [Some(1)]);
        assert_eq!(seg.cables[1].end_indices, [Some(2), Some(3)]);
        // Each is reported once.
        assert!(seg.twin_ends().is_empty());
    }
}
