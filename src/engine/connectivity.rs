//! Connectivity of superpixels: after k-means a label may cover several separate
//! fragments; each must become one 4-connected region.

/// Relabels so that every label is one 4-connected region. A fragment of fewer than
/// `min_size` pixels takes the label of the region it touches before it in raster
/// order (so the merged region stays connected); any other fragment gets a fresh label.
/// Returns the new labels and their count.
pub fn enforce_connectivity(
    labels: &[u32],
    w: usize,
    h: usize,
    min_size: usize,
) -> (Vec<u32>, usize) {
    const UNSET: u32 = u32::MAX;
    let mut out = vec![UNSET; labels.len()];
    let mut component: Vec<usize> = Vec::new();
    let mut next = 0u32;
    for start in 0..labels.len() {
        if out[start] != UNSET {
            continue;
        }
        let original = labels[start];
        // A neighbour that already has a final label: the merge target for a small fragment.
        let (sx, sy) = (start % w, start / w);
        let adjacent = if sx > 0 && out[start - 1] != UNSET {
            Some(out[start - 1])
        } else if sy > 0 {
            Some(out[start - w])
        } else {
            None
        };
        component.clear();
        component.push(start);
        out[start] = next;
        let mut head = 0;
        while head < component.len() {
            let p = component[head];
            head += 1;
            let (x, y) = (p % w, p / w);
            let mut visit = |q: usize| {
                if out[q] == UNSET && labels[q] == original {
                    out[q] = next;
                    component.push(q);
                }
            };
            if x > 0 {
                visit(p - 1);
            }
            if x + 1 < w {
                visit(p + 1);
            }
            if y > 0 {
                visit(p - w);
            }
            if y + 1 < h {
                visit(p + w);
            }
        }
        match adjacent {
            Some(target) if component.len() < min_size => {
                for &p in &component {
                    out[p] = target;
                }
            }
            _ => next += 1,
        }
    }
    (out, next as usize)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn connectivity_splits_and_merges() {
        // Label 0 in two far-apart blocks, label 1 in two pieces (the right one of
        // two pixels), and a one-pixel island of label 2.
        #[rustfmt::skip]
        let labels = vec![
            0, 0, 1, 1, 0, 0,
            0, 0, 1, 1, 0, 0,
            1, 1, 1, 2, 1, 1,
        ];
        let (out, count) = enforce_connectivity(&labels, 6, 3, 2);
        assert_eq!(count, 4);
        assert_eq!(out[0], out[1]);
        assert_ne!(out[0], out[4]);
        assert_ne!(out[12], out[16]);
        assert_eq!(out[15], out[14], "the island merged into its neighbour");
    }
}
