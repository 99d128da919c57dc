//! Outlines read from files (image and SVG contours), with a small cache so that editing the
//! other contour or the height in the app does not decode and trace the picture again.

use std::path::{Path, PathBuf};
use std::sync::Mutex;
use std::time::SystemTime;

use glam::DVec2;

use crate::contour::ContourError;
use crate::design::ContourSpec;

/// What identifies a traced outline: the file (and its modification), and the settings.
#[derive(Debug, Clone, PartialEq)]
struct Key {
    file: PathBuf,
    modified: Option<SystemTime>,
    len: u64,
    spec: ContourSpec,
}

/// The last few outlines traced.
static CACHE: Mutex<Vec<(Key, Vec<DVec2>)>> = Mutex::new(Vec::new());
const CACHE_ENTRIES: usize = 4;

/// The file a contour spec reads, relative to `base`.
pub fn resolve(path: &str, base: Option<&Path>) -> PathBuf {
    let p = Path::new(path);
    match base {
        Some(b) if p.is_relative() => b.join(p),
        _ => p.to_path_buf(),
    }
}

/// The outline (mm, y up, centred) of an image or SVG contour spec.
pub fn outline_of(spec: &ContourSpec, base: Option<&Path>) -> Result<Vec<DVec2>, ContourError> {
    let (path, size) = match spec {
        ContourSpec::Image { path, size, .. } | ContourSpec::Svg { path, size, .. } => {
            (path, *size)
        }
        _ => return Err(ContourError::TooFewPoints),
    };
    let file = resolve(path, base);
    let meta = std::fs::metadata(&file).ok();
    let key = Key {
        file: file.clone(),
        modified: meta.as_ref().and_then(|m| m.modified().ok()),
        len: meta.as_ref().map_or(0, |m| m.len()),
        spec: spec.clone(),
    };
    if let Ok(cache) = CACHE.lock()
        && let Some((_, pts)) = cache.iter().find(|(k, _)| *k == key)
    {
        return Ok(pts.clone());
    }
    let shown = path.clone();
    let pts = match spec {
        ContourSpec::Image { threshold, .. } => {
            let err = |reason| ContourError::Image {
                file: shown.clone(),
                reason,
            };
            let grey = crate::trace::load_grey(&file).map_err(err)?;
            crate::trace::contour_from_grey(&grey, *threshold, size)
                .map_err(err)?
                .0
        }
        ContourSpec::Svg { id, .. } => {
            let err = |reason| ContourError::Svg {
                file: shown.clone(),
                reason,
            };
            let tree = crate::svg::load_svg(&file).map_err(err)?;
            let outline = crate::svg::closed_outline(&tree, id.as_deref()).map_err(err)?;
            crate::svg::outline_mm(&outline, size)
        }
        _ => unreachable!("checked above"),
    };
    if let Ok(mut cache) = CACHE.lock() {
        cache.retain(|(k, _)| k.file != key.file || k.spec != key.spec);
        cache.insert(0, (key, pts.clone()));
        cache.truncate(CACHE_ENTRIES);
    }
    Ok(pts)
}
