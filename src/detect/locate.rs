//! Where the model and ONNX Runtime are looked for, so that `ariadne` works from any
//! folder: the working directory first, then beside the executable, an install prefix,
//! and last the source tree the binary was built from.

use std::path::{Path, PathBuf};

/// File name of the ONNX Runtime library this build is made for.
pub const RUNTIME_FILE: &str = "libonnxruntime.so.1.31.1";

/// The places a relative `path` (`models/cable_field.onnx`) is looked for, in order:
/// the working directory, the executable's folder and its `../share/ariadne`,
/// `/usr/local/share/ariadne`, and the source tree of this build. An absolute path is
/// only itself.
pub fn candidates(path: &Path) -> Vec<PathBuf> {
    if path.is_absolute() {
        return vec![path.to_owned()];
    }
    let mut places = vec![path.to_owned()];
    if let Some(dir) = exe_dir() {
        places.push(dir.join(path));
        places.push(dir.join("../share/ariadne").join(path));
    }
    places.push(Path::new("/usr/local/share/ariadne").join(path));
    places.push(Path::new(env!("CARGO_MANIFEST_DIR")).join(path));
    places
}

/// Where the runtime library is looked for when no path is configured, in order:
/// `.ort/` under the working directory (`make setup`), next to the executable,
/// `/usr/local/lib` (the container image), and `.ort/` in the source tree.
pub fn default_runtime_candidates() -> Vec<PathBuf> {
    let mut paths = vec![Path::new(".ort").join(RUNTIME_FILE)];
    if let Some(dir) = exe_dir() {
        paths.push(dir.join(RUNTIME_FILE));
    }
    paths.push(Path::new("/usr/local/lib").join(RUNTIME_FILE));
    paths.push(
        Path::new(env!("CARGO_MANIFEST_DIR"))
            .join(".ort")
            .join(RUNTIME_FILE),
    );
    paths
}

/// The first of `places` that is a file, or the list of places as one line.
pub fn first_file(places: &[PathBuf]) -> Result<&PathBuf, String> {
    places.iter().find(|p| p.is_file()).ok_or_else(|| {
        let looked: Vec<_> = places.iter().map(|p| p.display().to_string()).collect();
        format!("not found (looked at {})", looked.join(", "))
    })
}

fn exe_dir() -> Option<PathBuf> {
    std::env::current_exe()
        .ok()
        .and_then(|e| e.parent().map(Path::to_owned))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn relative_paths_are_looked_for_beyond_the_working_directory() {
        let places = candidates(Path::new("models/cable_field.onnx"));
        assert_eq!(places[0], Path::new("models/cable_field.onnx"));
        assert!(places.len() >= 4);
        // The bundled model is found whatever the working directory.
        assert!(first_file(&places).is_ok());
        let absolute = candidates(Path::new("/nowhere/model.onnx"));
        assert_eq!(absolute, vec![PathBuf::from("/nowhere/model.onnx")]);
        let err = first_file(&absolute).unwrap_err();
        assert!(err.contains("/nowhere/model.onnx"), "{err}");
    }
}
