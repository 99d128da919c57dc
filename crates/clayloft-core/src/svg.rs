//! Contours from SVG files (SPEC §1.1, beyond the paper): the first closed path of the drawing,
//! or the path with a given id, with its transforms applied (usvg resolves groups, `transform`
//! attributes, units and turns circles, ellipses, rectangles and polygons into paths), curves
//! flattened to within a tolerance, scaled so its longer side is `size` mm. SVG's y points down;
//! the contour is returned with y up, centred on its bounding box.

use glam::DVec2;
use usvg::tiny_skia_path::PathSegment;

/// Largest SVG file read, bytes.
pub const MAX_BYTES: u64 = 50_000_000;
/// Flattening tolerance, relative to the drawing's size (1/2000 of the longer side).
const FLATNESS: f64 = 1.0 / 2000.0;

/// Why an SVG gave no contour. Messages are completed with the file name by the caller.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum SvgError {
    #[error("cannot read: {0}")]
    Read(String),
    #[error("not an SVG drawing ({0})")]
    Parse(String),
    #[error("no path with id \"{0}\"")]
    NoSuchId(String),
    #[error("the drawing has no closed path")]
    NoClosedPath,
    #[error(
        "the drawing's paths flatten to more than {MAX_FLAT_POINTS} points before a closed one is found: simplify it"
    )]
    TooComplex,
}

/// Most points all flattened paths of a drawing may give: far beyond any outline a vessel needs
/// (designs sample at most 100 000 points), and a bound on time and memory for any file.
pub const MAX_FLAT_POINTS: usize = 2_000_000;

/// Reads an SVG file (at most [`MAX_BYTES`]) into a tree.
pub fn load_svg(path: &std::path::Path) -> Result<usvg::Tree, SvgError> {
    let meta = std::fs::metadata(path).map_err(|e| SvgError::Read(reason(&e)))?;
    if meta.is_dir() {
        return Err(SvgError::Read("is a folder".into()));
    }
    if meta.len() > MAX_BYTES {
        return Err(SvgError::Read(format!(
            "{} bytes is too large for a drawing",
            meta.len()
        )));
    }
    let data = std::fs::read(path).map_err(|e| SvgError::Read(reason(&e)))?;
    parse_svg(&data)
}

/// Parses SVG text (or gzip-compressed SVG) into a tree.
pub fn parse_svg(data: &[u8]) -> Result<usvg::Tree, SvgError> {
    usvg::Tree::from_data(data, &usvg::Options::default())
        .map_err(|e| SvgError::Parse(e.to_string()))
}

fn reason(e: &std::io::Error) -> String {
    if e.kind() == std::io::ErrorKind::NotFound {
        "no such file".into()
    } else {
        e.to_string()
    }
}

/// The first closed sub-path of the first path (document order) or of the path `id`, flattened,
/// in the drawing's user units with transforms applied (y down).
pub fn closed_outline(tree: &usvg::Tree, id: Option<&str>) -> Result<Vec<DVec2>, SvgError> {
    let mut paths = Vec::new();
    collect_paths(tree.root(), &mut paths);
    let size = tree.size();
    let tol = (size.width().max(size.height()) as f64 * FLATNESS).max(1e-6);
    match id {
        Some(id) => {
            let p = paths
                .iter()
                .find(|p| p.id() == id)
                .ok_or_else(|| SvgError::NoSuchId(id.into()))?;
            let mut budget = MAX_FLAT_POINTS;
            first_closed(p, tol, &mut budget)?.ok_or(SvgError::NoClosedPath)
        }
        None => {
            let mut budget = MAX_FLAT_POINTS;
            for p in &paths {
                if let Some(outline) = first_closed(p, tol, &mut budget)? {
                    return Ok(outline);
                }
            }
            Err(SvgError::NoClosedPath)
        }
    }
}

fn collect_paths<'a>(group: &'a usvg::Group, out: &mut Vec<&'a usvg::Path>) {
    for node in group.children() {
        match node {
            usvg::Node::Group(g) => collect_paths(g, out),
            usvg::Node::Path(p) => out.push(p),
            _ => {}
        }
    }
}

/// Flattens the first sub-path ending in `Close` (or returning to its start) of a path.
/// `budget`: points all paths may still give ([`MAX_FLAT_POINTS`] in all).
fn first_closed(
    path: &usvg::Path,
    tol: f64,
    budget: &mut usize,
) -> Result<Option<Vec<DVec2>>, SvgError> {
    let t = path.abs_transform();
    let map = |p: usvg::tiny_skia_path::Point| {
        let mut q = p;
        t.map_point(&mut q);
        DVec2::new(q.x as f64, q.y as f64)
    };
    let mut pts: Vec<DVec2> = Vec::new();
    let mut last = DVec2::ZERO;
    for seg in path.data().segments() {
        let before = pts.len();
        match seg {
            PathSegment::MoveTo(p) => {
                if closes(&pts) {
                    return Ok(Some(pts));
                }
                pts.clear();
                last = map(p);
                pts.push(last);
            }
            PathSegment::LineTo(p) => {
                last = map(p);
                pts.push(last);
            }
            PathSegment::QuadTo(c, p) => {
                let (c, p) = (map(c), map(p));
                flatten(
                    &mut pts,
                    |s| {
                        let u = 1.0 - s;
                        last * (u * u) + c * (2.0 * u * s) + p * (s * s)
                    },
                    last.distance(c) + c.distance(p),
                    tol,
                );
                last = p;
            }
            PathSegment::CubicTo(c1, c2, p) => {
                let (c1, c2, p) = (map(c1), map(c2), map(p));
                let l = last.distance(c1) + c1.distance(c2) + c2.distance(p);
                let start = last;
                flatten(
                    &mut pts,
                    |s| {
                        let u = 1.0 - s;
                        start * (u * u * u)
                            + c1 * (3.0 * u * u * s)
                            + c2 * (3.0 * u * s * s)
                            + p * (s * s * s)
                    },
                    l,
                    tol,
                );
                last = p;
            }
            PathSegment::Close => {
                if pts.len() >= 3 {
                    return Ok(Some(pts));
                }
            }
        }
        let added = pts.len().saturating_sub(before).max(1);
        if added > *budget {
            return Err(SvgError::TooComplex);
        }
        *budget -= added;
    }
    Ok(closes(&pts).then_some(pts))
}

/// A sub-path that ends where it began is closed even without `Z`.
fn closes(pts: &[DVec2]) -> bool {
    pts.len() >= 4 && pts[0].distance(pts[pts.len() - 1]) < 1e-6
}

/// Appends points of a curve `c(s)`, s in (0, 1], at a step fine enough that the chord error of a
/// curve of control-polygon length `len` stays near `tol`.
fn flatten(out: &mut Vec<DVec2>, c: impl Fn(f64) -> DVec2, len: f64, tol: f64) {
    let steps = ((len / tol).sqrt().ceil() as usize).clamp(2, 4096);
    for k in 1..=steps {
        out.push(c(k as f64 / steps as f64));
    }
}

/// Outline in mm, y up, centred on its bounding box, longer side `size`.
pub fn outline_mm(points: &[DVec2], size: f64) -> Vec<DVec2> {
    crate::trace::outline_mm(points, size)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn circle_comes_back_round_and_at_size() {
        let svg = br#"<svg xmlns="http://www.w3.org/2000/svg" width="200" height="200">
            <rect x="0" y="0" width="5" height="5" fill="none"/>
            <circle cx="120" cy="80" r="50"/></svg>"#;
        let tree = parse_svg(svg).unwrap();
        let pts = closed_outline(&tree, None).unwrap();
        // The invisible rect comes first in document order but is closed too: pick by id next.
        assert!(pts.len() >= 4);
        let svg = br#"<svg xmlns="http://www.w3.org/2000/svg" width="200" height="200">
            <circle id="pot" cx="120" cy="80" r="50"/></svg>"#;
        let tree = parse_svg(svg).unwrap();
        let pts = closed_outline(&tree, Some("pot")).unwrap();
        for p in &pts {
            let r = (*p - DVec2::new(120.0, 80.0)).length();
            assert!((r - 50.0).abs() < 0.1, "{r}");
        }
        let mm = outline_mm(&pts, 80.0);
        for p in &mm {
            assert!((p.length() - 40.0).abs() < 0.1, "{}", p.length());
        }
    }

    #[test]
    fn transforms_are_applied() {
        // A 20 × 10 rectangle path, scaled by 2 and moved by (100, 50), inside a rotated group.
        let svg = br#"<svg xmlns="http://www.w3.org/2000/svg" width="400" height="400">
            <g transform="translate(100 50)"><path id="p" transform="scale(2)" d="M0 0 L20 0 L20 10 L0 10 Z"/></g>
            </svg>"#;
        let pts = closed_outline(&parse_svg(svg).unwrap(), Some("p")).unwrap();
        let xs: Vec<f64> = pts.iter().map(|p| p.x).collect();
        let ys: Vec<f64> = pts.iter().map(|p| p.y).collect();
        let (x0, x1) = (
            xs.iter().cloned().fold(f64::INFINITY, f64::min),
            xs.iter().cloned().fold(f64::NEG_INFINITY, f64::max),
        );
        let (y0, y1) = (
            ys.iter().cloned().fold(f64::INFINITY, f64::min),
            ys.iter().cloned().fold(f64::NEG_INFINITY, f64::max),
        );
        assert!(
            (x0 - 100.0).abs() < 1e-4 && (x1 - 140.0).abs() < 1e-4,
            "{x0} {x1}"
        );
        assert!(
            (y0 - 50.0).abs() < 1e-4 && (y1 - 70.0).abs() < 1e-4,
            "{y0} {y1}"
        );
        // Longer side 40 units → 80 mm: 2 mm per unit, the short side 40 mm.
        let mm = outline_mm(&pts, 80.0);
        let h = mm.iter().map(|p| p.y).fold(f64::NEG_INFINITY, f64::max)
            - mm.iter().map(|p| p.y).fold(f64::INFINITY, f64::min);
        assert!((h - 40.0).abs() < 1e-6, "{h}");
    }

    #[test]
    fn a_drawing_of_millions_of_curves_is_refused_not_flattened_forever() {
        // 2000 open cubic curves, each flattened to 4096 points: 8 M points, past the budget.
        let mut d = String::from("M 0 0");
        for k in 0..2000 {
            d += &format!(
                " C {} 1e9 {} -1e9 {} 0",
                k * 10 + 3,
                k * 10 + 6,
                k * 10 + 10
            );
        }
        let svg = format!(
            "<svg xmlns='http://www.w3.org/2000/svg' width='100' height='100'><path d='{d}'/></svg>"
        );
        let tree = parse_svg(svg.as_bytes()).unwrap();
        assert_eq!(closed_outline(&tree, None), Err(SvgError::TooComplex));
    }

    #[test]
    fn bad_drawings_are_errors() {
        let no_path = br#"<svg xmlns="http://www.w3.org/2000/svg" width="10" height="10"><text>hi</text></svg>"#;
        assert_eq!(
            closed_outline(&parse_svg(no_path).unwrap(), None),
            Err(SvgError::NoClosedPath)
        );
        let open = br#"<svg xmlns="http://www.w3.org/2000/svg" width="10" height="10"><path d="M0 0 L5 5 L9 1" stroke="black"/></svg>"#;
        assert_eq!(
            closed_outline(&parse_svg(open).unwrap(), None),
            Err(SvgError::NoClosedPath)
        );
        assert!(matches!(
            closed_outline(&parse_svg(open).unwrap(), Some("x")),
            Err(SvgError::NoSuchId(_))
        ));
        assert!(matches!(
            parse_svg(b"not xml at all"),
            Err(SvgError::Parse(_))
        ));
    }
}
