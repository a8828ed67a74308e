//! Reading a folder laid out like `shared/datasets/cables`.

use std::path::{Path, PathBuf};

use image::GrayImage;
use thiserror::Error;

/// Environment variable that overrides the dataset folder.
pub const DATASET_ENV: &str = "ARIADNE_DATASET";
/// Default dataset folder, relative to the repository root.
pub const DEFAULT_DATASET: &str = "../shared/datasets/cables";
/// A centreline end this close to the border is where the cable leaves the frame, not a
/// terminal, pixels (the dataset puts such ends "on or within a few pixels of" it).
pub const BORDER_TOLERANCE_PX: f32 = 12.0;

/// Problems reading the dataset.
#[derive(Debug, Error)]
pub enum DatasetError {
    /// A file or folder could not be read.
    #[error("{0}: {1}")]
    Io(PathBuf, String),
    /// A centreline file is malformed.
    #[error("{0}, line {1}: {2}")]
    Parse(PathBuf, usize, String),
    /// An image or mask could not be decoded.
    #[error("{0}: {1}")]
    Image(PathBuf, String),
    /// The engine refused the image.
    #[error("{0}: {1}")]
    Engine(PathBuf, String),
    /// No image was found.
    #[error(
        "no images found under {0} (expected sub-folders such as simple/ and hard/ with NNNNN.jpg and NNNNN.txt)"
    )]
    Empty(PathBuf),
}

impl DatasetError {
    /// Wraps an I/O error with its path.
    pub fn io(path: &Path, e: std::io::Error) -> Self {
        Self::Io(path.to_path_buf(), e.to_string())
    }
}

/// One annotated image.
#[derive(Debug, Clone)]
pub struct Sample {
    /// Sub-folder name.
    pub set: String,
    /// File stem.
    pub name: String,
    /// The photograph.
    pub image: PathBuf,
    /// Centreline of each cable, in order from one end to the other.
    pub cables: Vec<Vec<[f32; 2]>>,
}

/// The dataset folder: `$ARIADNE_DATASET`, else `../shared/datasets/cables`.
pub fn default_dataset_dir() -> PathBuf {
    std::env::var_os(DATASET_ENV).map_or_else(|| PathBuf::from(DEFAULT_DATASET), PathBuf::from)
}

impl Sample {
    fn sibling(&self, suffix: &str) -> PathBuf {
        self.image.with_file_name(format!("{}{suffix}", self.name))
    }

    /// The union mask, foreground where > 127.
    pub fn mask_all(&self) -> Result<GrayImage, DatasetError> {
        read_mask(&self.sibling("_mask_all.png"))
    }

    /// One mask per cable, in the order of `cables`.
    pub fn cable_masks(&self) -> Result<Vec<GrayImage>, DatasetError> {
        (0..self.cables.len())
            .map(|k| read_mask(&self.sibling(&format!("_mask_{k}.png"))))
            .collect()
    }
}

fn read_mask(path: &Path) -> Result<GrayImage, DatasetError> {
    let img =
        image::open(path).map_err(|e| DatasetError::Image(path.to_path_buf(), e.to_string()))?;
    Ok(img.into_luma8())
}

/// Every sample under `dir`, sub-folders in name order (`hard` before `simple`), images
/// in name order.
pub fn load_dataset(dir: &Path) -> Result<Vec<Sample>, DatasetError> {
    let mut sets: Vec<PathBuf> = std::fs::read_dir(dir)
        .map_err(|e| DatasetError::io(dir, e))?
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.is_dir())
        .collect();
    sets.sort();
    let mut samples = Vec::new();
    for set in sets {
        let mut txts: Vec<PathBuf> = std::fs::read_dir(&set)
            .map_err(|e| DatasetError::io(&set, e))?
            .filter_map(|e| e.ok().map(|e| e.path()))
            .filter(|p| p.extension().is_some_and(|x| x == "txt"))
            .collect();
        txts.sort();
        for txt in txts {
            let image = txt.with_extension("jpg");
            if !image.exists() {
                continue;
            }
            let text = std::fs::read_to_string(&txt).map_err(|e| DatasetError::io(&txt, e))?;
            samples.push(Sample {
                set: set
                    .file_name()
                    .map(|s| s.to_string_lossy().into_owned())
                    .unwrap_or_default(),
                name: txt
                    .file_stem()
                    .map(|s| s.to_string_lossy().into_owned())
                    .unwrap_or_default(),
                cables: parse_centrelines(&text)
                    .map_err(|(line, msg)| DatasetError::Parse(txt.clone(), line, msg))?,
                image,
            });
        }
    }
    if samples.is_empty() {
        return Err(DatasetError::Empty(dir.to_path_buf()));
    }
    Ok(samples)
}

/// Parses `K x0 y0 ... x(K-1) y(K-1)` lines; errors carry the 1-based line number.
pub fn parse_centrelines(text: &str) -> Result<Vec<Vec<[f32; 2]>>, (usize, String)> {
    let mut cables = Vec::new();
    for (i, line) in text.lines().enumerate() {
        let nums: Vec<&str> = line.split_whitespace().collect();
        if nums.is_empty() {
            continue;
        }
        let k: usize = nums[0]
            .parse()
            .map_err(|_| (i + 1, format!("bad point count `{}`", nums[0])))?;
        if nums.len() < 1 + 2 * k || k < 2 {
            return Err((i + 1, format!("expected {k} points (at least 2)")));
        }
        let mut pts = Vec::with_capacity(k);
        for j in 0..k {
            let parse = |s: &str| {
                s.parse::<f32>()
                    .map_err(|_| (i + 1, format!("bad coordinate `{s}`")))
            };
            pts.push([parse(nums[1 + 2 * j])?, parse(nums[2 + 2 * j])?]);
        }
        cables.push(pts);
    }
    Ok(cables)
}

/// The cable ends that are terminals: first and last centreline points not within
/// [`BORDER_TOLERANCE_PX`] of the border of a `width` x `height` image.
pub fn terminal_ends(cables: &[Vec<[f32; 2]>], width: u32, height: u32) -> Vec<[f64; 2]> {
    let on_border = |p: [f32; 2]| {
        p[0] < BORDER_TOLERANCE_PX
            || p[1] < BORDER_TOLERANCE_PX
            || p[0] > width as f32 - 1.0 - BORDER_TOLERANCE_PX
            || p[1] > height as f32 - 1.0 - BORDER_TOLERANCE_PX
    };
    cables
        .iter()
        .flat_map(|c| [c[0], c[c.len() - 1]])
        .filter(|&p| !on_border(p))
        .map(|p| [p[0] as f64, p[1] as f64])
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parses_and_filters_border_ends() {
        let cables = parse_centrelines("3 100 100 150 120 8 200\n2 50 60 70 80\n\n").unwrap();
        assert_eq!(cables.len(), 2);
        assert_eq!(cables[0][2], [8.0, 200.0]);
        let ends = terminal_ends(&cables, 640, 480);
        assert_eq!(ends, vec![[100.0, 100.0], [50.0, 60.0], [70.0, 80.0]]);
        assert_eq!(parse_centrelines("3 1 2").unwrap_err().0, 1);
        assert!(parse_centrelines("x 1 2").is_err());
    }
}
